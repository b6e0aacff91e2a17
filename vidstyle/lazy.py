"""Packages whose public names load their submodule on first use (PEP 562).

The CLI reads each stage's ``defaults`` module when it builds its options; that must not import
scikit-learn, SciPy, OpenCV or PyTorch into every command's start-up (``vidstyle --help`` in well under a
second, ``scripts/bench_startup.py``). A package's ``__init__`` therefore names its API and where each name
lives, and calls :func:`lazy_package`:

>>> _WHERE = {"augment": "augment", "match_poses": "match"}          # doctest: +SKIP
>>> __getattr__ = lazy_package(__name__, _WHERE)                    # doctest: +SKIP

``package.NAME`` then imports ``package.<_WHERE[NAME]>`` and returns its ``NAME``; ``package.sub`` imports
the submodule ``sub`` (found on disk, so no list drifts). A function that shares its submodule's name
(``augmg.augment``, ``style.learn``) stays the function whoever imports the submodule first: the import
system binds a freshly loaded submodule to its package's attribute, and the package's module class
refuses that one binding.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from importlib import import_module
from importlib.util import find_spec
from types import ModuleType


class LazyPackage(ModuleType):
    """Module class of a lazy package: a submodule never replaces an API name of the same name."""

    _lazy_where: Mapping[str, str] = {}

    def __setattr__(self, name: str, value) -> None:
        if name in self._lazy_where and isinstance(value, ModuleType):
            return
        super().__setattr__(name, value)


def lazy_package(name: str, where: Mapping[str, str]) -> Callable[[str], object]:
    """Make the package ``name`` lazy (see the module docstring); returns its module ``__getattr__``."""
    module = sys.modules[name]
    module.__class__ = LazyPackage
    vars(module)["_lazy_where"] = dict(where)

    def __getattr__(attr: str):
        if attr in where:
            value = getattr(import_module(f".{where[attr]}", name), attr)
        elif not attr.startswith("_") and find_spec(f"{name}.{attr}") is not None:  # a submodule
            value = import_module(f".{attr}", name)
        else:
            raise AttributeError(f"module {name!r} has no attribute {attr!r}")
        vars(module)[attr] = value
        return value

    return __getattr__
