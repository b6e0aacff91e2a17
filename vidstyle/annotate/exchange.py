"""Export and import of one video's marks in the formats other tools read, each convention spelled out.

Our own (``native``): the annotations file itself (:mod:`vidstyle.formats.annotations`) holding the one
video: 0-based decoded frame indices, half-open segments ``[start, end)``, sha256 and decoded frame count.

``labelstudio`` - Label Studio JSON export of a video task with ``<TimelineLabels>`` (Label Studio >= 1.12):
    a list of one task ``{"data": {"video": name, ...}, "annotations": [{"result": [...]}]}``; each segment
    is a result ``{"type": "timelinelabels", "from_name": "actions", "to_name": "video", "value":
    {"ranges": [{"start": s, "end": e}], "timelinelabels": [action]}}`` where **ranges are 1-based and
    inclusive frame numbers**: our ``[start, end)`` is ``{"start": start + 1, "end": end}``. A transition at
    frame ``f`` is a one-frame range ``{"start": f + 1, "end": f + 1}`` of label ``"transition"`` from
    ``from_name: "transitions"`` with its actions, status and candidates in the region's ``meta.text[0]``
    (JSON). ``data`` also carries ``vidstyle_sha256``, ``vidstyle_frames``, ``vidstyle_fps`` and
    ``vidstyle_classes``; :func:`labelstudio_config` gives the project's labeling config. Label
    Studio numbers frames as ``time x fps`` in the browser; its frames equal decoded frames only on a
    constant-rate video, so a variable-rate video exports correctly but Label Studio may show it shifted.

``cvat`` - CVAT for video 1.1 XML: frames are **0-based** decoded indices (CVAT decodes with PyAV too).
    A segment is a ``<track>`` of its action label holding a whole-frame ``<box>`` with ``keyframe="1"
    outside="0"`` at ``start`` and, unless it runs to the last frame, a ``keyframe="1" outside="1"`` box at
    ``end`` (the first frame it is gone). A transition is a ``<tag frame="f" label="transition">`` with
    ``<attribute>``s ``from_action``, ``to_action``, ``status`` and ``candidates`` (JSON). On import every
    run of frames where a track is inside (the latest box at or before the frame has ``outside="0"``,
    keyframes or CVAT's interpolated per-frame boxes alike) becomes a segment.

``via`` - VGG Image Annotator 3 project JSON: **times in seconds**, not frames. Frame ``f`` is at its decoded
    presentation timestamp ``t[f]`` (seconds from the first frame) - never ``f / fps``, so variable-rate
    video is exact. A segment is a temporal region ``z = [t[start], t[end]]`` (``t[frames]`` = the video's
    duration) with attribute ``action``; a transition is a point ``z = [t[f]]`` with attributes
    ``from_action``, ``to_action``, ``status``, ``candidates`` (JSON). Times are written rounded to the
    millisecond (as VIA keeps them) and read back as the **nearest** decoded timestamp (segment ends: the
    nearest frame boundary).

Export then import is the identity on the transitions, segments and classes (tested on constant and
variable frame-rate videos). The performer choice (``performer``) travels in ``native`` only, and an import
brings marks, not a choice: the page keeps its own.
"""

from __future__ import annotations

import json
import math
import re
import xml.etree.ElementTree as ET
import xml.parsers.expat
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..fileio import parse_json_bytes
from ..formats import FormatError
from ..formats.annotations import (
    SCHEMA_VERSION,
    STATUSES,
    ActionSpan,
    Annotations,
    CandidateDecision,
    Transition,
    VideoAnnotations,
    from_document,
    to_document,
)

FORMATS = ("native", "labelstudio", "cvat", "via")
MEDIA = {"native": ("application/json", ".json"), "labelstudio": ("application/json", ".labelstudio.json"),
         "cvat": ("application/xml", ".cvat.xml"), "via": ("application/json", ".via.json")}
TRANSITION = "transition"


