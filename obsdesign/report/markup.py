"""The report page's markup rules: one number format, the content policy with its check, and the
allowlist a kept derivation table must pass before it is put on a page.

Shared by the entry point :mod:`obsdesign.report.html` and the page builder
:mod:`obsdesign.report.page` (one place for both, no import cycle).
"""

from __future__ import annotations

import base64
import hashlib
import math
import re
from html.parser import HTMLParser

from .._format import with_unit

__all__ = ["ReportContentError", "is_derivation_markup"]

#: What :func:`obsdesign.symbolic.printing.derivation_html` writes: an HTML table of MathML presentation
#: elements. A derivation read back from the result memo (a file on disk) must hold nothing else.
_DERIVATION_TAGS = frozenset({
    "table", "caption", "tr", "th", "td", "math", "mi", "mn", "mo", "ms", "mtext", "mspace", "mrow", "mfrac",
    "msqrt", "mroot", "msub", "msup", "msubsup", "munder", "mover", "munderover", "mtable", "mtr", "mtd",
    "mfenced", "mstyle", "mpadded", "mphantom"})
#: Its attributes: presentation keywords and lengths only (no URL, no script, no style).
_DERIVATION_ATTRS = frozenset({"class", "fence", "stretchy", "symmetric", "width", "mathvariant", "separators",
                               "open", "close", "lspace", "rspace", "columnalign", "accent", "linethickness"})
_MATHML_NS = "http://www.w3.org/1998/Math/MathML"
_PLAIN_VALUE = re.compile(r"[A-Za-z0-9 .,%#+-]*")


class _DerivationCheck(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.ok = True

    def handle_starttag(self, tag, attrs):
        if tag not in _DERIVATION_TAGS:
            self.ok = False
        for name, value in attrs:
            if name == "xmlns":
                self.ok &= tag == "math" and value == _MATHML_NS
            else:
                self.ok &= name in _DERIVATION_ATTRS and _PLAIN_VALUE.fullmatch(value or "") is not None

    handle_startendtag = handle_starttag

    def handle_endtag(self, tag):
        self.ok &= tag in _DERIVATION_TAGS

    def handle_decl(self, decl):
        self.ok = False

    handle_pi = unknown_decl = handle_decl


def is_derivation_markup(text) -> bool:
    """Whether ``text`` is a derivation table as the report writes it: allowed elements and attributes only.

    The report embeds its derivation as markup; read back from the result memo it is a file on disk,
    so it is embedded only when every element is one of the table and MathML presentation elements
    and every attribute a presentation keyword with a plain value. Otherwise the derivation is computed
    again (and the entry rewritten).

    Parameters
    ----------
    text : str
        The markup (anything else is not a derivation table).

    Examples
    --------
    >>> is_derivation_markup("<table class='obsdesign-derivation'><tr><td><math xmlns="
    ...                      "'http://www.w3.org/1998/Math/MathML'><mi>x</mi></math></td></tr></table>")
    True
    >>> is_derivation_markup("<table><tr><td><img src=x onerror=alert(1)></td></tr></table>")
    False
    >>> is_derivation_markup("<table><tr><td><mi mathvariant='x\\' onclick='y'>a</mi></td></tr></table>")
    False
    """
    if not isinstance(text, str):
        return False
    check = _DerivationCheck()
    check.feed(text)
    check.close()
    return check.ok


def _quantity(value, unit: str = "") -> str:
    """One number format for the report's prose and tables: 4 significant digits and the unit."""
    if isinstance(value, (list, tuple)):
        return ", ".join(_quantity(v) for v in value) + (f" {unit}" if unit and value else "")
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float) and math.isinf(value):
        return "infinite"
    if isinstance(value, complex):
        text = f"{value.real:.4g}{value.imag:+.4g}j" if value.imag else f"{value.real:.4g}"
        return f"{text} {unit}" if unit else text
    return with_unit(value, unit, 4)


_CSP_MARK = "obsdesign-content-security-policy"
_SCRIPT = re.compile(r"<script>(.*?)</script>", re.S)
#: Elements a report never holds outside its head: they could navigate the page (meta refresh), change
#: where its links point (base) or send data (form). Matched case-insensitively, with any whitespace.
_FORBIDDEN = re.compile(r"<\s*(script|meta|base|form)\b", re.I)


class ReportContentError(ValueError):
    """The rendered page holds an element the report never writes: some input text escaped its escaping."""


def _section_of(html: str, at: int) -> str:
    """The id of the last element with an id before position ``at`` (the report's section), for messages."""
    ids = re.findall(r'\bid="([^"]+)"', html[:at])
    return ids[-1] if ids else "head"


def _check_elements(html: str) -> str:
    """The explorer's script text, after checking the page holds no element it should not.

    The report writes exactly one script (the explorer) and two meta elements (charset and the
    policy), in that order of the page: every other ``script``, ``meta``, ``base`` or ``form``
    element is refused with :class:`ReportContentError` naming the element and the section it is in.
    """
    scripts = _SCRIPT.findall(html)
    expected = {"meta": 2, "script": 1}
    found = list(_FORBIDDEN.finditer(html))
    counts: dict[str, int] = {}
    for match in found:
        name = match.group(1).lower()
        counts[name] = counts.get(name, 0) + 1
        if counts[name] > expected.get(name, 0):
            raise ReportContentError(
                f"report: refusing to write a page with an extra <{name}> element ({html[match.start():][:40]!r} in "
                f"section {_section_of(html, match.start())!r}); expected {expected.get(name, 0)}: some input text "
                "(a folder's file, a config, a data file) escaped its escaping")
    if len(scripts) != 1 or counts.get("script", 0) != 1:
        raise ReportContentError(f"report: expected exactly one script element (the explorer), "
                                 f"found {len(scripts)} complete and {counts.get('script', 0)} opening tags")
    return scripts[0]


def _with_csp(html: str) -> str:
    """Fill the policy of the meta tag: no external load, only the report's own inline script (by hash).

    The policy forbids every fetch (``default-src 'none'``), any ``<base>`` (``base-uri 'none'``) and
    any form submission (``form-action 'none'``). A policy cannot stop a ``<meta http-equiv="refresh">``,
    so the page itself is checked as well (:func:`_check_elements`): it may hold one script, the charset
    and policy meta elements, and no ``<base>`` or ``<form>``.

    Raises
    ------
    ReportContentError
        A ``ValueError``: the page holds an element the report does not write.
    """
    script = _check_elements(html)
    digest = base64.b64encode(hashlib.sha256(script.encode("utf-8")).digest()).decode("ascii")
    policy = (f"default-src 'none'; script-src 'sha256-{digest}'; style-src 'unsafe-inline'; img-src data:; "
              "base-uri 'none'; form-action 'none'")
    return html.replace(_CSP_MARK, policy, 1)
