"""The package's version: the one place it is written.

``pyproject.toml`` reads it (``[tool.setuptools.dynamic] version = {attr = ...}``),
``obsdesign.__version__`` and ``obsdesign --version`` import it, and the installed
metadata (``importlib.metadata.version("obsdesign")``) is built from it; a test keeps
them equal.

Examples
--------
>>> from obsdesign._version import __version__
>>> __version__.count(".")
2
"""

__all__ = ["__version__"]

__version__ = "0.1.0"
