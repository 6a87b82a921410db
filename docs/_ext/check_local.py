"""The built site loads nothing from another host: a check run at the end of every HTML build.

Every ``<script src>``, ``<link href>``, ``<img src|srcset>``, ``<iframe src>``, ``<source>``,
``<audio>``/``<video>``, ``<object data>`` and ``<embed src>`` of every page, and every
``url(...)``/``@import`` of every style sheet, ``<style>`` element and ``style`` attribute, must be relative (or ``data:``); an
absolute ``http(s)://`` or protocol-relative ``//host`` address is reported as a Sphinx warning,
which ``-W`` (``make docs``) turns into a failed build. Plain links (``<a href>``) load nothing and
may point anywhere.

Examples
--------
>>> external_loads('<script src="_static/x.js"></script><a href="https://example.org">ok</a>')
[]
>>> external_loads('<link rel="stylesheet" href="https://cdn.example/x.css">')
['<link href="https://cdn.example/x.css">']
>>> external_css("body { background: url('//cdn.example/a.png') }")
['url(//cdn.example/a.png)']
"""

from __future__ import annotations

import re
from html.parser import HTMLParser
from pathlib import Path

#: (tag, attribute) pairs whose value the browser fetches.
LOADS = {("script", "src"), ("link", "href"), ("img", "src"), ("img", "srcset"), ("iframe", "src"),
         ("source", "src"), ("source", "srcset"), ("audio", "src"), ("video", "src"), ("video", "poster"),
         ("object", "data"), ("embed", "src"), ("input", "src"), ("track", "src")}
_REMOTE = re.compile(r"^\s*(https?:)?//", re.I)
_CSS = re.compile(r"""url\(\s*['"]?([^'")]+)['"]?\s*\)|@import\s+['"]([^'"]+)['"]""", re.I)


def _remote(value: str) -> bool:
    return any(_REMOTE.match(part.strip().split(" ")[0]) for part in value.split(",")) if value else False


class _Loads(HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.found: list[str] = []

        self._style = False

    def handle_starttag(self, tag, attrs):
        self._style = tag == "style"
        for name, value in attrs:
            if (tag, name) in LOADS and value and _remote(value):
                self.found.append(f'<{tag} {name}="{value}">')
            elif name == "style" and value:
                self.found += [f'<{tag} style="{f}">' for f in external_css(value)]

    def handle_endtag(self, tag):
        self._style = False

    def handle_data(self, data):
        if self._style:  # a <style> element: its url() and @import load too
            self.found += [f"<style> {f}" for f in external_css(data)]


def external_loads(html: str) -> list[str]:
    """The tags of an HTML page that load something from another host (``[]`` when none)."""
    parser = _Loads()
    parser.feed(html)
    parser.close()
    return parser.found


def external_css(css: str) -> list[str]:
    """The ``url()`` and ``@import`` of a style sheet that point at another host."""
    found = []
    for m in _CSS.finditer(css):
        target = m.group(1) or m.group(2)
        if _remote(target):
            found.append(f"url({target.strip()})" if m.group(1) else f"@import {target}")
    return found


def check_tree(outdir: str | Path) -> list[tuple[Path, str]]:
    """``(file, offending load)`` for every HTML page and style sheet under ``outdir``."""
    problems = []
    for path in sorted(Path(outdir).rglob("*")):
        if path.suffix in (".html", ".htm"):
            problems += [(path, f) for f in external_loads(path.read_text(encoding="utf-8", errors="replace"))]
        elif path.suffix == ".css":
            problems += [(path, f) for f in external_css(path.read_text(encoding="utf-8", errors="replace"))]
    return problems


def _check(app, exc):
    if exc is not None or app.builder.format != "html":
        return
    from sphinx.util import logging

    logger = logging.getLogger(__name__)
    problems = check_tree(app.outdir)
    for path, found in problems:
        logger.warning("page loads from another host: %s in %s", found, path.relative_to(app.outdir))
    if not problems:
        logger.info("check_local: %d pages and style sheets load nothing from another host",
                    sum(1 for p in Path(app.outdir).rglob("*") if p.suffix in (".html", ".css")))


def setup(app):
    # after sphinx-mathjax-offline has copied MathJax (also on build-finished): a later priority
    app.connect("build-finished", _check, priority=900)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
