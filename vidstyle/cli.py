"""The ``vidstyle`` command line.

Each stage lives in its own module under ``vidstyle/commands/`` and exposes ``register(app)``, which
adds its commands (or a command group) to the root Typer app. Modules are discovered, so adding a stage
touches one new file. Errors derived from :class:`vidstyle.errors.VidstyleError` become a one-line
message on stderr and a non-zero exit status.

Exit status: 0 success; 1 internal error (a bug: traceback on stderr); 2 bad input or usage (a file,
an argument); 3 out of memory (:class:`MemoryError` or :class:`vidstyle.errors.ResourceError`: the
input is too large at these settings); 130 interrupted.
"""

from __future__ import annotations

import importlib
import logging
import pkgutil
import sys

import typer

from . import __version__
from .errors import ResourceError, VidstyleError

MEMORY_EXIT = ResourceError.exit_code

app = typer.Typer(
    name="vidstyle",
    help="Learn a performer's action style from video and turn it into new 3D character motion.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"vidstyle {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    verbose: int = typer.Option(0, "--verbose", "-v", count=True, help="More logging (-vv for debug)."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="Only warnings and errors."),
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print version."),
) -> None:
    from .logutil import configure

    configure(-1 if quiet else verbose)


def _register_commands() -> None:
    from . import commands

    for mod in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        if mod.name.startswith("_"):
            continue
        module = importlib.import_module(f"{commands.__name__}.{mod.name}")
        module.register(app)


#: --help lists the commands in pipeline order, stages apart from the tools
_ORDER = ["features", "vocabulary", "train-recognizer", "recognize", "learn-style", "generate", "build-graph",
          "synthesize", "demo", "render", "evaluate", "report", "mocap"]
_TOOLS = {"demo", "render", "mocap", "evaluate", "report"}


def _arrange_help() -> None:
    def name(info) -> str:
        return info.name or (info.typer_instance.info.name if getattr(info, "typer_instance", None) else "") or ""

    def rank(info) -> int:
        return _ORDER.index(name(info)) if name(info) in _ORDER else len(_ORDER)

    for info in [*app.registered_commands, *app.registered_groups]:
        info.rich_help_panel = "Data, evaluation and tools" if name(info) in _TOOLS else "Pipeline stages, in order"
    app.registered_commands.sort(key=rank)
    app.registered_groups.sort(key=rank)


_register_commands()
_arrange_help()


def main(argv: list[str] | None = None) -> int:
    """Console-script entry point. Returns the exit status instead of raising SystemExit."""
    try:
        app(args=argv, standalone_mode=False)
    except VidstyleError as e:
        msg = " ".join(str(e).split())  # one line, always
        print(f"vidstyle: error: {msg}", file=sys.stderr)
        return e.exit_code
    except typer.Exit as e:
        return e.exit_code
    except typer.Abort:
        print("vidstyle: aborted", file=sys.stderr)
        return 130
    except KeyboardInterrupt:
        print("vidstyle: interrupted", file=sys.stderr)
        return 130
    except MemoryError:
        # the input is too large for this machine at these settings: the user's to fix, like bad input
        print("vidstyle: error: out of memory (try a smaller input, working size or fewer jobs)", file=sys.stderr)
        return MEMORY_EXIT
    except Exception as e:
        # usage errors (unknown option, missing argument): Typer raises click's ClickException, from
        # its vendored copy of click in recent versions, so match the interface rather than the class
        if callable(getattr(e, "show", None)) and isinstance(getattr(e, "exit_code", None), int):
            e.show()
            return e.exit_code
        logging.getLogger("vidstyle").exception("internal error")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
