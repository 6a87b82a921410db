"""The report page's markup rules: one number format, and the content policy with its check.

Shared by the entry point :mod:`obsdesign.report.html` and the page builder
:mod:`obsdesign.report.page` (one place for both, no import cycle).
"""

from __future__ import annotations

import base64
import hashlib
import math
import re

from .._format import with_unit

__all__ = ["ReportContentError"]


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
