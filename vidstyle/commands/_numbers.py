"""Numeric options checked where they enter: every ``int`` / ``float`` option of every command is finite
and inside its documented range, or the command stops before doing anything with one line naming the
flag and exit status 2 (``vidstyle: error: --views: must be an integer in 1..360, got 100000``).

Declare a bounded option with :func:`number` instead of ``typer.Option`` (same arguments, plus the
range); the range is appended to its help. :func:`check_all_numbers` (called once by :mod:`vidstyle.cli`)
gives every other ``int`` / ``float`` option the unbounded check: a float must be finite (``nan``,
``inf`` and ``1e400`` are refused), an integer must be an integer; an option named ``seed`` must be a
valid random seed (0..2**32-1).

The check is the option's ``parser`` (Typer's conversion hook): it raises
:class:`vidstyle.errors.ParameterError` (the CLI's one-line error) instead of a multi-line usage error.
"""

from __future__ import annotations

import math
from typing import Any

import typer

from ..errors import ParameterError

#: the largest seed numpy's legacy generators take
MAX_SEED = 2**32 - 1


def _fmt(x: float) -> str:
    return str(int(x)) if float(x).is_integer() and abs(x) < 1e15 else f"{x:g}"


class Number:
    """An integer (``integer=True``) or a finite float in ``lo``..``hi`` (either end may be None: no
    bound; ``lo_open`` / ``hi_open``: that end excluded); ``also``: values accepted outside the range
    (``-1`` = all cores)."""

    def __init__(self, integer: bool, lo: float | None = None, hi: float | None = None, *,
                 lo_open: bool = False, hi_open: bool = False, also: tuple = (), flag: str = "value") -> None:
        self.integer = integer
        self.flag = flag
        self.lo, self.hi, self.lo_open, self.hi_open, self.also = lo, hi, lo_open, hi_open, tuple(also)
        self.name = "integer" if integer else "float"

    def describe(self) -> str:
        """The range as the help shows it (``"1..360"``, ``"> 0"``, ``"0..1000, or -1"``); "" if none."""
        lo, hi = self.lo, self.hi
        if lo is not None and hi is not None:
            if not self.lo_open and not self.hi_open:
                text = f"{_fmt(lo)}..{_fmt(hi)}"
            else:
                text = f"{'>' if self.lo_open else '>='} {_fmt(lo)} and {'<' if self.hi_open else '<='} {_fmt(hi)}"
        elif lo is not None:
            text = f"{'>' if self.lo_open else '>='} {_fmt(lo)}"
        elif hi is not None:
            text = f"{'<' if self.hi_open else '<='} {_fmt(hi)}"
        else:
            return ""
        if self.also:
            text += ", or " + " or ".join(_fmt(a) for a in self.also)
        return text

    def __call__(self, value: Any) -> Any:
        flag = self.flag
        if value is None:  # an optional number not given
            return None
        if isinstance(value, bool):
            raise ParameterError(flag, f"expected a number, got {value!r}")
        if self.integer:
            if isinstance(value, int):
                x = value
            elif isinstance(value, float) and value.is_integer():
                x = int(value)
            else:
                text = str(value).strip()
                try:
                    x = int(text, 10)
                except ValueError:
                    raise ParameterError(flag, f"expected an integer, got {str(value)!r}") from None
        else:
            try:
                x = float(value)
            except (TypeError, ValueError):
                raise ParameterError(flag, f"expected a number, got {str(value)!r}") from None
            if not math.isfinite(x):
                raise ParameterError(flag, f"must be a finite number, got {str(value)!r}")
        if x in self.also:
            return x
        low = self.lo is not None and (x <= self.lo if self.lo_open else x < self.lo)
        high = self.hi is not None and (x >= self.hi if self.hi_open else x > self.hi)
        if low or high:
            kind = "an integer" if self.integer else "a number"
            raise ParameterError(flag, f"must be {kind} {'in ' if '..' in self.describe() else ''}"
                                       f"{self.describe()}, got {_fmt(x) if self.integer else value}")
        return x

    def __repr__(self) -> str:
        return f"Number({self.name}, {self.describe() or 'any'})"


