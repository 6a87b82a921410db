"""The report page's markup rules: one number format, the content policy with its check, and the
derivation table as data (what the result memo keeps) with its schema and its escaping renderer.

Shared by the entry point :mod:`obsdesign.report.html` and the page builder
:mod:`obsdesign.report.page` (one place for both, no import cycle).
"""

from __future__ import annotations

import base64
import hashlib
import html
import math
import re
from html.parser import HTMLParser

from .._format import with_unit

__all__ = ["ReportContentError", "derivation_tree", "is_derivation_tree", "render_derivation", "is_figure_svg"]

#: What :func:`obsdesign.symbolic.printing.derivation_html` writes: an HTML table of MathML presentation
#: elements. A derivation tree read back from the result memo (a file on disk) must hold nothing else.
_DERIVATION_TAGS = frozenset({
    "table", "caption", "tr", "th", "td", "math", "mi", "mn", "mo", "ms", "mtext", "mspace", "mrow", "mfrac",
    "msqrt", "mroot", "msub", "msup", "msubsup", "munder", "mover", "munderover", "mtable", "mtr", "mtd",
    "mfenced", "mstyle", "mpadded", "mphantom"})
#: Its attributes: presentation keywords and lengths only (no URL, no script, no style).
_DERIVATION_ATTRS = frozenset({"class", "fence", "stretchy", "symmetric", "width", "mathvariant", "separators",
                               "open", "close", "lspace", "rspace", "columnalign", "accent", "linethickness"})
_MATHML_NS = "http://www.w3.org/1998/Math/MathML"
_PLAIN_VALUE = re.compile(r"[A-Za-z0-9 .,%#+-]*")


#: Ceilings of a kept derivation tree: the largest one written (variant ``lag``) has about 2,000 nodes, 9 deep.
_MAX_NODES = 50_000
_MAX_DEPTH = 40


