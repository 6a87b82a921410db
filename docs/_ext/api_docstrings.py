"""How the API reference reads the package's docstrings (autodoc hooks).

* The docstrings are plain numpydoc read as text too (``help()``, the REPL), where ``|S|`` is a
  magnitude; in reStructuredText ``|S|`` is a substitution, so bars outside literals, roles and
  tables are escaped before docutils sees them.
* A module documents what it defines and names in its ``__all__`` (the package ``__init__``
  modules re-export names lazily, documented where they are defined).
"""

from __future__ import annotations

import re
import sys

_CODE = re.compile(r"(``.+?``|:[\w:.-]+:`[^`]*`|`[^`]*`_?)")
_TABLE = re.compile(r"^\s*(\+[-=+]*\+\s*$|\| )")  # a grid-table border or a row / line block


def escape_bars(line: str) -> str:
    """``line`` with every ``|`` outside inline literals and roles escaped (table rows kept).

    >>> escape_bars("the peak of |S(j omega)| and ``|x|`` and :math:`|T|`")
    'the peak of \\\\|S(j omega)\\\\| and ``|x|`` and :math:`|T|`'
    >>> escape_bars("| a line block |")
    '| a line block |'
    """
    if "|" not in line or _TABLE.match(line):
        return line
    parts = _CODE.split(line)
    return "".join(p if i % 2 else p.replace("|", r"\|") for i, p in enumerate(parts))


def _process(app, what, name, obj, options, lines):
    lines[:] = [escape_bars(line) for line in lines]


def _skip(app, what, name, obj, skip, options):
    module = sys.modules.get(getattr(obj, "__module__", None) or "")
    names = getattr(module, "__all__", None)
    if what == "module" and names is not None and name not in names and not skip:
        return True
    return None


def setup(app):
    app.connect("autodoc-process-docstring", _process)
    app.connect("autodoc-skip-member", _skip)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
