"""Files vidstyle writes for a new project: the template pipeline (``vidstyle init DIR``).

``pipeline/dvc.yaml`` and ``pipeline/params.yaml`` are the repository's ``pipelines/template/`` (tested
equal): method 1 and method 2 on a folder of videos, an annotations file and a labelled mocap library.
:func:`write_pipeline` copies them into a directory with ``params.yaml`` pointing at the user's files,
the classes and marked videos read from the annotations file.
"""

from __future__ import annotations

import os
import re
from collections.abc import Sequence
from importlib import resources
from pathlib import Path

from ..errors import InputError

FILES = ("dvc.yaml", "params.yaml")
#: the validated values of the demo (pipelines/kickboxing) that the committed example loosens for its
#: three-clip library; a new project starts from them
VALIDATED = {("graph", "quantile"): "0.05", ("augmg", "max_match_cost"): '"blazepose=0.637"'}


def template_text(name: str) -> str:
    """The text of the template file ``name`` (one of :data:`FILES`)."""
    return resources.files(__package__).joinpath("pipeline", name).read_text(encoding="utf-8")


def set_param(text: str, section: str, key: str, value: str) -> str:
    """``text`` (a params.yaml) with ``section.key`` set to ``value`` (YAML as written), its comment kept."""
    lines = text.splitlines(keepends=True)
    inside = False
    for i, line in enumerate(lines):
        if re.match(rf"^{re.escape(section)}:\s*(#.*)?$", line):
            inside = True
            continue
        if inside and re.match(r"^\S", line):
            break
        m = re.match(rf"^(\s+{re.escape(key)}:\s*)(\"[^\"]*\"|[^#\n]*?)(\s+#.*)?(\n?)$", line) if inside else None
        if m:
            comment = m.group(3) or ""
            lines[i] = f"{m.group(1)}{value}{comment}{m.group(4)}"
            return "".join(lines)
    raise KeyError(f"{section}.{key} not in the template's params.yaml")


def _quote(value: str) -> str:
    return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"' if re.search(r"[\s:#*?\[\]{}&!|>'\"%@`,]", value) \
        else value


def write_pipeline(directory: str | os.PathLike, videos: str | os.PathLike, annotations: str | os.PathLike,
                   library: Sequence[str | os.PathLike], library_labels: str | os.PathLike,
                   pattern: str = "*.mp4", force: bool = False) -> list[Path]:
    """Write the template pipeline into ``directory`` (created) with ``params.yaml`` naming the folder of
    ``videos`` (files matching ``pattern``), the ``annotations`` file (its classes become
    ``library.classes``, its videos with transition marks ``augmg.videos``), the ``library`` clips (files
    or folders) and their ``library_labels`` CSV. Paths are written absolute. Refuses to replace an
    existing dvc.yaml or params.yaml unless ``force``. Returns the files written."""
    from ..fileio import write_text
    from ..formats.annotations import read_annotations

    out = Path(directory)
    videos, annotations, labels = Path(videos), Path(annotations), Path(library_labels)
    if not videos.is_dir():
        raise InputError(f"videos: {videos} is not a folder")
    if not labels.is_file():
        raise InputError(f"library_labels: {labels}: no such file")
    if not library:
        raise InputError("library: give the mocap clips (BVH files or folders)")
    for clip in map(Path, library):
        if not clip.exists():
            raise InputError(f"library: {clip}: no such file or folder")
    ann = read_annotations(annotations)
    marked = [Path(v.path).name for v in ann.videos if v.transitions]
    existing = [out / f for f in FILES if (out / f).exists()]
    if existing and not force:
        raise InputError(f"{existing[0]} exists (give force / --force to replace it)")
    params = template_text("params.yaml")
    values = {
        ("data", "videos"): _quote(str(videos.resolve())),
        ("data", "pattern"): f'"{pattern}"',
        ("data", "annotations"): _quote(str(annotations.resolve())),
        ("library", "clips"): _quote(" ".join(str(Path(c).resolve()) for c in library)),
        ("library", "labels"): _quote(str(labels.resolve())),
        ("library", "classes"): _quote(",".join(ann.classes)),
        ("augmg", "videos"): _quote(" ".join(marked)),
        **VALIDATED,
    }
    for (section, key), value in values.items():
        params = set_param(params, section, key, value)
    head = ("# Written by `vidstyle init`: the template pipeline (docs/template.md) for your files. Run\n"
            "# `dvc init --no-scm && dvc repro` here; outputs go to out/.\n")
    params = head + params.split("\n", 3)[3] if params.startswith("# Parameters of the template") else head + params
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, text in (("dvc.yaml", template_text("dvc.yaml")), ("params.yaml", params)):
        write_text(out / name, text)
        written.append(out / name)
    if not marked:
        import logging

        logging.getLogger(__name__).warning(
            "%s has no transition marks: method 2 (the pose_marks, augment and synthesize_augmg stages) has "
            "nothing to use; mark transitions with vidstyle annotate (T) first", annotations)
    return written
