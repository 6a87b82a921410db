"""Lazy public names for package ``__init__`` modules (PEP 562 module ``__getattr__``).

A package lists its public names and the module each comes from; nothing is imported until a
name is first used, so the command line can build its parser without loading SymPy,
python-control, SciPy, numba or matplotlib.

Examples
--------
>>> getattr_, dir_ = lazy_names("json", {"dumps": "json"})
>>> getattr_("dumps")({"a": 1})
'{"a": 1}'
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import Any, Callable, Mapping

__all__ = ["lazy_names", "keep_functions"]


def lazy_names(package: str, table: Mapping[str, str]) -> tuple[Callable[[str], Any], Callable[[], list]]:
    """The module ``__getattr__`` and ``__dir__`` of a package whose names load on first use.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    table : mapping of str to str
        Public name -> module it comes from (relative to ``package`` when it starts with ``.``).

    Returns
    -------
    (callable, callable)
        ``__getattr__`` (imports the module, caches the value in the package) and ``__dir__``.
    """

    def __getattr__(name: str):
        if name in table:
            module = importlib.import_module(table[name], package)
            value = getattr(module, name)
            setattr(sys.modules[package], name, value)
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__():
        return sorted(set(vars(sys.modules[package])) | set(table))

    return __getattr__, __dir__


def keep_functions(package: str, names: tuple[str, ...]) -> None:
    """Keep the public function ``name`` of a package when its submodule of the same name is imported.

    Importing ``package.name`` sets the attribute ``name`` of the package to the submodule; an
    eager ``from .name import name`` used to overwrite it with the function, and this keeps
    that behaviour for lazily loaded names.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    names : tuple of str
        Names that are both a submodule and a function of that submodule.
    """
    module = sys.modules[package]

    class _Package(types.ModuleType):
        def __setattr__(self, name, value):
            if name in names and isinstance(value, types.ModuleType) and hasattr(value, name):
                value = getattr(value, name)
            super().__setattr__(name, value)

    module.__class__ = _Package
