"""ONNX export of the recognizer, for use outside Python.

The graph takes the per-frame context word counts (``counts``: float32 (frames, n_words) — what
:meth:`ActionRecognizer.histograms` returns; computing them needs only the vocabulary centres in
``vocab.npz`` and a nearest-centre search) and computes, in float64:

    word grouping (MatMul by the 0/1 pooling matrix) -> row normalisation -> PCA (Sub mean, MatMul) ->
    RBF kernel against the union of the support vectors -> MatMul dual coefficients + intercepts

and outputs ``ova`` (frames, K) and ``ovo`` (frames, K(K-1)/2) decision values and ``features`` (the PCA
vector). The one-vs-all / one-vs-one resolution is a few comparisons, done by the same numpy function the
Python model uses (:func:`vidstyle.recognition.classifier.combine_ova_ovo`); its rules are documented in
the model's ``metadata_props`` (``vidstyle``: JSON with classes, pairs, thresholds, smoothing).

skl2onnx has no converter for this combination of custom pooling and a packed multi-machine SVM, so the
graph is written with :mod:`onnx.helper` from standard ai.onnx operators only (opset 18); it runs on any
ONNX runtime. Only the ``ova-ovo`` classifier is exported.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np

from ..errors import InputError
from .classifier import OvaOvoSVC, combine_ova_ovo, softmax
from .smoothing import DurationModel, smooth_labels

log = logging.getLogger(__name__)

OPSET = 18


def build_onnx(model) -> "onnx.ModelProto":  # noqa: F821
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    clf = model.clf_
    if not isinstance(clf, OvaOvoSVC):
        raise InputError("onnx export: only the 'ova-ovo' classifier can be exported")
    V = model.vocabulary.n_words_
    G = model.grouping_.matrix_.toarray().astype(np.float64)
    pca = model.pca_
    K = len(clf.classes_)
    inits = {
        "G": G,
        "pca_mean": pca.mean_.astype(np.float64),
        "pca_W": pca.components_.T.astype(np.float64),
        "sv_T": clf.support_vectors_.T.astype(np.float64),
        "sv_sq": np.einsum("ij,ij->i", clf.support_vectors_, clf.support_vectors_)[None, :].astype(np.float64),
        "dual": clf.dual_coef_.astype(np.float64),
        "bias": clf.intercept_[None, :].astype(np.float64),
        "neg_gamma": np.array(-clf.gamma_, np.float64),
        "minus_two": np.array(-2.0, np.float64),
        "zero": np.array(0.0, np.float64),
        "tiny": np.array(1e-300, np.float64),
        "axis1": np.array([1], np.int64),
        "split": np.array([K, clf.dual_coef_.shape[1] - K], np.int64),
    }
    initializers = [numpy_helper.from_array(v, name=k) for k, v in inits.items()]
    n = []
    n.append(helper.make_node("Cast", ["counts"], ["c64"], to=TensorProto.DOUBLE))
    nb = int(getattr(model, "n_blocks", 1))
    if nb == 1:
        n += _group_and_normalise(helper, model.normalize, "c64", "normed", "")
    else:  # multi-scale context: one block per context, grouped and normalised separately
        initializers.append(numpy_helper.from_array(np.full(nb, V, np.int64), name="blocks"))
        n.append(helper.make_node("Split", ["c64", "blocks"], [f"c64_{b}" for b in range(nb)], axis=1))
        for b in range(nb):
            n += _group_and_normalise(helper, model.normalize, f"c64_{b}", f"normed_{b}", f"_{b}")
        n.append(helper.make_node("Concat", [f"normed_{b}" for b in range(nb)], ["normed"], axis=1))
    n.append(helper.make_node("Sub", ["normed", "pca_mean"], ["centred"]))
    n.append(helper.make_node("MatMul", ["centred", "pca_W"], ["features"]))
    # ||x - s||^2 = ||x||^2 - 2 x.s + ||s||^2, clipped at 0 against rounding, as in rbf_kernel
    n.append(helper.make_node("ReduceSumSquare", ["features", "axis1"], ["x_sq"], keepdims=1))
    n.append(helper.make_node("MatMul", ["features", "sv_T"], ["xs"]))
    n.append(helper.make_node("Mul", ["xs", "minus_two"], ["m2xs"]))
    n.append(helper.make_node("Add", ["m2xs", "x_sq"], ["d1"]))
    n.append(helper.make_node("Add", ["d1", "sv_sq"], ["d2"]))
    n.append(helper.make_node("Max", ["d2", "zero"], ["dist"]))
    n.append(helper.make_node("Mul", ["dist", "neg_gamma"], ["arg"]))
    n.append(helper.make_node("Exp", ["arg"], ["kernel"]))
    n.append(helper.make_node("MatMul", ["kernel", "dual"], ["kd"]))
    n.append(helper.make_node("Add", ["kd", "bias"], ["decision"]))
    n.append(helper.make_node("Split", ["decision", "split"], ["ova", "ovo"], axis=1))
    graph = helper.make_graph(
        n,
        "vidstyle_recognizer",
        [helper.make_tensor_value_info("counts", TensorProto.FLOAT, ["frames", V * nb])],
        [
            helper.make_tensor_value_info("ova", TensorProto.DOUBLE, ["frames", K]),
            helper.make_tensor_value_info("ovo", TensorProto.DOUBLE, ["frames", len(clf.pairs_)]),
            helper.make_tensor_value_info("features", TensorProto.DOUBLE, ["frames", int(pca.n_components_)]),
        ],
        initializers,
    )
    m = helper.make_model(graph, opset_imports=[helper.make_opsetid("", OPSET)], producer_name="vidstyle")
    m.ir_version = 8
    meta = {
        "classes": [str(c) for c in model.classes_],
        "classifier_classes": [int(c) for c in clf.classes_],
        "pairs": [list(p) for p in clf.pairs_],
        "claim_threshold": clf.claim_threshold,
        "n_competitors": clf.n_competitors,
        "context": model.context,
        "coarse_context": int(getattr(model, "coarse_context", 0)),
        "n_words": V,
        "normalize": model.normalize,
        "smoothing_window": model.smoothing_window,
        "smoothing": model.smoothing,
        "emission_weight": float(getattr(model, "emission_weight", 1.0)),
        "transitions": None if getattr(model, "transitions_", None) is None else np.asarray(model.transitions_).tolist(),
        "durations": None if getattr(model, "durations_", None) is None else model.durations_.to_dict(),
        "rules": "claims = ova > claim_threshold; one claim -> that class; several -> the claimants, none -> the "
        "n_competitors best ova play one-vs-one (ovo[:, p] > 0 -> pairs[p][0]); most wins, draw -> higher ova",
    }
    onnx.helper.set_model_props(m, {"vidstyle": json.dumps(meta)})
    onnx.checker.check_model(m)
    return m


def _group_and_normalise(helper, norm: str, src: str, dst: str, sfx: str) -> list:
    """Nodes: ``dst`` = rows of ``src`` @ G, normalised by ``norm`` (as :func:`normalize_rows`)."""
    g = f"grouped{sfx}"
    n = [helper.make_node("MatMul", [src, "G"], [g])]
    if norm == "none":
        n.append(helper.make_node("Identity", [g], [dst]))
    elif norm in ("l1", "sqrt"):
        n.append(helper.make_node("ReduceSum", [g, "axis1"], [f"rsum{sfx}"], keepdims=1))
        # counts are >= 0: an all-zero row divided by the tiny floor stays zero, as in the Python path
        n.append(helper.make_node("Max", [f"rsum{sfx}", "tiny"], [f"rsum_safe{sfx}"]))
        n.append(helper.make_node("Div", [g, f"rsum_safe{sfx}"], [f"l1{sfx}" if norm == "sqrt" else dst]))
        if norm == "sqrt":
            n.append(helper.make_node("Sqrt", [f"l1{sfx}"], [dst]))
    else:  # l2
        n.append(helper.make_node("ReduceSumSquare", [g, "axis1"], [f"rss{sfx}"], keepdims=1))
        n.append(helper.make_node("Sqrt", [f"rss{sfx}"], [f"rnorm{sfx}"]))
        n.append(helper.make_node("Max", [f"rnorm{sfx}", "tiny"], [f"rnorm_safe{sfx}"]))
        n.append(helper.make_node("Div", [g, f"rnorm_safe{sfx}"], [dst]))
    return n


def export_onnx(model, path: str | Path) -> None:
    from ..fileio import atomic_path

    m = build_onnx(model)
    with atomic_path(path) as tmp:
        tmp.write_bytes(m.SerializeToString())


class OnnxRecognizer:
    """Runs an exported model with onnxruntime and resolves OvA/OvO claims in numpy."""

    def __init__(self, path: str | Path):
        import onnx
        import onnxruntime as ort

        path = Path(path)
        if not path.is_file():
            raise InputError(f"{path}: ONNX model not found")
        props = {p.key: p.value for p in onnx.load(str(path), load_external_data=False).metadata_props}
        if "vidstyle" not in props:
            raise InputError(f"{path}: not a vidstyle ONNX recognizer")
        self.meta = json.loads(props["vidstyle"])
        self.session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
        self.classes_ = np.array(self.meta["classes"])

    def decision(self, counts) -> tuple[np.ndarray, np.ndarray]:
        H = counts.toarray() if hasattr(counts, "toarray") else np.asarray(counts)
        ova, ovo, _ = self.session.run(None, {"counts": H.astype(np.float32)})
        return ova, ovo

    def predict_histograms(self, counts) -> dict[str, np.ndarray]:
        ova, ovo = self.decision(counts)
        pairs = [tuple(p) for p in self.meta["pairs"]]
        pred, _ = combine_ova_ovo(ova, ovo, pairs, self.meta["claim_threshold"], self.meta["n_competitors"])
        present = np.asarray(self.meta["classifier_classes"], np.int64)
        s = softmax(ova)
        scores = np.zeros((len(pred), len(self.classes_)))
        scores[:, present] = s
        raw = present[pred]
        conf = s[np.arange(len(pred)), pred]
        sm, sconf = smooth_labels(
            raw, len(self.classes_), self.meta["smoothing_window"], conf, scores, self.meta["smoothing"],
            transitions=None if self.meta.get("transitions") is None else np.asarray(self.meta["transitions"]),
            emission_weight=self.meta.get("emission_weight", 1.0),
            durations=None if self.meta.get("durations") is None else DurationModel.from_dict(self.meta["durations"]),
        )
        return {"raw": raw, "scores": scores, "confidence": conf, "smoothed": sm, "smoothed_confidence": sconf}
