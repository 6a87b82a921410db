"""Plain-text and HTML rendering shared by the design result objects."""

from __future__ import annotations

import html

__all__ = ["Condition", "ResultDisplay", "fmt"]

from dataclasses import dataclass


def fmt(value: object) -> str:
    """Compact formatting of numbers (4 significant digits), booleans and text.

    >>> fmt(1234.5678), fmt(True), fmt(None), fmt(-2.4384e-3)
    ('1235', 'yes', '-', '-0.002438')
    """
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, complex):
        return f"{value.real:.4g}{value.imag:+.4g}j" if value.imag else f"{value.real:.4g}"
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


_TEX = {"\\": "\\textbackslash{}", "&": "\\&", "%": "\\%", "$": "\\$", "#": "\\#", "_": "\\_",
        "{": "\\{", "}": "\\}", "^": "\\^{}", "~": "\\~{}"}


def _tex(text: str) -> str:
    """Escape text for LaTeX (one pass, so replacements are not escaped again).

    >>> print(_tex("a_1 & 50% \\\\x"))
    a\\_1 \\& 50\\% \\textbackslash{}x
    """
    return "".join(_TEX.get(ch, ch) for ch in text)


@dataclass(frozen=True)
class Condition:
    """One verdict of a check: its name, whether it holds, and the numbers behind it."""

    name: str
    holds: bool
    detail: str

    def to_dict(self) -> dict:
        return {"name": self.name, "holds": bool(self.holds), "detail": self.detail}


class ResultDisplay:
    """Mixin: ``__str__`` and ``_repr_html_`` from ``_title`` and ``_rows()``.

    Subclasses return ``(label, value)`` pairs from ``_rows`` and may return
    conditions from ``_conditions`` for a verdict table.
    """

    _title = "result"

    def _rows(self) -> list[tuple[str, object]]:
        return []

    def _conditions(self) -> tuple[Condition, ...]:
        return ()

    def __str__(self) -> str:
        rows = [(label, fmt(value)) for label, value in self._rows()]
        width = max((len(label) for label, _ in rows), default=0)
        lines = [self._title, "=" * len(self._title)]
        lines += [f"{label.ljust(width)}  {value}" for label, value in rows]
        conds = self._conditions()
        if conds:
            w = max(len(c.name) for c in conds)
            lines += ["", f"{'condition'.ljust(w)}  verdict  detail"]
            lines += [f"{c.name.ljust(w)}  {'PASS' if c.holds else 'FAIL':7}  {c.detail}" for c in conds]
        return "\n".join(lines)

    def _repr_latex_(self) -> str:
        """A LaTeX tabular of the rows and verdicts (for notebooks and papers)."""
        rows = [(label, fmt(value)) for label, value in self._rows()]
        rows += [(c.name, "PASS" if c.holds else "FAIL") for c in self._conditions()]
        body = " \\\\\n".join(f"{_tex(a)} & {_tex(b)}" for a, b in rows)
        return f"\\begin{{tabular}}{{ll}}\n\\multicolumn{{2}}{{l}}{{{_tex(self._title)}}} \\\\ \\hline\n{body}\n\\end{{tabular}}"

    def _repr_html_(self) -> str:
        esc = html.escape
        out = [f"<table class='obsdesign-result'><caption>{esc(self._title)}</caption>"]
        out += [f"<tr><th>{esc(label)}</th><td>{esc(fmt(value))}</td></tr>" for label, value in self._rows()]
        out.append("</table>")
        conds = self._conditions()
        if conds:
            out.append("<table class='obsdesign-verdicts'><tr><th>condition</th><th>verdict</th><th>detail</th></tr>")
            for c in conds:
                color = "#1a7f37" if c.holds else "#cf222e"
                out.append(
                    f"<tr><td>{esc(c.name)}</td><td style='color:{color}'>{'PASS' if c.holds else 'FAIL'}</td>"
                    f"<td>{esc(c.detail)}</td></tr>"
                )
            out.append("</table>")
        return "".join(out)
