"""Evaluation protocol of the statistical action models on the demo dataset (``docs/actionmodel.md``).

Performers come from the recognition split (:func:`vidstyle.recognition.splits.performer_groups` of the
dataset's performers with the split seed): training = sets A and B, validation = V, test = T. For one
performer, :func:`evaluate_performer` fits an :class:`~vidstyle.actionmodel.ActionModel` on their
single-action takes and every performance take but the last, which is held out, and reports per label:

* ``fit_seconds`` (one label of one performer), ``sample_ms`` per instance;
* ``samples`` / ``sources``: :func:`vidstyle.actionmodel.metrics.pooled` naturalness of as many samples
  as the label has source instances (at least ``min_samples``), and of the source instances (the truth
  clips the motion graph is built from), and their ratios ``ratio_<figure>`` (samples / sources);
  ``samples_unpinned``: the same draws without foot pinning (what the pinning changes);
  ``sample_to_nearest_source_mm`` / ``source_to_nearest_other_mm``: medians of the nearest-neighbour
  distance (time-normalised joint positions) of each sample to the sources, and of each source to the
  other sources (novelty: samples are not copies, nor outliers);
* ``mpjpe_heldout_mm``: held-out instances (of the model's contact signature) through ``encode`` /
  ``decode`` at their own length; ``mpjpe_mean_mm``: the same instances against the decoded mean
  coefficients (z = 0) at their length, the error of knowing nothing about the instance.

:func:`evaluate_pooled` fits one model on several performers and reports the held-out reconstruction of
other performers' instances (unseen performers).
"""

from __future__ import annotations

import json
import logging
import time
from pathlib import Path

import numpy as np

log = logging.getLogger(__name__)


def read_manifest(dataset: str | Path) -> dict:
    from ..formats.dataset import read_dataset

    dataset = Path(dataset)
    read_dataset(dataset / "dataset.json")  # checked
    return json.loads((dataset / "dataset.json").read_text())


def split_groups(manifest: dict, seed: int) -> dict[str, list[str]]:
    from ..recognition.splits import performer_groups

    return performer_groups([p["id"] for p in manifest["performers"]], seed)


def performer_takes(dataset: str | Path, performer: str) -> tuple[list[Path], list[Path]]:
    """(single-action BVHs, performance BVHs sorted by take) of ``performer``."""
    mocap = Path(dataset) / "mocap"
    perf = sorted(mocap.glob(f"{performer}_perf*.bvh"), key=lambda p: int(p.stem.rsplit("perf", 1)[1]))
    singles = sorted(p for p in mocap.glob(f"{performer}_*.bvh") if "_perf" not in p.stem)
    return singles, perf


def _instances(paths, reference=None, params=None):
    from ..actionmodel import cut_instances, load_labelled

    p = params or {}
    return cut_instances(load_labelled(paths), p.get("min_frames", 6), p.get("min_run", 3), p.get("min_primitive", 3),
                         reference=reference)


def reconstruction(model, insts, unit_mm: float) -> dict:
    """Per label: held-out MPJPE through encode/decode and of the mean (z = 0), over the instances of the
    model's signature (others are counted, not scored)."""
    from ..actionmodel.metrics import mpjpe

    out = {}
    for label in model.labels_:
        lm = model.models_[label]
        sig = tuple(tuple(bool(x) for x in s) for s in lm.states)
        rows = [i for i in insts if i.label == label]
        use = [i for i in rows if i.signature == sig]
        err, base = [], []
        for inst in use:
            z = model.encode(inst, label)
            rec = model.decode(z, label, n_frames=inst.n_frames)
            err.append(mpjpe(rec, inst.motion, unit_mm))
            base.append(mpjpe(model.decode(np.zeros_like(z), label, n_frames=inst.n_frames), inst.motion, unit_mm))
        out[label] = {"heldout_instances": len(use), "heldout_other_signature": len(rows) - len(use),
                      "mpjpe_heldout_mm": float(np.mean(err)) if err else None,
                      "mpjpe_mean_mm": float(np.mean(base)) if base else None}
    return out


