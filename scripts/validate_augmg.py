"""Validation table for the defaults of ``vidstyle evaluate augmg`` (segment mode, segment scale, window).

Runs on a *validation* demo dataset (seed 1: other performers than the test dataset of seed 0) and the
library; prints a table and writes bench_results/validate_augmg.json. The default is the row with the
lowest AugMG transition error (2D from ground truth).

    vidstyle demo make-dataset --out /tmp/augmg_val --seed 1 --no-video
    vidstyle demo make-library --out /tmp/augmg_lib
    python scripts/validate_augmg.py /tmp/augmg_val /tmp/augmg_lib
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from vidstyle.augmg.evaluate import evaluate_augmg

GRID = [("fixed", 1.0, 5, "first"), ("fixed", 1.0, 9, "first"), ("fixed", 0.6, 9, "first"),
        ("fixed", 0.4, 9, "first"), ("fixed", 0.25, 9, "first"), ("nodes", 1.0, 5, "first"),
        ("nodes", 1.0, 9, "first"), ("fixed", 1.0, 9, "both")]


def main(dataset: str, library: str) -> None:
    rows = []
    print(f"{'segment':8} {'scale':>5} {'window':>6} {'place':>6} {'plain mm':>9} {'AugMG mm':>9} {'reduction':>9}")
    for seg, scale, win, place in GRID:
        r = evaluate_augmg(Path(dataset), Path(library), sources=("gt",), segment=seg, segment_scale=scale,
                           enh_window=win, place=place)["by_source"]["gt"]
        rows.append({"segment": seg, "segment_scale": scale, "enh_window": win, "place": place,
                     **{k: v for k, v in r.items() if k != "by_kind"}})
        print(f"{seg:8} {scale:5.2f} {win:6d} {place:>6} {r['transition_plain_mm']:9.1f} {r['transition_augmg_mm']:9.1f} "
              f"{100 * r['transition_reduction']:8.1f}%", flush=True)
    best = min(rows, key=lambda x: x["transition_augmg_mm"])
    print(f"best: segment={best['segment']} segment_scale={best['segment_scale']} enh_window={best['enh_window']}")
    Path("bench_results").mkdir(exist_ok=True)
    Path("bench_results/validate_augmg.json").write_text(json.dumps({"dataset": dataset, "library": library,
                                                                     "rows": rows, "best": best}, indent=2))


if __name__ == "__main__":
    main(*sys.argv[1:3])
