#!/usr/bin/env python
"""Figure: per test performer of split seed ``--seed``, a generated jab from their fitted action style next
to their true jab and the unfitted pooled model's mean jab (stick figures seen from above and from the
side at the start, middle and end of the DTW-aligned action; canonical frame, the performer facing +Z).

The model and population are fitted on the training performers (A+B), the style from ``--input`` 2D
(true or noisy) with the true labels, as ``scripts/eval_action_style.py`` does.

    python scripts/plot_action_style.py --dataset pipelines/kickboxing/out/dataset --seed 0 --label Jab

Writes ``--out`` (default ``pipelines/kickboxing/results/action_style_<label>_seed<seed>.png``).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", type=Path, default=ROOT / "pipelines" / "kickboxing" / "out" / "dataset")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--label", default="Jab")
    ap.add_argument("--input", default="noisy", choices=("true", "noisy"))
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    out = args.out or ROOT / "pipelines" / "kickboxing" / "results" / f"action_style_{args.label.lower()}_seed{args.seed}.png"
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from vidstyle.actionmodel.dtw import dtw
    from vidstyle.actionmodel.stylefit import fit_action_style
    from vidstyle.evaluation.actionmodel import read_manifest, split_groups
    from vidstyle.evaluation.actionstyle import (
        fit_population,
        orthodox_model,
        performer_videos,
        true_instances,
    )
    from vidstyle.formats.dataset import read_dataset
    from vidstyle.mocap.keypoints import KEYPOINT_INDEX, PARTS, keypoint_positions

    manifest = read_manifest(args.dataset)
    ds = read_dataset(args.dataset / "dataset.json")
    g = split_groups(manifest, args.seed)
    train = sorted(g["A"] + g["B"])
    model = orthodox_model(args.dataset, manifest, train, args.seed)
    est = fit_population(ds, manifest, train)
    lm = model.models_[args.label]
    mu = lm.gmm_means[int(np.argmax(lm.gmm_weights))]
    bones = [(KEYPOINT_INDEX[a], KEYPOINT_INDEX[b]) for a, b in PARTS.values()]
    bones += [(KEYPOINT_INDEX["neck"], KEYPOINT_INDEX[s]) for s in ("left_shoulder", "right_shoulder")]
    bones += [(KEYPOINT_INDEX["pelvis"], KEYPOINT_INDEX[s]) for s in ("left_hip", "right_hip")]
    perfs = g["T"]
    fig, axes = plt.subplots(len(perfs), 2, figsize=(10, 3.2 * len(perfs)), squeeze=False)
    for row, p in enumerate(perfs):
        vids = performer_videos(ds, manifest, p, args.input, rng=np.random.default_rng([args.seed, int(p[1:])]))
        style = fit_action_style(model, est, vids, random_state=args.seed)
        true_m = true_instances(args.dataset, p, model, max_per_label=1, seed=args.seed)[args.label][0]
        n = true_m.n_frames
        seqs = {"true": keypoint_positions(true_m), "fitted": keypoint_positions(style.realise(model, args.label, n)),
                "unfitted": keypoint_positions(model.decode(mu, args.label, n_frames=n))}
        colours = {"true": "k", "fitted": "tab:blue", "unfitted": "tab:red"}
        for col, (view, (a, b)) in enumerate((("from above (x, z)", (0, 2)), ("from the side (z, y)", (2, 1)))):
            ax = axes[row, col]
            for name, pts in seqs.items():
                if name == "true":
                    idx = np.linspace(0, n - 1, 3).astype(int)
                else:
                    C = np.linalg.norm(pts[:, None] - seqs["true"][None], axis=-1).mean(-1)
                    _, path = dtw(C, 5)
                    path = np.asarray(path)
                    idx = [int(path[path[:, 1] == t][0, 0]) for t in np.linspace(0, n - 1, 3).astype(int)]
                for k, f in enumerate(idx):
                    off = np.array([0.0, 0.0, 0.0])
                    off[a] += k * 40.0 if a == 0 else 0.0
                    off[b] += 0.0
                    for i, j in bones:
                        q = pts[f, [i, j]] + (k * 45.0 if a == 0 else 0.0) * np.eye(3)[0] + (k * 45.0 if a == 2 else 0.0) * np.eye(3)[2]
                        ax.plot(q[:, a], q[:, b], colours[name], lw=1.2, alpha=0.85,
                                label=name if (i, j) == bones[0] and k == 0 else None)
            ax.set_aspect("equal")
            ax.set_title(f"{p} ({manifest['performers'][int(p[1:])]['style']['lead']}, fitted {style.global_style.lead}) "
                         f"{args.label}: {view}", fontsize=8)
            ax.tick_params(labelsize=6)
            if row == 0 and col == 0:
                ax.legend(fontsize=7)
    fig.suptitle(f"{args.label} of the test performers (split seed {args.seed}, {args.input} 2D): true, fitted, unfitted "
                 "(start / middle / end, offset)", fontsize=9)
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
