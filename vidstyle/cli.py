"""The ``vidstyle`` command line.

Each stage lives in its own module under ``vidstyle/commands/`` and exposes ``register(app)``, which
adds its commands (or a command group) to the root Typer app. Modules are discovered, so adding a stage
touches one new file. Errors derived from :class:`vidstyle.errors.VidstyleError` become a one-line
message on stderr and a non-zero exit status.

Exit status: 0 success; 1 internal error (a bug: traceback on stderr); 2 bad input or usage (a file,
an argument; also a file or directory the system refuses: an ``OSError`` naming it); 3 out of memory (:class:`MemoryError` or :class:`vidstyle.errors.ResourceError`: the
input is too large at these settings); 130 interrupted.

With ``VIDSTYLE_TIMINGS=DIR`` in the environment, every command also writes its own timing record into
DIR as it exits, whatever its exit status (:mod:`vidstyle.timing`; ``vidstyle timing`` makes the table).

Start-up stays light: this module and the command modules import no numerical package at module level
(NumPy, SciPy, scikit-learn, OpenCV, PyTorch, MediaPipe ...); each command imports what it runs, so
``vidstyle --help`` and a command that needs none of them do not pay for them
(``tests/test_startup_imports.py``, ``scripts/bench_startup.py``).
"""

from __future__ import annotations

import importlib
import logging
import os
import pkgutil
import sys
import time

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
          "synthesize", "fit-actions", "sample-action", "train-pose", "pose", "match-pose", "augment", "reconstruct", "annotate", "demo", "render", "evaluate",
          "report", "timing", "mocap", "init", "compile"]
_TOOLS = {"annotate", "demo", "render", "mocap", "evaluate", "report", "timing", "init", "compile"}


def _check_numbers() -> None:
    """Every int / float option finite and in its range, checked as it is parsed (:mod:`.commands._numbers`)."""
    from .commands._numbers import check_all_numbers

    check_all_numbers(app)


def _arrange_help() -> None:
    def name(info) -> str:
        return info.name or (info.typer_instance.info.name if getattr(info, "typer_instance", None) else "") or ""

    def rank(info) -> int:
        return _ORDER.index(name(info)) if name(info) in _ORDER else len(_ORDER)

    for info in [*app.registered_commands, *app.registered_groups]:
        info.rich_help_panel = "Data, evaluation and tools" if name(info) in _TOOLS else "Pipeline stages, in order"
    app.registered_commands.sort(key=rank)
    app.registered_groups.sort(key=rank)


def _literal_help(typer_app: typer.Typer) -> None:
    """Help texts are shown as written: Rich markup would swallow bracketed text such as the defaults
    ``[10; --small: 3]``, so every command's, group's and option's help is escaped (recursively, once per
    declaration: option declarations shared by several commands are escaped once)."""
    import inspect

    from rich.markup import escape
    from typer.models import ArgumentInfo, OptionInfo

    def literal(obj, attr: str, text: str | None) -> None:
        if text and not getattr(obj, "_vidstyle_literal", False):
            # a docstring's line breaks are not meant for the terminal: reflow each paragraph
            text = "\n\n".join(" ".join(par.split()) for par in text.split("\n\n") if par.strip())
            setattr(obj, attr, escape(text))
            obj._vidstyle_literal = True

    for info in typer_app.registered_commands:
        cb = info.callback
        if cb is None:
            continue
        literal(info, "help", info.help if info.help is not None else inspect.getdoc(cb))
        for p in inspect.signature(cb).parameters.values():
            if isinstance(p.default, (OptionInfo, ArgumentInfo)):
                literal(p.default, "help", p.default.help)
    for group in typer_app.registered_groups:
        sub = group.typer_instance
        if sub is None:
            continue
        if isinstance(sub.info.help, str):
            literal(sub.info, "help", sub.info.help)
        _literal_help(sub)


def _flags_take_no_value() -> None:
    """An on/off flag (``--small``, ``--help``) takes no value, so --help shows no type for it (Typer's
    rich help prints ``<bool>`` as if it took one)."""
    option = getattr(typer.core, "TyperOption", None)
    show = getattr(option, "display_type_rich", None)
    if show is None or getattr(show, "_vidstyle", False):
        return

    def display_type_rich(self, ctx):
        if getattr(self, "is_flag", False) and not getattr(self, "count", False):
            return None
        return show(self, ctx)

    display_type_rich._vidstyle = True
    option.display_type_rich = display_type_rich


