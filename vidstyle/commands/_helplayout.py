"""--help that fits the terminal (80 columns and up) without cutting anything (issue 32, item 5).

Typer's Rich help lays each panel out as a table with one column per kind of name (long, short, off
form, short off form), a type column and a help column, and leaves Rich's default ``overflow="ellipsis"``
on every column. At 80 columns a long option name (``--max-frames-per-class``) then shares the width with
three mostly empty name columns, Rich shrinks them all, and the name is cut to ``--max-frames-per-…``;
a help word longer than its column (a path) is cut the same way.

Here each panel has one name column that never wraps and is as wide as the command's longest name
(``--out, -o`` on one line, an off form such as ``--no-mirror`` on the next, the same width in every
panel of the command so they line up), a type column, and a help column that takes the rest and folds a
word too long for it instead of cutting it. Group help keeps Typer's layout; only its descriptions fold
instead of being cut.

:func:`install` is called by :mod:`vidstyle.cli` just before help is formatted (Typer imports its Rich
module only then, so start-up stays light).
"""

from __future__ import annotations

from typing import Any

_INSTALLED = False


def _name_lines(param: Any) -> list[tuple[str, bool]]:
    """The names ``param`` is shown under, one line each, with whether the line is an off form: long and
    short names together, then any further long names, then the off forms (``--no-mirror``)."""
    from typer.core import TyperArgument

    if isinstance(param, TyperArgument):
        name = getattr(param, "display_name_raw", None) or (param.name or "").upper()
        if param.metavar is None and param.nargs != 1:
            name += "..."
        return [(name, False)]

    def lines(opts: list[str], off: bool) -> list[tuple[str, bool]]:
        longs = [o for o in opts if o.startswith("--")]
        shorts = [o for o in opts if not o.startswith("--")]
        if not opts:
            return []
        return [(", ".join([*longs[:1], *shorts]), off), *((o, off) for o in longs[1:])]

    return [*lines(list(param.opts), False), *lines(list(param.secondary_opts), True)]


def _shown(ctx: Any) -> list:
    """The visible parameters of the command being helped (every panel is laid out for all of them)."""
    return [p for p in ctx.command.get_params(ctx) if not getattr(p, "hidden", False)]


def _name_width(ctx: Any) -> int:
    """The widest name line of the visible parameters of the command being helped."""
    return max((len(line) for p in _shown(ctx) for line, _ in _name_lines(p)), default=0)


def _folding(renderable: Any) -> Any:
    """``renderable`` with every piece of text set to fold a word too long for its column (Rich's table
    columns default to cutting it with an ellipsis)."""
    from rich.columns import Columns
    from rich.text import Text

    if isinstance(renderable, Text):
        renderable.overflow = "fold"
    elif isinstance(renderable, Columns):
        for item in renderable.renderables:
            _folding(item)
    return renderable


def _print_options_panel(*, name: str, params: list, ctx: Any, markup_mode: Any, console: Any) -> None:
    from rich import box
    from rich.panel import Panel
    from rich.table import Table
    from rich.text import Text
    from typer import rich_utils as ru

    if not params:
        return
    any_required = any(p.required for p in _shown(ctx))  # the same columns in every panel
    table = Table(highlight=True, show_header=False, expand=True, box=getattr(box, ru.STYLE_OPTIONS_TABLE_BOX, None),
                  show_lines=ru.STYLE_OPTIONS_TABLE_SHOW_LINES, leading=ru.STYLE_OPTIONS_TABLE_LEADING,
                  border_style=ru.STYLE_OPTIONS_TABLE_BORDER_STYLE, row_styles=ru.STYLE_OPTIONS_TABLE_ROW_STYLES,
                  pad_edge=ru.STYLE_OPTIONS_TABLE_PAD_EDGE, padding=ru.STYLE_OPTIONS_TABLE_PADDING)
    if any_required:
        table.add_column(no_wrap=True, width=1)
    table.add_column(no_wrap=True, min_width=_name_width(ctx))
    table.add_column(overflow="fold")
    table.add_column(ratio=1, overflow="fold")
    for param in params:
        names = Text("\n").join([(ru.negative_highlighter if off else ru.highlighter)(Text(line))
                                 for line, off in _name_lines(param)])
        types = Text(style=ru.STYLE_TYPES, overflow="fold")
        shown = param.display_type_rich(ctx=ctx)
        if shown is not None:
            types.append(shown)
        range_str = getattr(param, "_get_number_range_help_str", lambda: None)()
        if range_str:
            types.append(ru.RANGE_STRING.format(range_str))
        help_ = _folding(ru._get_parameter_help(param=param, ctx=ctx, markup_mode=markup_mode))
        row = [names, ru.types_highlighter(types), help_]
        if any_required:
            row.insert(0, Text(ru.REQUIRED_SHORT_STRING, style=ru.STYLE_REQUIRED_SHORT) if param.required else "")
        table.add_row(*row)
    console.print(Panel(table, border_style=ru.STYLE_OPTIONS_PANEL_BORDER, title=name,
                        title_align=ru.ALIGN_OPTIONS_PANEL))


def install() -> None:
    """Use the layout above for every panel of options and arguments, and let command descriptions in
    group help fold rather than be cut. Idempotent."""
    global _INSTALLED
    if _INSTALLED:
        return
    from typer import rich_utils as ru

    make_command_help = ru._make_command_help

    def _make_command_help(**kwargs: Any) -> Any:
        return _folding(make_command_help(**kwargs))

    ru._print_options_panel = _print_options_panel
    ru._make_command_help = _make_command_help
    _INSTALLED = True
