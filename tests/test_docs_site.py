"""The documentation site's local checks (docs/_ext): nothing loaded from another host, and the
docstring bars escaped for reStructuredText. The site itself is built by ``make docs``."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "docs" / "_ext"))

from api_docstrings import escape_bars  # noqa: E402
from check_local import check_tree, external_css, external_loads  # noqa: E402


@pytest.mark.parametrize("html", [
    '<script src="https://cdn.example.org/mathjax/tex-chtml.js"></script>',
    '<script src="//cdn.example.org/x.js"></script>',
    '<link rel="stylesheet" href="http://fonts.example.org/css?family=X" />',
    '<img srcset="a.png 1x, https://img.example.org/b.png 2x">',
    '<iframe src="https://ghbtns.example.org/github-btn.html"></iframe>',
    '<div style="background: url(https://img.example.org/a.png)"></div>',
    '<style>@import "https://fonts.example.org/x.css";</style>',
    '<SCRIPT SRC="HTTPS://CDN.EXAMPLE.ORG/X.JS"></SCRIPT>',
])
def test_a_remote_load_is_found(html):
    assert len(external_loads(html)) == 1


def test_local_loads_and_plain_links_pass():
    html = ('<script src="_static/mathjax/tex-chtml.js"></script><link href="../_static/basic.css" rel="stylesheet">'
            '<img src="data:image/png;base64,AAAA"><a href="https://example.org/paper.pdf">the paper</a>'
            '<p>https://example.org in text</p>')
    assert external_loads(html) == []


def test_css_and_tree(tmp_path):
    assert external_css("a { background: url('img/x.png') } b { background: url(https://x.example/y.png) }") == [
        "url(https://x.example/y.png)"]
    (tmp_path / "sub").mkdir()
    (tmp_path / "index.html").write_text('<script src="_static/x.js"></script>', encoding="utf-8")
    (tmp_path / "sub" / "page.html").write_text('<script src="https://cdn.example/x.js"></script>', encoding="utf-8")
    (tmp_path / "sub" / "theme.css").write_text('@import "//fonts.example/a.css";', encoding="utf-8")
    found = check_tree(tmp_path)
    assert [(p.name, f) for p, f in found] == [("page.html", '<script src="https://cdn.example/x.js">'),
                                               ("theme.css", "@import //fonts.example/a.css")]


def test_bars_escaped_outside_literals_and_roles():
    assert escape_bars("bound of |S| [m/V]") == r"bound of \|S\| [m/V]"
    assert escape_bars("``|x|`` and :math:`|T|` and `|y|`_") == "``|x|`` and :math:`|T|` and `|y|`_"
    assert escape_bars("| a | grid row |") == "| a | grid row |"
    assert escape_bars("+-----+-----+") == "+-----+-----+"
    assert escape_bars("        |values| above the limit") == r"        \|values\| above the limit"


ROOT = Path(__file__).resolve().parents[1]
GALLERY_SCRIPTS = sorted([*(ROOT / "analysis").glob("fig_*.py"), ROOT / "analysis" / "emps.py",
                          *(ROOT / "docs" / "examples").glob("plot_*.py")])


@pytest.mark.parametrize("script", GALLERY_SCRIPTS, ids=[p.name for p in GALLERY_SCRIPTS])
def test_gallery_script_has_a_title_and_asserts(script):
    """sphinx-gallery makes a page of every script: its docstring opens with an underlined title
    (the page's title) and says what it asserts, and the script asserts something."""
    import ast

    text = script.read_text(encoding="utf-8")
    doc = ast.get_docstring(ast.parse(text), clean=False).strip("\n").splitlines()
    assert len(doc) > 2 and doc[0].strip() and set(doc[1]) == {"="} and len(doc[1]) >= len(doc[0]), doc[:2]
    assert "Asserts:" in "\n".join(doc)
    assert "assert " in text or "require(" in text