def _flag(names, name: str) -> str:
    """The flag an error names: the first long one of ``names``, else the first, else ``--name``."""
    opts = [n for n in names or () if isinstance(n, str)]
    longs = [o for o in opts if o.startswith("--")]
    return longs[0] if longs else opts[0] if opts else "--" + name.replace("_", "-")


def number(default: Any, *names: str, help: str = "", integer: bool | None = None, lo: float | None = None,
           hi: float | None = None, lo_open: bool = False, hi_open: bool = False, also: tuple = (),
           **kwargs: Any) -> Any:
    """``typer.Option(default, *names, help=...)`` for a number in a range, the range appended to the help
    (``Range: 1..360.``). ``integer``: default, whether ``default`` is an int."""
    if integer is None:
        integer = isinstance(default, int) and not isinstance(default, bool)
    t = Number(integer, lo, hi, lo_open=lo_open, hi_open=hi_open, also=also, flag=_flag(names, "value"))
    text = t.describe()
    full = f"{help.rstrip()} Range: {text}." if text else help
    return typer.Option(default, *names, help=full, parser=t, metavar="INTEGER" if integer else "FLOAT", **kwargs)


def _numeric_kind(annotation: Any) -> bool | None:
    """True for an int annotation, False for a float one (``Optional`` of them too), None otherwise."""
    import typing

    args = typing.get_args(annotation)
    if args:
        kinds = {a for a in args if a is not type(None)}
        return _numeric_kind(next(iter(kinds))) if len(kinds) == 1 else None
    if annotation is bool:
        return None
    if annotation is int:
        return True
    if annotation is float:
        return False
    return None


def check_all_numbers(app: typer.Typer) -> None:
    """Give every ``int`` / ``float`` option or argument of every command of ``app`` (recursively) that
    has no :class:`Number` parser the unbounded check (finite; ``seed``: 0..2**32-1)."""
    import inspect
    import typing

    from typer.models import ArgumentInfo, OptionInfo

    for info in app.registered_commands:
        cb = info.callback
        if cb is None:
            continue
        try:
            hints = typing.get_type_hints(cb)
        except Exception:  # noqa: BLE001 - an annotation that does not resolve: leave that command as is
            continue
        for p in inspect.signature(cb).parameters.values():
            spec = p.default
            if not isinstance(spec, (OptionInfo, ArgumentInfo)) or spec.parser is not None:
                continue
            if getattr(spec, "count", False):
                continue
            integer = _numeric_kind(hints.get(p.name))
            if integer is None:
                continue
            flag = _flag(spec.param_decls, p.name) if isinstance(spec, OptionInfo) else p.name.upper()
            if p.name == "seed" and integer:
                spec.parser = Number(True, 0, MAX_SEED, flag=flag)
            else:
                spec.parser = Number(integer, flag=flag)
            spec.metavar = spec.metavar or ("INTEGER" if integer else "FLOAT")
    for group in app.registered_groups:
        if group.typer_instance is not None:
            check_all_numbers(group.typer_instance)


#: most parallel workers a command takes
MAX_JOBS = 1024


def jobs_option(default: int, *names: str, help: str) -> Any:
    """The ``--jobs`` / ``-j`` option: 1..1024 workers, or -1 for all cores.

    Convention: ``-1`` (all cores) is the default wherever a command's work splits into independent
    pieces (a pipeline runs one stage at a time, and one piece runs in-process anyway:
    :func:`vidstyle.parallel.parallel_map`); a command that defaults to anything else says why in its
    help (``build-graph``: its one process already runs a thread per core)."""
    return number(default, *(names or ("--jobs", "-j")), help=help, lo=1, hi=MAX_JOBS, also=(-1,))
