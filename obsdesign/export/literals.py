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

The LaTeX export carries no user text. A user-chosen identifier (the ``experiment`` C array's
``--name``) goes through :func:`check_identifier`: a plain identifier that is no keyword of any export
language (:data:`KEYWORDS`, the one list of them) and not reserved in C.

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

__all__ = ["NAME_MAX", "comment_text", "python_string", "c_string", "octave_string", "js_string", "KEYWORDS",
           "ST_LANGUAGE", "check_identifier"]

#: Longest user text placed in a comment or docstring.
NAME_MAX = 64
_UNSAFE = re.compile(r"[^A-Za-z0-9 _.,+\-]")

#: The reserved words of every language code is exported in (generated identifiers never use one).
KEYWORDS = {
    "C": frozenset(  # C23 keywords, their C11 spellings and the macros of <stdbool.h>, <stddef.h>
        "alignas alignof auto bool break case char const constexpr continue default do double else enum extern "
        "false float for goto if inline int long nullptr register restrict return short signed sizeof static "
        "static_assert struct switch thread_local true typedef typeof typeof_unqual union unsigned void volatile "
        "while _Alignas _Alignof _Atomic _BitInt _Bool _Complex _Decimal128 _Decimal32 _Decimal64 _Generic "
        "_Imaginary _Noreturn _Static_assert _Thread_local NULL".split()),
    "Python": frozenset(  # keyword.kwlist of Python 3.11 to 3.13
        "False None True and as assert async await break class continue def del elif else except finally for "
        "from global if import in is lambda nonlocal not or pass raise return try while with yield".split()),
    "Octave/MATLAB": frozenset(  # iskeyword() of GNU Octave 8 and MATLAB R2024
        "__FILE__ __LINE__ arguments break case catch classdef continue do else elseif end end_try_catch "
        "end_unwind_protect endclassdef endenumeration endevents endfor endfunction endif endmethods endparfor "
        "endproperties endspmd endswitch endwhile enumeration events for function global if methods otherwise "
        "parfor persistent properties return spmd switch try until unwind_protect unwind_protect_cleanup "
        "while".split()),
    "JavaScript": frozenset(  # ECMAScript 2024 reserved words, strict-mode and module reservations
        "arguments await break case catch class const continue debugger default delete do else enum eval export "
        "extends false finally for function if implements import in instanceof interface let new null package "
        "private protected public return static super switch this throw true try typeof var void while with "
        "yield".split()),
    # IEC 61131-3 (3rd edition) keywords, elementary type names and standard function names, with the common
    # extensions of CODESYS/TwinCAT (POINTER, REFERENCE, ...); ST is case-insensitive: compared in upper case
    "IEC 61131-3 ST": frozenset("""
ABSTRACT ACTION AND AND_THEN ANY ANY_BIT ANY_CHAR ANY_CHARS ANY_DATE ANY_DERIVED ANY_DURATION ANY_ELEMENTARY ANY_INT
ANY_MAGNITUDE ANY_NUM ANY_REAL ANY_SIGNED ANY_STRING ANY_UNSIGNED ARRAY AT BOOL BY BYTE CASE CHAR CLASS CONFIGURATION
CONSTANT CONTINUE DATE DATE_AND_TIME DINT DO DT DWORD ELSE ELSIF EN ENO END_ACTION END_CASE END_CLASS
END_CONFIGURATION END_FOR END_FUNCTION END_FUNCTION_BLOCK END_IF END_INTERFACE END_METHOD END_NAMESPACE END_PROGRAM
END_PROPERTY END_REPEAT END_RESOURCE END_STEP END_STRUCT END_TRANSITION END_TYPE END_UNION END_VAR END_WHILE EXIT
EXTENDS F_EDGE FALSE FINAL FOR FROM FUNCTION FUNCTION_BLOCK IF IMPLEMENTS INITIAL_STEP INT INTERFACE INTERNAL
INTERVAL JMP LDATE LDATE_AND_TIME LDT LINT LREAL LTIME LTIME_OF_DAY LTOD LWORD METHOD MOD NAMESPACE NON_RETAIN NOT
NULL OF ON OR OR_ELSE OVERLAP OVERRIDE PERSISTENT POINTER PRIORITY PRIVATE PROGRAM PROPERTY PROTECTED PUBLIC
READ_ONLY READ_WRITE REAL REF REFERENCE REF_TO REPEAT RESOURCE RETAIN RETURN R_EDGE SINGLE SINT STEP STRING STRUCT
SUPER TASK THEN THIS TIME TIME_OF_DAY TO TOD TRANSITION TRUE TYPE UDINT UINT ULINT UNION UNTIL USING USINT VAR
VAR_ACCESS VAR_CONFIG VAR_EXTERNAL VAR_GLOBAL VAR_INPUT VAR_INST VAR_IN_OUT VAR_OUTPUT VAR_STAT VAR_TEMP WCHAR
WHILE WITH WORD WSTRING XOR
ABS SQRT LN LOG EXP EXPT SIN COS TAN ASIN ACOS ATAN ATAN2 ADD SUB MUL DIV MOVE SHL SHR ROL ROR SEL MAX MIN LIMIT MUX
GT GE EQ LE LT NE LEN LEFT RIGHT MID CONCAT INSERT DELETE REPLACE FIND TRUNC ROUND SIZEOF ADR
""".split()),
}
#: The case-insensitive language of :data:`KEYWORDS` (its words are written in upper case).
ST_LANGUAGE = "IEC 61131-3 ST"
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,62}")


def check_identifier(name: str, text) -> str:
    """``text`` if it can name a variable in every export language, else ``ValueError`` naming ``name``.

    Parameters
    ----------
    name : str
        The parameter or flag the text came from (for the message).
    text : str
        The identifier.

    A letter or ``_``, then letters, digits or ``_``, at most 63 characters (C's portable limit); no
    keyword of C, Python, Octave/MATLAB, JavaScript or IEC 61131-3 ST (:data:`KEYWORDS`; ST in any case);
    not reserved in C (``__`` or
    ``_`` and a capital first).

    Examples
    --------
    >>> check_identifier("name", "axis_x")
    'axis_x'
    >>> check_identifier("name", "int")
    Traceback (most recent call last):
    ...
    ValueError: name: expected an identifier that is no keyword of an export language, found 'int' (a keyword of C, IEC 61131-3 ST)
    >>> check_identifier("name", "end")
    Traceback (most recent call last):
    ...
    ValueError: name: expected an identifier that is no keyword of an export language, found 'end' (a keyword of Octave/MATLAB)
    >>> check_identifier("name", "Elsif")
    Traceback (most recent call last):
    ...
    ValueError: name: expected an identifier that is no keyword of an export language, found 'Elsif' (a keyword of IEC 61131-3 ST)
    """
    if not isinstance(text, str) or not _IDENTIFIER.fullmatch(text):
        raise ValueError(f"{name}: expected a C identifier (a letter or _, then letters, digits or _, at most 63), "
                         f"found {text!r}")
    languages = [lang for lang, words in KEYWORDS.items() if (text.upper() if lang == ST_LANGUAGE else text) in words]
    if text.startswith("__") or re.match(r"_[A-Z]", text):
        languages.append("C (reserved: __ or _ and a capital)")
    if languages:
        raise ValueError(f"{name}: expected an identifier that is no keyword of an export language, found {text!r} "
                         f"(a keyword of {', '.join(languages)})")
    return text


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