def _help_fits_the_terminal() -> None:
    """--help fits an 80-column terminal without cutting an option name or a word
    (:mod:`.commands._helplayout`; the layout is installed as help is first formatted, which is when
    Typer imports Rich's table code)."""
    for cls in (typer.core.TyperCommand, typer.core.TyperGroup):
        original = cls.format_help
        if getattr(original, "_vidstyle", False):
            continue

        def format_help(self, ctx, formatter, _original=original):
            from .commands._helplayout import install

            install()
            return _original(self, ctx, formatter)

        format_help._vidstyle = True
        cls.format_help = format_help


_register_commands()
_arrange_help()
_check_numbers()
_literal_help(app)
_flags_take_no_value()
_help_fits_the_terminal()


#: library parameter -> the command parameter that sets it, where the names differ
_PARAM_ALIASES = {"k_range": "modes", "n_components": "components", "n_words": "words", "kind": "split",
                  "method": "smoothing", "smoothing_window": "window", "n_views": "views"}


def _as_flags(error: VidstyleError, argv: list[str]) -> str:
    """The message of ``error``, with a library parameter name (:class:`ParameterError`) shown as the flag
    of the running command that sets it (``window: ...`` -> ``--window: ...``)."""
    from .errors import ParameterError

    if not isinstance(error, ParameterError):
        return str(error)
    try:
        cmd = typer.main.get_command(app)
        for tok in argv:
            sub = getattr(cmd, "commands", None)
            if sub is not None and tok in sub:
                cmd = sub[tok]
        params = {p.name: p for p in getattr(cmd, "params", [])}
        p = params.get(error.param) or params.get(_PARAM_ALIASES.get(error.param, ""))
        flags = [o for o in getattr(p, "opts", []) if o.startswith("--")]
        if flags:
            return f"{flags[0]}: {error.problem}"
    except Exception:  # the plain message is still right
        pass
    return str(error)


def _command_path(argv: list[str]) -> str:
    """The subcommand words of ``argv`` (``"demo make-dataset"``; ``""`` for the bare ``vidstyle``)."""
    words: list[str] = []
    try:
        cmd = typer.main.get_command(app)
        for tok in argv:
            sub = getattr(cmd, "commands", None)
            if sub is None:
                break
            if tok.startswith("-"):  # a root or group flag (none of them takes a value)
                continue
            if tok not in sub:
                break
            words.append(tok)
            cmd = sub[tok]
    except Exception:
        return ""
    return " ".join(words)


def main(argv: list[str] | None = None) -> int:
    """Console-script entry point. Returns the exit status instead of raising SystemExit. With
    ``VIDSTYLE_TIMINGS`` set, records the run on the way out (:func:`vidstyle.timing.record_run`)."""
    entered = time.time()
    args = sys.argv[1:] if argv is None else list(argv)
    status = 1
    before = None
    if os.environ.get("VIDSTYLE_TIMINGS"):
        from .timing import inherited_usage

        before = inherited_usage()
    try:
        status = _main(argv)
    except SystemExit as e:  # not raised by the commands; counted all the same
        status = e.code if isinstance(e.code, int) else 0 if e.code is None else 1
        raise
    finally:
        directory = os.environ.get("VIDSTYLE_TIMINGS")
        if directory:
            from .timing import process_start_time, record_run

            # a shell that ran other commands before exec-ing this one (``a && vidstyle ...``): this process
            # starts when it was entered, and the children's CPU before that is theirs, not this one's
            started = entered if before is not None and before > 0 else (process_start_time() or entered)
            record_run(directory, _command_path(args), args, status, started, before or 0.0)
    return status


def _main(argv: list[str] | None) -> int:
    try:
        app(args=argv, standalone_mode=False)
    except VidstyleError as e:
        msg = " ".join(_as_flags(e, sys.argv[1:] if argv is None else argv).split())  # one line, always
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
    except OSError as e:
        if not getattr(e, "filename", None):  # not about a file the user named: a bug, shown in full below
            logging.getLogger("vidstyle").exception("internal error")
            return 1
        # a file or directory the system refused (missing parent, permission, not a directory, disk full)
        from .fileio import os_reason

        print(f"vidstyle: error: {os_reason(e)}", file=sys.stderr)
        return VidstyleError.exit_code
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
