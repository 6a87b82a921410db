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
import re
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


_FENCE = re.compile(r"<mo>([\[\]()])</mo>")
#: Variables of polynomials printed in descending powers (Laplace ``p``, eigenvalue ``lambda``).
_POLY_VARIABLES = ("p", "lambda")


def _ml(expr) -> str:
    return sp.mathml(expr, printer="presentation")


def _polynomial_ml(expr) -> str:
    """MathML of ``expr``; a sum that is a polynomial in ``p`` or ``lambda`` in descending powers."""
    names = {s.name: s for s in getattr(expr, "free_symbols", ())}
    var = next((names[n] for n in _POLY_VARIABLES if n in names), None)
    if var is None or not isinstance(expr, sp.Add):
        return _ml(expr)
    try:
        poly = sp.Poly(expr, var)
    except sp.PolynomialError:
        return _ml(expr)
    if poly.degree() < 1:
        return _ml(expr)
    parts: list[str] = []
    for (deg,), coeff in sorted(poly.terms(), key=lambda term: -term[0][0]):
        negative = coeff.could_extract_minus_sign()
        if negative:
            coeff = -coeff
        if parts or negative:
            parts.append("<mo>-</mo>" if negative else "<mo>+</mo>")
        power = _ml(var**deg) if deg else ""
        if coeff == 1 and deg:
            parts.append(power)
            continue
        c = _ml(coeff)
        if isinstance(coeff, sp.Add) and deg:
            c = f"<mrow><mo>(</mo>{c}<mo>)</mo></mrow>"
        parts.append(c + (f"<mo>&InvisibleTimes;</mo>{power}" if deg else ""))
    return "<mrow>" + "".join(parts) + "</mrow>"


def _mathml(expr) -> str:
    """Presentation MathML of a derivation step: equations side by side, rational functions with
    numerator and denominator in descending powers, brackets that stretch over matrices."""
    if isinstance(expr, sp.Equality):
        text = f"<mrow>{_mathml(expr.lhs)}<mo>=</mo>{_mathml(expr.rhs)}</mrow>"
    elif isinstance(expr, sp.Tuple):
        text = "<mrow>" + "<mo>,</mo><mspace width='1em'/>".join(_mathml(e) for e in expr) + "</mrow>"
    elif isinstance(expr, sp.Expr) and not isinstance(expr, sp.MatrixBase):
        num, den = sp.fraction(expr)
        if den != 1 and (isinstance(num, sp.Add) or isinstance(den, sp.Add)):
            text = f"<mfrac><mrow>{_polynomial_ml(num)}</mrow><mrow>{_polynomial_ml(den)}</mrow></mfrac>"
        else:
            text = _polynomial_ml(expr)
    else:
        text = _ml(expr)
    text = text.replace("<mo> </mo>", "")  # no gap inside subscripts such as G_(eta f)
    # Matrix brackets as a styled table (class "bmatrix"): they span every row in any browser,
    # with or without a MathML font that can stretch "[" and "]".
    text = text.replace("<mo>[</mo><mtable>", '<mtable class="bmatrix">').replace("</mtable><mo>]</mo>", "</mtable>")
    return _FENCE.sub(r'<mo fence="true" stretchy="true" symmetric="true">\1</mo>', text)


def derivation_html(d: "Derivation") -> str:
    """HTML table of the steps with MathML (SymPy's presentation printer).

    Parameters
    ----------
    d : Derivation
        From :func:`obsdesign.derive`.
    """
    rows = []
    for label, title, expr in d.steps:
        math = _mathml(expr)
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