@dataclass
class Target:
    """What an exchange needs to know of the video: its annotations entry and decoded timestamps."""

    video: VideoAnnotations
    timestamps: np.ndarray  # seconds of each decoded frame from the first
    duration: float
    width: int
    height: int

    @property
    def name(self) -> str:
        return Path(self.video.path).name


@dataclass
class Marks:
    classes: list[str]
    transitions: list[Transition]
    segments: list[ActionSpan]


def export(fmt: str, classes: list[str], target: Target) -> bytes:
    if fmt not in FORMATS:
        raise FormatError(None, "format", f"{fmt!r} is not one of {', '.join(FORMATS)}")
    return {"native": _native_out, "labelstudio": _ls_out, "cvat": _cvat_out, "via": _via_out}[fmt](classes, target)


def import_(fmt: str, data: bytes, classes: list[str], target: Target, name: str = "import") -> Marks:
    """The marks in ``data``, checked against the video (frames inside it, segments not overlapping);
    actions unknown to ``classes`` are appended to the returned class list."""
    if fmt not in FORMATS:
        raise FormatError(None, "format", f"{fmt!r} is not one of {', '.join(FORMATS)}")
    try:
        marks = {"native": _native_in, "labelstudio": _ls_in, "cvat": _cvat_in, "via": _via_in}[fmt](
            data, ClassList(classes), target, name)
    except FormatError:
        raise
    except _Refused as e:
        raise FormatError(name, e.field, e.problem) from None
    except RecursionError:
        raise FormatError(name, None, f"not a valid {fmt} export (nested too deeply)") from None
    except (ValueError, KeyError, TypeError, IndexError, AttributeError, ET.ParseError, OverflowError,
            xml.parsers.expat.ExpatError) as e:
        raise FormatError(name, None, f"not a valid {fmt} export ({type(e).__name__}: {e})"[:300]) from None
    # one validation for all formats: the marks as our own file
    v = target.video
    doc = to_document_unchecked(marks, v)
    ann = from_document(doc, name)
    return Marks(ann.classes, ann.videos[0].transitions, ann.videos[0].segments)


def to_document_unchecked(marks: Marks, v: VideoAnnotations) -> dict:
    return {"kind": "vidstyle.annotations", "schema_version": SCHEMA_VERSION, "revision": 0,
            "classes": marks.classes,
            "videos": [{"path": v.path, "sha256": v.sha256, "frames": v.frames, "fps": v.fps,
                        "transitions": [_t_doc(t) for t in marks.transitions],
                        "segments": [{"start": s.start, "end": s.end, "action": s.action} for s in marks.segments]}]}


def _t_doc(t: Transition) -> dict:
    d = {"frame": t.frame, "from_action": t.from_action, "to_action": t.to_action, "status": t.status}
    if t.candidates:
        d["candidates"] = [{"clip": c.clip, "time": c.time, "status": c.status} for c in t.candidates]
    return d


def _extra(t: Transition) -> dict:
    return {"from_action": t.from_action, "to_action": t.to_action, "status": t.status,
            "candidates": [{"clip": c.clip, "time": c.time, "status": c.status} for c in t.candidates]}


def _transition(frame: int, extra: dict) -> Transition:
    cands = []
    for k, c in enumerate(extra.get("candidates", [])):
        time = c["time"]
        if isinstance(time, bool) or not isinstance(time, (int, float)) or not math.isfinite(time):
            raise _Refused(f"candidates[{k}].time", f"{time!r} is not a finite number of seconds")
        cands.append(CandidateDecision(str(c["clip"]), float(time), str(c["status"])))
    status = str(extra.get("status", "accepted"))
    if status not in STATUSES:
        raise ValueError(f"transition status {status!r}")
    return Transition(int(frame), str(extra["from_action"]), str(extra["to_action"]), status, cands)


