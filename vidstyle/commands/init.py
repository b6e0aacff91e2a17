"""``vidstyle init``: write the template pipeline for your own videos into a directory."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Annotated

import typer

from ._flags import as_flags

log = logging.getLogger(__name__)


def register(app: typer.Typer) -> None:
    app.command("init")(init)


def init(
    directory: Annotated[Path, typer.Argument(help="Directory to write dvc.yaml and params.yaml into (created).")],
    videos: Annotated[Path, typer.Option("--videos", help="Folder of your videos.")],
    annotations: Annotated[Path, typer.Option(
        "--annotations", "-a", help="Annotations file of the videos (vidstyle annotate).")],
    library: Annotated[list[Path], typer.Option(
        "--library", "-l", help="Mocap clips: BVH files or folders (repeatable).")],
    library_labels: Annotated[Path, typer.Option(
        "--library-labels", help="Labels of the clips: CSV file,label[,start,end] or CMU clips.csv.")],
    pattern: Annotated[str, typer.Option("--pattern", help="Which files of --videos (a shell pattern).")] = "*.mp4",
    force: Annotated[bool, typer.Option("--force", help="Replace an existing dvc.yaml / params.yaml.")] = False,
) -> None:
    """Write the template pipeline (method 1 and method 2 end to end, docs/template.md) into DIRECTORY,
    its params.yaml naming your files; the classes and the videos with transition marks are read from
    the annotations file. Then run `dvc init --no-scm && dvc repro` there."""
    from ..templates import write_pipeline

    with as_flags(videos="--videos", annotations="--annotations", library_labels="--library-labels",
                  library="--library"):
        written = write_pipeline(directory, videos, annotations, library, library_labels, pattern=pattern,
                                 force=force)
    for path in written:
        typer.echo(str(path))
    log.info("next: cd %s && dvc init --no-scm && dvc repro", directory)