def evaluate_performer(dataset: str | Path, performer: str, params: dict, unit_mm: float, seed: int = 0,
                       min_samples: int = 10, naturalness: bool = True) -> dict:
    """Fit on ``performer``'s takes but the last performance; per label figures (module text)."""
    from ..actionmodel import ActionModel
    from ..actionmodel.metrics import FIGURES, nearest_distances, pooled, time_normalised_positions
    from ..actionmodel.metrics import naturalness as nat

    singles, perf = performer_takes(dataset, performer)
    train, held = singles + perf[:-1], perf[-1:]
    iset = _instances(train, params=params)
    model = ActionModel(**{**params, "random_state": seed}).fit(iset)
    held_insts = _instances(held, reference=model.skeleton_, params=params).instances
    rec = reconstruction(model, held_insts, unit_mm)
    out = {}
    for label in model.labels_:
        lm = model.models_[label]
        row = {"instances": lm.n_instances, "other_signature": lm.n_other_signature, "primitives": len(lm.keyframes),
               "coefficients": lm.n_coefficients, "spatial": lm.n_spatial, "temporal": lm.n_temporal,
               "gmm_components": lm.n_components, "covariance_type": lm.covariance_type,
               "fit_seconds": lm.fit_seconds, **rec[label]}
        srcs = iset.of(label)
        n = max(min_samples, len(srcs))
        t0 = time.perf_counter()
        samples = model.sample(label, n, random_state=seed)
        row["sample_ms"] = (time.perf_counter() - t0) / n * 1000
        if naturalness:
            s = pooled([nat(m, model.contact_height_, unit_mm) for m in samples])
            c = pooled([nat(i.motion, model.contact_height_, unit_mm) for i in srcs])
            raw = pooled([nat(m, model.contact_height_, unit_mm)
                          for m in model.sample(label, n, random_state=seed, pin=False)])
            row["samples"], row["samples_unpinned"], row["sources"] = s, raw, c
            src_pos = [time_normalised_positions(i.motion) for i in srcs]
            row["sample_to_nearest_source_mm"] = float(np.median(nearest_distances(
                [time_normalised_positions(m) for m in samples], src_pos, unit_mm)))
            row["source_to_nearest_other_mm"] = (float(np.median(nearest_distances(src_pos, src_pos, unit_mm, True)))
                                                 if len(src_pos) > 1 else None)
            for k in FIGURES:
                row[f"ratio_{k}"] = (s[k] / c[k]) if s[k] is not None and c[k] else None
        out[label] = row
    log.info("%s: fitted %d labels on %d takes, held out %s", performer, len(out), len(train),
             ", ".join(p.name for p in held))
    return {"labels": out, "held_out": [p.name for p in held], "trained_on": [p.name for p in train],
            "skipped": dict(model.skipped_), "contact_height": model.contact_height_}


def evaluate_pooled(dataset: str | Path, train_performers: list[str], test_performers: list[str], params: dict,
                    unit_mm: float, seed: int = 0) -> dict:
    """One model on every take of ``train_performers`` but their last performance; reconstruction of every
    instance of ``test_performers`` (unseen) and of the training performers' held-out takes."""
    from ..actionmodel import ActionModel

    train, held = [], []
    for p in train_performers:
        s, perf = performer_takes(dataset, p)
        train += s + perf[:-1]
        held += perf[-1:]
    t0 = time.perf_counter()
    iset = _instances(train, params=params)
    model = ActionModel(**{**params, "random_state": seed}).fit(iset)
    fit_s = time.perf_counter() - t0
    test = []
    for p in test_performers:
        s, perf = performer_takes(dataset, p)
        test += s + perf
    unseen = reconstruction(model, _instances(test, reference=model.skeleton_, params=params).instances, unit_mm)
    seen = reconstruction(model, _instances(held, reference=model.skeleton_, params=params).instances, unit_mm)
    labels = {}
    for label in model.labels_:
        lm = model.models_[label]
        labels[label] = {"instances": lm.n_instances, "gmm_components": lm.n_components,
                         "covariance_type": lm.covariance_type, "coefficients": lm.n_coefficients,
                         "fit_seconds": lm.fit_seconds,
                         "unseen": unseen[label], "heldout_take": seen[label]}
    return {"labels": labels, "fit_seconds_total": fit_s, "train_performers": list(train_performers),
            "test_performers": list(test_performers)}
