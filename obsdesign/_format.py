"""One home for number formatting: text tables, reports, CSV cells, code literals and JSON.

Examples
--------
>>> short(1234.5678), short(True), short(None), short(-2.4384e-3)
('1235', 'yes', '-', '-0.002438')
>>> with_unit(0.0024902, "m/V"), with_unit(None, "s")
('0.00249 m/V', '-')
>>> report(1e-6), report(0.0314908), report(-120000.0)
('1.0000e-06', '0.0314908', '-1.2000e+05')
>>> csv_field(0.1), csv_field(True), csv_field(None)
('0.1', 'true', '')
>>> jsonable({"a": float("inf"), "b": [1.5]})
{'a': None, 'b': [1.5]}
"""

from __future__ import annotations

import math

__all__ = ["short", "with_unit", "report", "csv_field", "code_literal", "jsonable", "toml_value"]


def short(value: object) -> str:
    """Compact text of a number (4 significant digits), a boolean (yes/no), None (-) or anything else."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, complex):
        return f"{value.real:.4g}{value.imag:+.4g}j" if value.imag else f"{value.real:.4g}"
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


def with_unit(value: object, unit: str = "", digits: int = 3) -> str:
    """A number with ``digits`` significant digits and its unit, e.g. ``'0.00249 m/V'``."""
    if value is None:
        return "-"
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return str(value)
    text = f"{value:.{digits}g}"
    return f"{text} {unit}" if unit else text


def report(value: object) -> str:
    """Report tables: 6 significant digits in [1e-3, 1e5), else 4-digit scientific notation."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if value == 0.0 or (1e-3 <= abs(value) < 1e5):
            return f"{value:.6g}"
        return f"{value:.4e}" if math.isfinite(value) else str(value)
    return str(value)


def csv_field(value: object) -> str:
    """A CSV cell that reads back exactly: floats by ``repr``, booleans as true/false, None empty."""
    if value is None:
        return ""
    if isinstance(value, bool) or _is_numpy_bool(value):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


def _is_numpy_bool(value: object) -> bool:
    """A NumPy boolean scalar, recognised without importing NumPy (the CLI starts without it)."""
    kind = type(value)
    return kind.__module__ == "numpy" and kind.__name__ in ("bool_", "bool")


def code_literal(value: float) -> str:
    """A float literal that every target language reads back exactly (``repr``)."""
    return repr(float(value))


def jsonable(value):
    """Strict JSON values: non-finite floats become null, NumPy scalars plain numbers."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def toml_value(value) -> str:
    """A TOML literal: booleans, integers, lists, floats (``repr``) and strings as basic strings
    with every control character escaped, so that ``tomllib`` reads back the same value.

    Parameters
    ----------
    value : bool, int, float, str or list
        The value.

    Examples
    --------
    >>> import tomllib
    >>> toml_value(True), toml_value([1, 2.5])
    ('true', '[1, 2.5]')
    >>> text = 'a"b' + chr(10) + chr(0)
    >>> tomllib.loads("x = " + toml_value(text))["x"] == text
    True
    """
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, int) and not isinstance(value, bool):
        return str(value)
    if isinstance(value, str):
        out = []
        for ch in value:
            if ch == "\\" or ch == '"':
                out.append("\\" + ch)
            elif ord(ch) < 0x20 or ord(ch) == 0x7F:
                out.append(f"\\u{ord(ch):04x}")
            else:
                out.append(ch)
        return '"' + "".join(out) + '"'
    return repr(float(value))
