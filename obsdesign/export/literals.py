r"""User text in generated code: one function per target language, nothing raw.

Generated code carries user text (a config ``name``) in two ways only:

* in a comment or docstring, through :func:`comment_text`, which keeps the character
  class ``[A-Za-z0-9 _.,+-]`` (safe inside any comment of C, Python, Octave,
  JavaScript and LaTeX: no quote, backslash, ``*``, ``/``, ``%``, newline or line
  separator survives) and caps the length;
* as a string literal, through :func:`python_string`, :func:`c_string`,
  :func:`octave_string` or :func:`js_string`, each of which escapes every character
  outside printable ASCII, so the literal is pure ASCII on one line and reads back
  as the exact text.

The LaTeX export carries no user text.

Examples
--------
>>> name = "x" + '"' * 3 + "; */" + chr(92) + chr(10) + chr(0x2028)
>>> comment_text(name)
'x____ _____'
>>> eval(python_string(name)) == name and python_string(name).isascii()
True
>>> print(c_string("*/ ??/"))
"*/ \?\?/"
>>> print(js_string("</script>"))
"\u003c/script\u003e"
>>> print(octave_string("it's" + chr(10)))
['it''s' char(10)]
"""

from __future__ import annotations

import re

__all__ = ["NAME_MAX", "comment_text", "python_string", "c_string", "octave_string", "js_string"]

#: Longest user text placed in a comment or docstring.
NAME_MAX = 64
_UNSAFE = re.compile(r"[^A-Za-z0-9 _.,+\-]")


def _text(text) -> str:
    if not isinstance(text, str):
        raise TypeError(f"name: expected a string, found {type(text).__name__}")
    return text


def comment_text(text: str, *, limit: int = NAME_MAX) -> str:
    r"""User text made safe for a comment or docstring of any generated language.

    Parameters
    ----------
    text : str
        User text (e.g. a config name).
    limit : int
        Longest result (characters).

    Returns
    -------
    str
        ``text`` with every character outside ``[A-Za-z0-9 _.,+-]`` replaced by ``_``,
        cut to ``limit`` characters.

    Examples
    --------
    >>> comment_text("a */ b" + chr(10) + "c" + chr(0x2028) + "d")
    'a __ b_c_d'
    """
    return _UNSAFE.sub("_", _text(text))[:limit]


def _printable(ch: str) -> bool:
    return " " <= ch <= "~"


def python_string(text: str) -> str:
    r"""A Python string literal of ``text``: ASCII only, one line, reads back exactly.

    Parameters
    ----------
    text : str
        User text.

    Examples
    --------
    >>> print(python_string("é'" + chr(0)))
    "\xe9'\x00"
    """
    return ascii(_text(text))


def c_string(text: str) -> str:
    r"""A C99 string literal of the UTF-8 bytes of ``text``.

    Printable ASCII other than ``"``, ``\\`` and ``?`` (trigraphs) is kept; every other
    byte becomes a three-digit octal escape, so no escape can swallow the next character.

    Parameters
    ----------
    text : str
        User text (lone surrogates are written as their ``surrogatepass`` bytes).

    Examples
    --------
    >>> print(c_string('a"' + chr(92) + chr(10)))
    "a\"\\\012"
    """
    out = []
    for byte in _text(text).encode("utf-8", "surrogatepass"):
        ch = chr(byte)
        if ch in '"\\?':
            out.append("\\" + ch)
        elif _printable(ch):
            out.append(ch)
        else:
            out.append(f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def js_string(text: str) -> str:
    r"""A JavaScript string literal of ``text`` (``\\uXXXX`` escapes, safe in an inline ``<script>``).

    Printable ASCII other than ``"``, ``'``, ``\\``, ``<``, ``>``, ``&`` and backtick is kept;
    every other UTF-16 code unit becomes ``\\uXXXX`` (this covers U+2028 and U+2029).

    Parameters
    ----------
    text : str
        User text.

    Examples
    --------
    >>> print(js_string("a" + chr(0x1F600)))
    "a\ud83d\ude00"
    """
    out = []
    units = _text(text).encode("utf-16-le", "surrogatepass")
    for i in range(0, len(units), 2):
        code = int.from_bytes(units[i:i + 2], "little")
        ch = chr(code)
        out.append(ch if _printable(ch) and ch not in "\"'\\<>&`" else f"\\u{code:04x}")
    return '"' + "".join(out) + '"'


def octave_string(text: str) -> str:
    r"""An Octave/MATLAB expression for ``text``: quoted runs of printable ASCII and ``char(N)``.

    Inside single quotes only ``'`` is special (doubled); every other character becomes
    ``char(N)`` with its code point (``N`` < 256 reads back exactly in Octave and MATLAB;
    larger code points are exact in MATLAB).

    Parameters
    ----------
    text : str
        User text.

    Examples
    --------
    >>> octave_string("")
    "''"
    >>> octave_string("a" + chr(9) + "b")
    "['a' char(9) 'b']"
    """
    parts, run = [], ""
    for ch in _text(text):
        if _printable(ch):
            run += "''" if ch == "'" else ch
        else:
            if run:
                parts.append(f"'{run}'")
                run = ""
            parts.append(f"char({ord(ch)})")
    if run or not parts:
        parts.append(f"'{run}'")
    return parts[0] if len(parts) == 1 else "[" + " ".join(parts) + "]"
