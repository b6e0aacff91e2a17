"""Why real punches are not recognised as punches: `vidstyle evaluate strikes` on controlled variants.

Diagnostics only - nothing here trains, tunes or selects anything (the recognizer is used as given,
and no default is chosen from these numbers). Each variant goes through the same evaluation
(:func:`vidstyle.evaluation.realmocap.evaluate_strikes`: same cameras, looks, seed, action-frame rule
recomputed on the variant's own motion):

* ``original``  - CMU 02_05 as captured (orthodox stance, nine right-hand = rear-hand straight punches);
* ``mirrored``  - its left-right mirror image (a southpaw throwing left-hand rear punches);
* ``arms_only`` - only the arms move: pelvis, legs, spine and head frozen at the clip's first frame
  (is it the real body's sway and footwork that reads as kicks?);
* ``upper_body`` - pelvis and legs frozen (and the root in place), spine, head and arms as captured
  (the torso's turn into the punch kept, the footwork and weight shift gone);
* ``slower`` / ``faster`` - played at 0.67x / 1.5x speed (is it the speed of real punches?);
* ``demo_<take>`` - procedural test-performer punches of the demo dataset (never trained on), their
  action frames from the take's ground-truth labels: the same harness on the motion the recognizer
  knows, which separates camera effects from real-motion effects.

    python scripts/strikes_diagnostics.py --bvh ../shared/data/mocap/cmu/02_05.bvh \\
        --model pipelines/kickboxing/out/models/recognizer.joblib \\
        --demo-mocap pipelines/kickboxing/out/dataset/mocap --demo-takes p02_jab,p04_jab,p06_jab \\
        --out pipelines/kickboxing/strikes/diagnostics_seed0.json

Prints a Markdown table (punch fraction of the action frames, smoothed labels, per camera and overall)
and writes all documents to ``--out`` (kind ``vidstyle.metrics.strikes`` per variant under ``variants``).
"""

from __future__ import annotations

import argparse
import logging
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vidstyle.formats.validation import write_validation
from vidstyle.mocap import Motion, read_bvh, write_bvh
from vidstyle.evaluation.realmocap import DEFAULT_CAMERAS, StrikeEvalParams, evaluate_strikes

log = logging.getLogger("strikes_diagnostics")

ARM_PREFIXES = ("LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand", "LeftFinger", "LThumb",
                "RightShoulder", "RightArm", "RightForeArm", "RightHand", "RightFinger", "RThumb")


def arms_only(m: Motion) -> Motion:
    """Everything but the arms (and the root position) frozen at frame 0."""
    rot = m.rotations.copy()
    tr = m.translations.copy()
    for j, name in enumerate(m.skeleton.names):
        if not name.startswith(ARM_PREFIXES):
            rot[:, j] = rot[0, j]
    tr[:, 0] = tr[0, 0]
    return Motion(m.skeleton, rot, tr, m.fps)


LEG_PREFIXES = ("LHipJoint", "LeftUpLeg", "LeftLeg", "LeftFoot", "LeftToe", "RHipJoint", "RightUpLeg", "RightLeg",
                "RightFoot", "RightToe")


def upper_body(m: Motion) -> Motion:
    """Root (rotation and position) and legs frozen at frame 0; spine, head and arms as captured."""
    rot = m.rotations.copy()
    tr = m.translations.copy()
    for j, name in enumerate(m.skeleton.names):
        if j == 0 or name.startswith(LEG_PREFIXES):
            rot[:, j] = rot[0, j]
    tr[:, 0] = tr[0, 0]
    return Motion(m.skeleton, rot, tr, m.fps)


def retimed(m: Motion, speed: float) -> Motion:
    """Played ``speed`` times as fast (resampled back to the clip's rate)."""
    return Motion(m.skeleton, m.rotations, m.translations, m.fps * speed).resample(m.fps)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bvh", required=True, type=Path)
    ap.add_argument("--model", required=True, type=Path)
    ap.add_argument("--demo-mocap", type=Path, help="the demo dataset's mocap/ directory (BVH + labels)")
    ap.add_argument("--demo-takes", default="", help="comma-separated takes of test performers, e.g. p02_jab")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", required=True, type=Path)
    a = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s", stream=sys.stderr)

    real = read_bvh(a.bvh)[1:]  # frame 0 of a CMU file is a T-pose
    variants = {"original": real, "mirrored": real.mirror(), "arms_only": arms_only(real),
                "upper_body": upper_body(real),
                "slower": retimed(real, 0.67), "faster": retimed(real, 1.5)}
    docs = {}
    with tempfile.TemporaryDirectory(prefix="strikes-diag-") as tmp:
        for name, motion in variants.items():
            path = Path(tmp) / f"{name}.bvh"
            write_bvh(motion, path)
            log.info("variant %s", name)
            docs[name] = evaluate_strikes(path, a.model, DEFAULT_CAMERAS, params=StrikeEvalParams(start=0),
                                          seed=a.seed)
        for take in [t for t in a.demo_takes.split(",") if t]:
            log.info("demo take %s", take)
            docs[f"demo_{take}"] = evaluate_strikes(
                a.demo_mocap / f"{take}.bvh", a.model, DEFAULT_CAMERAS, params=StrikeEvalParams(start=0),
                seed=a.seed, actions=a.demo_mocap / f"{take}.labels.json", action_labels=("Jab", "Hook", "Uppercut"))
    cams = [c.name for c in DEFAULT_CAMERAS]
    lines = ["| variant | " + " | ".join(cams) + " | overall | punch share of punch+kick |",
             "|---|" + "---:|" * (len(cams) + 2)]

    def pct(v):
        return "n/a" if v is None else f"{100 * v:.1f} %"

    for name, d in docs.items():
        per = [pct(c["smoothed"]["punch_fraction"]) for c in d["cameras"]]
        o = d["overall"]["smoothed"]
        lines.append(f"| {name} | " + " | ".join(per) + f" | {pct(o['punch_fraction'])} | "
                     f"{pct(o['punch_share_of_strikes'])} |")
    table = "\n".join(lines)
    print(table)
    write_validation(a.out, {"kind": "vidstyle.strikes_diagnostics", "schema_version": 1, "seed": a.seed,
                             "command": "python scripts/strikes_diagnostics.py " + " ".join(argv or sys.argv[1:]),
                             "table": table, "variants": docs})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