class ClassList(list):
    """Class names in order with a set of them beside: adding one is O(1), so an import of many classes
    takes linear time (a list search per name made 20k classes take seconds)."""

    def __init__(self, names=()) -> None:
        super().__init__(names)
        self.known = set(self)

    def add(self, name: str) -> str:
        if name not in self.known:
            self.known.add(name)
            self.append(name)
        return name


class _Refused(Exception):
    """A value an importer refuses: the field and the problem (made a :class:`FormatError` naming the file)."""

    def __init__(self, field: str, problem: str) -> None:
        super().__init__(f"{field}: {problem}")
        self.field, self.problem = field, problem


_DIGITS = re.compile(r"[0-9]{1,12}")


def _int(value: Any, field: str) -> int:
    """A JSON integer, strictly: a float (even 3.0), a string, a boolean, ``Infinity`` or ``1e400`` is
    refused, never truncated."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise _Refused(field, f"{value!r} is not an integer frame number")
    return value


def _xml_int(text: str | None, field: str) -> int:
    """A non-negative integer written in ASCII digits in XML (``" 12"``, ``"1e3"``, ``"١٢"`` refused)."""
    if text is None or not _DIGITS.fullmatch(text):
        raise _Refused(field, f"{text!r} is not a frame number (ASCII digits)")
    return int(text)


def _seconds(value: Any, field: str, duration: float) -> float:
    """A VIA time: a finite number of seconds inside the video (0 .. duration, to VIA's millisecond)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _Refused(field, f"{value!r} is not a number of seconds")
    t = float(value)
    if not math.isfinite(t):
        raise _Refused(field, f"{value!r} is not a finite time")
    if not -_VIA_TOLERANCE <= t <= duration + _VIA_TOLERANCE:
        raise _Refused(field, f"{t:g} s is outside the video (0 .. {duration:.3f} s)")
    return t


def _add_class(classes: ClassList, name: str) -> str:
    return classes.add(name)


# ------------------------------------------------------------------------------------------ native
def _native_out(classes, target: Target) -> bytes:
    ann = Annotations(list(classes), [target.video], 0)
    return (json.dumps(to_document(ann), indent=2) + "\n").encode()


def _native_in(data: bytes, classes, target: Target, name) -> Marks:
    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise FormatError(name, None, f"not valid JSON ({e})") from None
    ann = from_document(doc, name)
    entry = ann.video(target.video.sha256)
    if entry is None:
        raise FormatError(name, "videos", f"no annotations of {target.name} (no video with its sha256)")
    if entry.frames != target.video.frames:
        raise FormatError(name, "frames", f"{entry.frames} frames, the video decodes to {target.video.frames}")
    for c in ann.classes:
        _add_class(classes, c)
    return Marks(classes, entry.transitions, entry.segments)


# ------------------------------------------------------------------------------------------ Label Studio
def _ls_out(classes, target: Target) -> bytes:
    v = target.video
    result: list[dict] = []
    for k, s in enumerate(sorted(v.segments, key=lambda s: s.start)):
        result.append({"id": f"seg{k}", "type": "timelinelabels", "from_name": "actions", "to_name": "video",
                       "origin": "manual",
                       "value": {"ranges": [{"start": s.start + 1, "end": s.end}], "timelinelabels": [s.action]}})
    for k, t in enumerate(sorted(v.transitions, key=lambda t: t.frame)):
        result.append({"id": f"tr{k}", "type": "timelinelabels", "from_name": "transitions", "to_name": "video",
                       "origin": "manual",
                       "value": {"ranges": [{"start": t.frame + 1, "end": t.frame + 1}],
                                 "timelinelabels": [TRANSITION]},
                       "meta": {"text": [json.dumps(_extra(t))]}})
    task = {"id": 1, "data": {"video": target.name, "vidstyle_sha256": v.sha256, "vidstyle_frames": v.frames,
                              "vidstyle_fps": v.fps, "vidstyle_classes": list(classes)},
            "annotations": [{"id": 1, "result": result}], "predictions": []}
    return (json.dumps([task], indent=2) + "\n").encode()


def _ls_in(data: bytes, classes, target: Target, name) -> Marks:
    doc = parse_json_bytes(data, name)  # strict: NaN / Infinity refused; 1e400 refused where read
    tasks = doc if isinstance(doc, list) else [doc]
    if not tasks:
        raise FormatError(name, None, "no task")
    task = next((t for t in tasks if t.get("data", {}).get("vidstyle_sha256") == target.video.sha256), None)
    if task is None:
        if len(tasks) != 1:
            raise FormatError(name, None, f"{len(tasks)} tasks and none is {target.name} (vidstyle_sha256)")
        task = tasks[0]
    d = task.get("data", {})
    if "vidstyle_frames" in d and _int(d["vidstyle_frames"], "data.vidstyle_frames") != target.video.frames:
        raise FormatError(name, "data.vidstyle_frames", f"{d['vidstyle_frames']} frames, the video decodes to "
                                                        f"{target.video.frames}")
    for c in d.get("vidstyle_classes", []):
        _add_class(classes, str(c))
    anns = task.get("annotations") or task.get("completions") or []
    if not anns:
        raise FormatError(name, "annotations", "the task has no annotation")
    segs, trans = [], []
    for i, r in enumerate(anns[-1]["result"]):
        if r.get("type") != "timelinelabels":
            continue
        val = r["value"]
        label = val["timelinelabels"][0]
        for j, rg in enumerate(val["ranges"]):
            where = f"annotations[-1].result[{i}].value.ranges[{j}]"
            start, end = _int(rg["start"], f"{where}.start"), _int(rg["end"], f"{where}.end")  # 1-based inclusive
            if not 1 <= start <= end <= target.video.frames:
                raise _Refused(where, f"frames {start}..{end} are not inside the video's 1..{target.video.frames} "
                                      "(1-based, inclusive, start <= end)")
            if r.get("from_name") == "transitions" or label == TRANSITION and "meta" in r:
                if start != end:
                    raise ValueError(f"a transition spans frames {start}..{end}")
                extra = parse_json_bytes(str(r["meta"]["text"][0]).encode(), name)
                t = _transition(start - 1, extra)
                _add_class(classes, t.from_action)
                _add_class(classes, t.to_action)
                trans.append(t)
            else:
                segs.append(ActionSpan(start - 1, end, _add_class(classes, str(label))))
    return Marks(classes, trans, segs)


# ------------------------------------------------------------------------------------------ CVAT
def _cvat_out(classes, target: Target) -> bytes:
    v = target.video
    n = v.frames
    root = ET.Element("annotations")
    ET.SubElement(root, "version").text = "1.1"
    meta = ET.SubElement(root, "meta")
    task = ET.SubElement(meta, "task")
    for k, val in (("name", target.name), ("size", n), ("mode", "interpolation"), ("overlap", 0),
                   ("start_frame", 0), ("stop_frame", n - 1), ("frame_filter", "")):
        ET.SubElement(task, k).text = str(val)
    labels = ET.SubElement(task, "labels")
    for c in classes:
        lab = ET.SubElement(labels, "label")
        ET.SubElement(lab, "name").text = c
        ET.SubElement(lab, "type").text = "rectangle"
        ET.SubElement(lab, "attributes")
    lab = ET.SubElement(labels, "label")
    ET.SubElement(lab, "name").text = TRANSITION
    ET.SubElement(lab, "type").text = "tag"
    attrs = ET.SubElement(lab, "attributes")
    for a in ("from_action", "to_action", "status", "candidates"):
        at = ET.SubElement(attrs, "attribute")
        ET.SubElement(at, "name").text = a
        ET.SubElement(at, "input_type").text = "select" if a == "status" else "text"
    size = ET.SubElement(task, "original_size")
    ET.SubElement(size, "width").text = str(target.width)
    ET.SubElement(size, "height").text = str(target.height)
    ET.SubElement(meta, "source").text = target.name
    ET.SubElement(meta, "vidstyle_sha256").text = v.sha256
    box = {"occluded": "0", "xtl": "0.00", "ytl": "0.00", "xbr": f"{target.width:.2f}",
           "ybr": f"{target.height:.2f}", "z_order": "0"}
    for k, s in enumerate(sorted(v.segments, key=lambda s: s.start)):
        tr = ET.SubElement(root, "track", id=str(k), label=s.action, source="manual")
        ET.SubElement(tr, "box", frame=str(s.start), keyframe="1", outside="0", **box)
        if s.end < n:
            ET.SubElement(tr, "box", frame=str(s.end), keyframe="1", outside="1", **box)
    for t in sorted(v.transitions, key=lambda t: t.frame):
        tag = ET.SubElement(root, "tag", frame=str(t.frame), label=TRANSITION, source="manual")
        ex = _extra(t)
        for a in ("from_action", "to_action", "status"):
            ET.SubElement(tag, "attribute", name=a).text = ex[a]
        ET.SubElement(tag, "attribute", name="candidates").text = json.dumps(ex["candidates"])
    ET.indent(root)
    return b'<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="utf-8") + b"\n"


def _refuse_dtd(*_args) -> None:
    raise _Refused("DOCTYPE", "XML with a document type declaration or entities is not accepted")


def _safe_xml(data: bytes) -> ET.Element:
    """Parse ``data`` with no DTD and no entity: expat reads it first, in whatever encoding it declares
    (UTF-16 too, which a byte search for ``<!DOCTYPE`` misses), and stops at a document type
    declaration, an entity declaration or an external entity reference; only then is the tree built."""
    scan = xml.parsers.expat.ParserCreate()
    scan.SetParamEntityParsing(xml.parsers.expat.XML_PARAM_ENTITY_PARSING_NEVER)
    scan.StartDoctypeDeclHandler = _refuse_dtd
    scan.EntityDeclHandler = _refuse_dtd
    scan.UnparsedEntityDeclHandler = _refuse_dtd
    scan.ExternalEntityRefHandler = _refuse_dtd
    scan.Parse(data, True)
    return ET.fromstring(data)


def _cvat_in(data: bytes, classes, target: Target, name) -> Marks:
    root = _safe_xml(data)
    if root.tag != "annotations":
        raise FormatError(name, None, f"root element <{root.tag}>, expected <annotations> (CVAT for video 1.1)")
    n = target.video.frames
    size = root.findtext("meta/task/size")
    if size is not None and _xml_int(size, "meta.task.size") != n:
        raise FormatError(name, "meta.task.size", f"{size} frames, the video decodes to {n}")
    start_frame = _xml_int(root.findtext("meta/task/start_frame") or "0", "meta.task.start_frame")
    for lab in root.findall("meta/task/labels/label"):
        nm = lab.findtext("name")
        if nm and nm != TRANSITION and (lab.findtext("type") or "") != "tag":
            _add_class(classes, nm)
    segs = []
    for k, tr in enumerate(root.findall("track")):
        label = tr.get("label")
        shapes = sorted(((_xml_int(b.get("frame"), f"track[{k}].{b.tag}.frame") - start_frame,
                          _xml_flag(b.get("outside", "0"), f"track[{k}].{b.tag}.outside")) for b in tr),
                        key=lambda x: x[0])
        if not shapes:
            continue
        _add_class(classes, label)
        run_start = None
        for f, outside in shapes:
            if not outside and run_start is None:
                run_start = f
            elif outside and run_start is not None:
                segs.append(ActionSpan(run_start, f, label))
                run_start = None
        if run_start is not None:
            segs.append(ActionSpan(run_start, n, label))
    trans = []
    for k, tag in enumerate(root.findall("tag")):
        if tag.get("label") != TRANSITION:
            continue
        attrs = {a.get("name"): (a.text or "") for a in tag.findall("attribute")}
        extra = {k: attrs[k] for k in ("from_action", "to_action", "status") if k in attrs}
        extra["candidates"] = parse_json_bytes((attrs.get("candidates") or "[]").encode(), name)
        t = _transition(_xml_int(tag.get("frame"), f"tag[{k}].frame") - start_frame, extra)
        _add_class(classes, t.from_action)
        _add_class(classes, t.to_action)
        trans.append(t)
    return Marks(classes, trans, segs)


def _xml_flag(text: str | None, field: str) -> bool:
    if text not in ("0", "1"):
        raise _Refused(field, f"{text!r} is not 0 or 1")
    return text == "1"


# ------------------------------------------------------------------------------------------ VIA 3
_VIA_ATTR = {"1": "action", "2": "from_action", "3": "to_action", "4": "status", "5": "candidates"}


def _boundaries(target: Target) -> np.ndarray:
    """t[0..frames-1] and the duration: the time of each frame boundary (frame f starts at b[f])."""
    return np.append(np.asarray(target.timestamps, dtype=np.float64), target.duration)


def _via_out(classes, target: Target) -> bytes:
    v = target.video
    b = _boundaries(target)
    attribute = {
        "1": {"aname": "action", "anchor_id": "FILE1_Z2_XY0", "type": 4, "desc": "action segment",
              "options": {str(k): c for k, c in enumerate(classes)}, "default_option_id": ""},
        "2": {"aname": "from_action", "anchor_id": "FILE1_Z1_XY0", "type": 1, "desc": "transition from",
              "options": {}, "default_option_id": ""},
        "3": {"aname": "to_action", "anchor_id": "FILE1_Z1_XY0", "type": 1, "desc": "transition to",
              "options": {}, "default_option_id": ""},
        "4": {"aname": "status", "anchor_id": "FILE1_Z1_XY0", "type": 3, "desc": "accepted | discarded",
              "options": {"0": "accepted", "1": "discarded"}, "default_option_id": "0"},
        "5": {"aname": "candidates", "anchor_id": "FILE1_Z1_XY0", "type": 1, "desc": "enhancement nodes (JSON)",
              "options": {}, "default_option_id": ""},
    }
    metadata = {}
    option = {}
    for k, c in enumerate(classes):
        option.setdefault(c, k)
    for k, s in enumerate(sorted(v.segments, key=lambda s: s.start)):
        metadata[f"1_seg{k}"] = {"vid": "1", "flg": 0, "z": [round(float(b[s.start]), 3), round(float(b[s.end]), 3)],
                                 "xy": [], "av": {"1": str(option[s.action])}}
    for k, t in enumerate(sorted(v.transitions, key=lambda t: t.frame)):
        metadata[f"1_tr{k}"] = {"vid": "1", "flg": 0, "z": [round(float(b[t.frame]), 3)], "xy": [],
                                "av": {"2": t.from_action, "3": t.to_action, "4": str(STATUSES.index(t.status)),
                                       "5": json.dumps(_extra(t)["candidates"])}}
    doc = {
        "project": {"pid": "__VIA_PROJECT_ID__", "rev": "__VIA_PROJECT_REV_ID__", "rev_timestamp": "",
                    "pname": target.name, "creator": "vidstyle annotate", "created": 0,
                    "vid_list": ["1"]},
        "config": {"file": {"loc_prefix": {"1": "", "2": "", "3": "", "4": ""}},
                   "ui": {"file_content_align": "center", "file_metadata_editor_visible": True,
                          "spatial_metadata_editor_visible": True, "temporal_segment_metadata_editor_visible": True,
                          "spatial_region_label_attribute_id": "", "gtimeline_visible_row_count": "4"}},
        "attribute": attribute,
        "file": {"1": {"fid": "1", "fname": target.name, "type": 4, "loc": 1, "src": ""}},
        "view": {"1": {"fid_list": ["1"]}},
        "metadata": metadata,
        "vidstyle": {"sha256": v.sha256, "frames": v.frames},
    }
    return (json.dumps(doc, indent=2) + "\n").encode()


#: how far (seconds) a VIA time may lie outside the video: VIA keeps times to the millisecond
_VIA_TOLERANCE = 0.0005


def _nearest(b: np.ndarray, t: float, lo: int, hi: int) -> int:
    i = int(np.argmin(np.abs(b[lo:hi + 1] - t)))
    return lo + i


def _via_in(data: bytes, classes, target: Target, name) -> Marks:
    doc = parse_json_bytes(data, name)  # strict: NaN / Infinity refused; 1e400 refused where read
    n = target.video.frames
    vs = doc.get("vidstyle", {})
    if "frames" in vs and _int(vs["frames"], "vidstyle.frames") != n:
        raise FormatError(name, "vidstyle.frames", f"{vs['frames']} frames, the video decodes to {n}")
    names = {aid: a["aname"] for aid, a in doc["attribute"].items()}
    by_name = {v: k for k, v in names.items()}
    action_opts = doc["attribute"][by_name["action"]].get("options", {}) if "action" in by_name else {}
    for k in sorted(action_opts, key=lambda k: int(k) if str(k).isdigit() else 0):
        _add_class(classes, action_opts[k])
    status_opts = doc["attribute"].get(by_name.get("status", ""), {}).get("options", {})
    b = _boundaries(target)
    segs, trans = [], []
    duration = float(b[-1])
    for key, md in doc["metadata"].items():
        z = [_seconds(x, f"metadata.{key}.z[{j}]", duration) for j, x in enumerate(md["z"])]
        av = {names.get(k, k): v for k, v in md.get("av", {}).items()}
        if len(z) == 2:
            opt = av["action"]
            action = action_opts.get(opt, opt)
            if not z[0] < z[1]:
                raise _Refused(f"metadata.{key}.z", f"segment {z[0]:g} .. {z[1]:g} s does not end after it starts")
            start = _nearest(b, z[0], 0, n - 1)
            end = _nearest(b, z[1], 0, n)
            if end <= start:
                raise _Refused(f"metadata.{key}.z", f"segment {z[0]:g} .. {z[1]:g} s is shorter than one frame")
            segs.append(ActionSpan(start, end, _add_class(classes, action)))
        elif len(z) == 1:
            frame = _nearest(b, z[0], 0, n - 1)
            status = status_opts.get(av.get("status", "0"), av.get("status", "accepted"))
            t = _transition(frame, {"from_action": av["from_action"], "to_action": av["to_action"],
                                    "status": status,
                                    "candidates": parse_json_bytes(str(av.get("candidates") or "[]").encode(), name)})
            _add_class(classes, t.from_action)
            _add_class(classes, t.to_action)
            trans.append(t)
    return Marks(classes, trans, segs)


def labelstudio_config(classes: list[str]) -> str:
    """The Label Studio labeling config that matches :func:`export` ``labelstudio`` files (paste it into a
    project's Labeling Interface, then import the exported JSON as tasks)."""
    from xml.sax.saxutils import quoteattr

    labels = "".join(f"<Label value={quoteattr(c)}/>" for c in classes)
    return ('<View><Video name="video" value="$video" framerate="$vidstyle_fps"/>'
            f'<TimelineLabels name="actions" toName="video">{labels}</TimelineLabels>'
            f'<TimelineLabels name="transitions" toName="video"><Label value="{TRANSITION}"/></TimelineLabels></View>')


def default_filename(fmt: str, target: Target) -> str:
    return Path(target.name).stem + MEDIA[fmt][1]


def describe() -> dict[str, Any]:
    return {f: {"media_type": MEDIA[f][0], "suffix": MEDIA[f][1]} for f in FORMATS}
