"""Render a :class:`~obsdesign.symbolic.derivation.Derivation` as text, LaTeX, JSON or HTML.

All renderers walk the same ordered ``Derivation.steps``; the expressions are
printed by SymPy's own printers (``sstr``, ``latex``, ``mathml``).

Examples
--------
>>> from obsdesign.symbolic import derive
>>> from obsdesign.symbolic.printing import derivation_json
>>> doc = derivation_json(derive("static"))
>>> doc["gain_rule"]["L1"]
'2*sqrt(kappa)*rho/sqrt(m) - sigma/m'
"""

from __future__ import annotations

import html
from typing import TYPE_CHECKING, Any

import sympy as sp

if TYPE_CHECKING:  # annotations only: derivation.py imports this module for its displays
    from .derivation import Derivation

__all__ = ["derivation_text", "derivation_latex", "derivation_json", "derivation_html"]


def _label(label: str | None) -> str:
    return f"({label})" if label else ""


def derivation_text(d: "Derivation") -> str:
    """Plain-text derivation, one numbered step per block.

    Parameters
    ----------
    d : Derivation
        From :func:`obsdesign.derive`.
    """
    out = [f"Reduced-order friction observer, variant '{d.variant}'", ""]
    for i, (label, title, expr) in enumerate(d.steps, 1):
        out.append(f"[{i}] {title} {_label(label)}".rstrip())
        out.append("    " + sp.pretty(expr, use_unicode=False, wrap_line=False).replace("\n", "\n    "))
        out.append("")
    return "\n".join(out)


def derivation_latex(d: "Derivation", *, standalone: bool = True) -> str:
    """LaTeX of the derivation; a complete document when ``standalone``.

    Parameters
    ----------
    d : Derivation
        From :func:`obsdesign.derive`.
    standalone : bool
        A complete document (else the body only).
    """
    body = []
    for label, title, expr in d.steps:
        tag = f" \\quad \\text{{{label}}}" if label else ""
        body.append(f"\\paragraph{{{title}}}\n\\[\n{sp.latex(expr)}{tag}\n\\]")
    text = "\n\n".join(body)
    if not standalone:
        return text
    return (
        "\\documentclass{article}\n\\usepackage{amsmath}\n\\begin{document}\n"
        f"\\section*{{Reduced-order friction observer, variant \\texttt{{{d.variant}}}}}\n\n"
        f"{text}\n\n\\end{{document}}\n"
    )


def derivation_json(d: "Derivation") -> dict[str, Any]:
    """JSON-ready dictionary: the steps and the key results as strings.

    Parameters
    ----------
    d : Derivation
        From :func:`obsdesign.derive`.
    """
    L1, L2 = d.symbols["L1"], d.symbols["L2"]
    return {
        "variant": d.variant,
        "observable": d.observable,
        "a0": sp.sstr(d.a0),
        "a1": sp.sstr(d.a1),
        "eigenvalues": [sp.sstr(e) for e in d.eigenvalues],
        "gain_rule": {"L1": sp.sstr(d.gain_rule[L1]), "L2": sp.sstr(d.gain_rule[L2])},
        "designed_eigenvalues": [sp.sstr(e) for e in d.designed_eigenvalues],
        "dominant_pole": sp.sstr(d.dominant_pole),
        "stability_conditions": [sp.sstr(c) for c in d.stability_conditions],
        "noise_friction_feedthrough": sp.sstr(d.noise.friction_feedthrough),
        "steps": [
            {"label": label, "title": title, "text": sp.sstr(expr), "latex": sp.latex(expr)}
            for label, title, expr in d.steps
        ],
    }


def derivation_html(d: "Derivation") -> str:
    """HTML table of the steps with MathML (SymPy's presentation printer).

    Parameters
    ----------
    d : Derivation
        From :func:`obsdesign.derive`.
    """
    rows = []
    for label, title, expr in d.steps:
        math = sp.mathml(expr, printer="presentation")
        rows.append(
            f"<tr><td>{html.escape(label or '')}</td><td>{html.escape(title)}</td>"
            f'<td><math xmlns="http://www.w3.org/1998/Math/MathML">{math}</math></td></tr>'
        )
    return (
        f"<table class='obsdesign-derivation'><caption>Observer derivation, variant "
        f"{html.escape(d.variant)}</caption><tr><th>eq.</th><th>step</th><th>expression</th></tr>"
        + "".join(rows)
        + "</table>"
    )
