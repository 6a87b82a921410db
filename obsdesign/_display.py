"""One home for displaying results: plain text, HTML (notebooks, reports) and LaTeX.

Every result object of the package (stability report, PID, noise analysis,
simulation, ...) mixes in :class:`ResultDisplay` and provides ``_title`` and
``_rows()``; numbers are formatted by :func:`obsdesign._format.short`. The rows'
labels carry their unit in brackets, written for a linear axis driven in V
(``'kappa [N/m]'``); :meth:`ResultDisplay.text` writes them for the config's axis
(:meth:`obsdesign.axis.AxisSpec.label`).
"""

from __future__ import annotations

import html
from dataclasses import dataclass

from ._format import short as fmt

__all__ = ["Condition", "ResultDisplay", "tex_escape"]


_TEX = {"\\": "\\textbackslash{}", "&": "\\&", "%": "\\%", "$": "\\$", "#": "\\#", "_": "\\_",
        "{": "\\{", "}": "\\}", "^": "\\^{}", "~": "\\~{}"}


def tex_escape(text: str) -> str:
    """Escape text for LaTeX (one pass, so replacements are not escaped again).

    >>> print(tex_escape("a_1 & 50% \\\\x"))
    a\\_1 \\& 50\\% \\textbackslash{}x
    """
    return "".join(_TEX.get(ch, ch) for ch in text)


@dataclass(frozen=True)
class Condition:
    """One verdict of a check: its name, whether it holds, and the numbers behind it.

    Attributes
    ----------
    name : str
        What is checked.
    holds : bool
        Whether it holds.
    detail : str
        The numbers behind the verdict.
    """

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
        return self.text()

    def text(self, units=None) -> str:
        """The plain-text table, its units those of ``units`` (an :class:`~obsdesign.axis.AxisSpec`; None: linear, V).

        Parameters
        ----------
        units : AxisSpec, optional
            The axis the numbers are about (``Config.units``).
        """
        label_of = units.label if units is not None else str
        rows = [(label_of(label), fmt(value)) for label, value in self._rows()]
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
        body = " \\\\\n".join(f"{tex_escape(a)} & {tex_escape(b)}" for a, b in rows)
        return f"\\begin{{tabular}}{{ll}}\n\\multicolumn{{2}}{{l}}{{{tex_escape(self._title)}}} \\\\ \\hline\n{body}\n\\end{{tabular}}"

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