class _TreeBuilder(HTMLParser):
    """Reads the derivation markup SymPy's printer wrote (this process's own output) into a tree."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.root: list = ["root", []]
        self.stack = [self.root]

    def handle_starttag(self, tag, attrs):
        node = [tag, [[name, value or ""] for name, value in attrs]]
        self.stack[-1].append(node)
        self.stack.append(node)

    def handle_startendtag(self, tag, attrs):
        self.stack[-1].append([tag, [[name, value or ""] for name, value in attrs]])

    def handle_endtag(self, tag):
        if len(self.stack) > 1 and self.stack[-1][0] == tag:
            self.stack.pop()
        else:
            raise ValueError(f"derivation markup: unbalanced </{tag}>")

    def handle_data(self, data):
        self.stack[-1].append(data)


def derivation_tree(markup: str) -> list:
    """The derivation table as data: ``[tag, [[attribute, value], ...], child, ...]``, text children as strings.

    What the result memo keeps of the derivation (never markup): :func:`render_derivation` writes the page's
    markup from it, escaping every text and attribute, whether the tree was just computed or read from disk.

    Parameters
    ----------
    markup : str
        :func:`obsdesign.symbolic.printing.derivation_html` of a derivation (the package's own output).

    Returns
    -------
    list
        The root element's tree.

    Examples
    --------
    >>> derivation_tree("<table class='d'><tr><td>a &lt; b</td></tr></table>")
    ['table', [['class', 'd']], ['tr', [], ['td', [], 'a < b']]]
    """
    builder = _TreeBuilder()
    builder.feed(markup)
    builder.close()
    if len(builder.stack) != 1 or len(builder.root) != 3 or not isinstance(builder.root[2], list):
        raise ValueError("derivation markup: expected one element")
    return builder.root[2]


def is_derivation_tree(tree) -> bool:
    """Whether ``tree`` is a derivation table as :func:`derivation_tree` writes it (the memo entry's schema).

    Elements are the table and MathML presentation elements only; attributes presentation keywords with
    plain values (the MathML namespace on ``math``); at most 50,000 nodes, 40 deep. Text is anything: it is
    escaped when rendered.

    Parameters
    ----------
    tree : object
        A value read from the result memo.

    Examples
    --------
    >>> is_derivation_tree(['table', [['class', 'd']], ['tr', [], ['td', [], '<!--> <img onerror=x>']]])
    True
    >>> is_derivation_tree(['table', [], ['style', [], 'td {display: none}']])
    False
    >>> is_derivation_tree(['table', [['onclick', 'x']]])
    False
    """
    count = 0
    todo = [(tree, 0)]
    while todo:
        node, depth = todo.pop()
        count += 1
        if count > _MAX_NODES or depth > _MAX_DEPTH:
            return False
        if isinstance(node, str):
            continue
        if not (isinstance(node, list) and len(node) >= 2 and node[0] in _DERIVATION_TAGS
                and isinstance(node[1], list)):
            return False
        for pair in node[1]:
            if not (isinstance(pair, list) and len(pair) == 2 and all(isinstance(p, str) for p in pair)):
                return False
            name, value = pair
            if name == "xmlns":
                if node[0] != "math" or value != _MATHML_NS:
                    return False
            elif name not in _DERIVATION_ATTRS or _PLAIN_VALUE.fullmatch(value) is None:
                return False
        todo.extend((child, depth + 1) for child in node[2:])
    return isinstance(tree, list) and bool(tree) and tree[0] == "table"


def render_derivation(tree: list) -> str:
    """The page's markup of a derivation tree: elements from the allowlist, every text and value escaped.

    Parameters
    ----------
    tree : list
        A tree that passes :func:`is_derivation_tree`.

    Raises
    ------
    ValueError
        ``tree`` is not a derivation tree.

    Examples
    --------
    >>> render_derivation(['table', [['class', 'd']], ['tr', [], ['td', [], '<!--> <img onerror=x>']]])
    '<table class="d"><tr><td>&lt;!--&gt; &lt;img onerror=x&gt;</td></tr></table>'
    """
    if not is_derivation_tree(tree):
        raise ValueError("tree: expected a derivation table of allowed elements and attributes")
    out: list[str] = []

    def write(node) -> None:
        if isinstance(node, str):
            out.append(html.escape(node))
            return
        attrs = "".join(f' {name}="{html.escape(value)}"' for name, value in node[1])
        out.append(f"<{node[0]}{attrs}>")
        for child in node[2:]:
            write(child)
        out.append(f"</{node[0]}>")

    write(tree)
    return "".join(out)


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


#: The elements a kept figure may hold: what matplotlib's SVG backend writes (an allow-list; a kept figure
#: holding anything else, a script or an event handler, is refused and drawn again).
_SVG_ELEMENTS = frozenset({"svg", "g", "use", "path", "text", "tspan", "defs", "clipPath", "rect", "style", "line",
                           "circle", "ellipse", "polyline", "polygon", "image", "title", "desc", "pattern", "mask",
                           "linearGradient", "radialGradient", "stop", "marker", "symbol"})
_TAG = re.compile(r"<\s*/?\s*([A-Za-z][\w:.-]*)")
_ATTR = re.compile(r"\s([A-Za-z_:][\w:.-]*)\s*=\s*(\"[^\"]*\"|'[^']*')")


def _well_formed_figure(text: str) -> bool:
    """Whether ``text`` is well-formed XML whose every element is allowed and no attribute an event handler.

    The regular expressions of :func:`is_figure_svg` read attributes as matplotlib quotes them; an HTML
    parser also reads ``<g onload=x>`` and ``<g/onload="x">`` as handlers. Matplotlib writes XML, so a kept
    figure must parse as XML (no DOCTYPE or entity reaches the parser: :func:`is_figure_svg` refuses ``<!``
    but comments first), and the parsed tree is checked again: element names, attribute names.
    """
    import xml.etree.ElementTree as ET  # noqa: N817 (the standard alias)

    try:
        root = ET.fromstring(text)
    except ET.ParseError:
        return False
    for el in root.iter():
        if not isinstance(el.tag, str) or el.tag.rpartition("}")[2] not in _SVG_ELEMENTS:
            return False
        if any(name.rpartition("}")[2].lower().startswith("on") for name in el.attrib):
            return False
    return True


def is_figure_svg(text) -> bool:
    """Whether ``text`` is an ``<svg>`` element as :func:`inline_svg` writes it: only the elements of
    matplotlib's SVG backend, no event-handler attribute, every link within the figure (``#id``) or a
    PNG data URL, no ``javascript:``, no CSS import or URL outside the figure, no CDATA section or
    declaration (comments are allowed: matplotlib writes a label's TeX source in one).

    The check of a figure read back from the result memo (:func:`kept_svg`) before it is put on a page.

    Parameters
    ----------
    text : object

    Examples
    --------
    >>> xlink = 'xmlns:xlink="http://www.w3.org/1999/xlink"'
    >>> is_figure_svg(f'<svg {xlink}><g id="a"><use xlink:href="#a"/></g></svg>')
    True
    >>> is_figure_svg('<svg><g onload=alert(1)></g></svg>')      # unquoted: not XML, an HTML handler
    False
    >>> is_figure_svg('<svg><g onload="alert(1)"/></svg>'), is_figure_svg('<svg><script>x</script></svg>')
    (False, False)
    """
    if not isinstance(text, str) or not text.startswith("<svg") or not text.rstrip().endswith("</svg>"):
        return False
    if any(m.group(1) not in _SVG_ELEMENTS for m in _TAG.finditer(text)):
        return False
    lowered = text.lower()
    if "javascript:" in lowered or "@import" in lowered or "<?" in lowered or re.search(r"<!(?!--)", text):
        return False  # comments (matplotlib writes each label's TeX source in one) but no CDATA or declaration
    if re.search(r"url\(\s*['\"]?(?!#)", lowered):
        return False
    if not _well_formed_figure(text):
        return False  # what a browser's HTML parser reads differently (an unquoted or slash-led handler)
    for name, value in _ATTR.findall(text):
        if name.lower().startswith("on"):
            return False
        if name.lower().endswith("href") and not (value[1:].startswith("#") or value[1:].startswith("data:image/png;base64,")):
            return False
    return True
