"""Exceptions that the CLI turns into a one-line message and a non-zero exit."""

from __future__ import annotations


class VidstyleError(Exception):
    """Base class of every error caused by bad input (file, shape, parameter), not by a bug.

    The message must name the offending file (or argument) and the problem, on one line.
    """

    exit_code = 2


class InputError(VidstyleError):
    """A file or argument that cannot be used (missing, unreadable, wrong shape, wrong schema)."""


class FormatError(InputError):
    """A file that is not a valid artifact of its kind. The message names the file and the field."""

    def __init__(self, path, field: str | None, problem: str) -> None:
        self.path = None if path is None else str(path)
        self.field = field
        self.problem = problem
        where = f"{self.path}: " if self.path else ""
        what = f"{field}: " if field else ""
        super().__init__(f"{where}{what}{problem}")

    def __reduce__(self):  # picklable (a worker process's error reaches the parent intact)
        return type(self), (self.path, self.field, self.problem)


class ParameterError(InputError):
    """A library parameter with a value it cannot take. The message names the parameter as the library
    calls it (``"window: must be >= 1"``); the CLI shows the flag that set it (``--window``)."""

    def __init__(self, param: str, problem: str) -> None:
        self.param = param
        self.problem = problem
        super().__init__(f"{param}: {problem}")

    def __reduce__(self):  # picklable, as FormatError
        return type(self), (self.param, self.problem)


class ResourceError(VidstyleError):
    """The machine ran out of a resource (memory) for this input at these settings: exit status 3.

    The CLI also turns a bare :class:`MemoryError` into this one-line error and exit status."""

    exit_code = 3
