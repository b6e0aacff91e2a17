"""``library.json``: the manifest of an AugMG mocap library (``vidstyle demo make-library``).

Schema (``kind`` = ``"vidstyle.library"``, ``schema_version`` 1)::

    {"kind": "vidstyle.library", "schema_version": 1,
     "params": {"seed": 0, "performers": 3, ...},        # the LibraryParams the library was made with
     "performers": [{"id": "lib00", ...}, ...],          # each library performer (body, style, ...)
     "clips": [{"name": "lib00_jab", "performer": "lib00",
                "kind": "action",                          # action | context | cmu
                "holds_pose": null,                        # context clips: the transition pose they hold
                "frames": 360,                             # frames of the BVH
                "bvh": "clips/lib00_jab.bvh",              # relative to the manifest's directory
                "labels": "clips/lib00_jab.labels.json",
                "source": "../shared/.../02_05.bvh"}]}     # cmu clips only: the retargeted original

Clip names are unique, and their paths stay inside the library directory.
"""

from __future__ import annotations

import os
from pathlib import PurePosixPath
from typing import Any

from ._base import Fields, FormatError, check_header, check_leaves, header, read_json_document, write_checked

KIND = "vidstyle.library"
SCHEMA_VERSION = 1
CLIP_KINDS = ("action", "context", "cmu")


def _relative(f: Fields, key: str) -> str:
    p = f.str(key, nonempty=True)
    parts = PurePosixPath(p).parts
    if p.startswith("/") or ".." in parts or "\\" in p:
        raise f.fail(key, f"{p!r} must be a path inside the library directory")
    return p


def parse_library(doc: Any, path: str | os.PathLike | None = None) -> dict:
    """Validate a manifest document; returns it as a plain dict (FormatError names the field)."""
    check_header(doc, path, KIND, (SCHEMA_VERSION,))
    top = Fields(doc, path)
    params = top.sub("params")
    params.int("seed", min=0)
    check_leaves(params.obj, path, "params")
    performers = top.list("performers")
    for i, p in enumerate(performers):
        Fields(p, path, f"performers[{i}]").str("id", nonempty=True)
        check_leaves(p, path, f"performers[{i}]")
    clips, names = [], set()
    for i, raw in enumerate(top.list("clips", min_len=1)):
        f = Fields(raw, path, f"clips[{i}]")
        name = f.str("name", nonempty=True)
        if name in names:
            raise f.fail("name", f"duplicate clip name {name!r}")
        names.add(name)
        kind = f.str("kind", choices=CLIP_KINDS)
        clip = {"name": name, "performer": f.str("performer", nonempty=True), "kind": kind,
                "holds_pose": f.str("holds_pose", required=False), "frames": f.int("frames", min=1),
                "bvh": _relative(f, "bvh"), "labels": _relative(f, "labels")}
        if kind == "cmu":
            clip["source"] = f.str("source", nonempty=True)
        clips.append(clip)
    return {**header(KIND, SCHEMA_VERSION), "params": dict(params.obj), "performers": list(performers), "clips": clips}


def library_document(params: dict, performers: list[dict], clips: list[dict]) -> dict:
    return {**header(KIND, SCHEMA_VERSION), "params": params, "performers": performers, "clips": clips}


def read_library(path: str | os.PathLike) -> dict:
    """Read and validate a ``library.json``."""
    return parse_library(read_json_document(path), path)


def write_library(path: str | os.PathLike, doc: dict) -> None:
    """Validate ``doc`` (as the reader would) and write it atomically."""
    write_checked(path, doc, parse_library, "library manifest")


__all__ = ["FormatError", "KIND", "SCHEMA_VERSION", "library_document", "parse_library", "read_library",
           "write_library"]
