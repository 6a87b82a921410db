"""Sphinx configuration of the obsdesign documentation site (``make docs``).

Everything is local: the Markdown pages of this folder (MyST), the API reference generated from
the numpydoc docstrings (autosummary), the command-line reference generated from the parser
(sphinx-argparse), the gallery run from ``analysis/`` and ``docs/examples/`` (sphinx-gallery) and
the notebooks of ``docs/notebooks/`` executed at build time (myst-nb). MathJax is served from the
site itself (sphinx-mathjax-offline), nothing is fetched from another host at build time, and
``docs/_ext/check_local.py`` fails the build when a page loads anything from one.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE / "_ext"))
os.environ.setdefault("MPLBACKEND", "agg")

import obsdesign  # noqa: E402

project = "obsdesign"
author = "obsdesign developers"
copyright = "obsdesign developers (MIT License)"
release = version = obsdesign.__version__

extensions = [
    "myst_nb",  # Markdown pages (myst-parser) and executed notebooks
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "sphinx.ext.viewcode",
    "sphinxarg.ext",
    "sphinx_gallery.gen_gallery",
    "sphinx-mathjax-offline",  # MathJax 3 copied into _static: no CDN
    "sphinx_design",  # cards and grids of the landing page and the section pages
    "sphinx_copybutton",  # a copy button on every code block (prompts and outputs left out)
    "gallery_scraper",
    "api_docstrings",
    "check_local",
]

root_doc = "index"
source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "conftest.py", "examples", "**/.ipynb_checkpoints", "gallery/**/*.ipynb", "gallery/**/*.py",
                    "gallery/**/*.zip", "gallery/**/*.json"]
templates_path = ["_templates"]
suppress_warnings = ["myst.header"]  # pages start at '#' and some skip a level, as on GitHub

# MathJax's menu can switch on its speech/assistive modules, whose IE fallbacks name a CDN: no menu.
mathjax3_config = {"options": {"enableMenu": False}}

# MyST: the pages are GitHub Markdown; '$' is not math there (shell prompts, prices), so no dollarmath.
myst_enable_extensions = ["colon_fence"]
myst_heading_anchors = 3

# Notebooks run at every build (their cells assert what they show); an error fails the build.
nb_execution_mode = "force"
nb_execution_raise_on_error = True
nb_execution_timeout = 180
nb_execution_show_tb = True
nb_merge_streams = True

# API reference: autosummary pages from the numpydoc docstrings.
autosummary_generate = True
autosummary_imported_members = False
autosummary_mock_imports = ["obsdesign.__main__"]  # importing it would run the command with Sphinx's argv
autodoc_typehints = "none"  # numpydoc's Parameters sections say the types
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()

# Gallery: the analysis scripts (each writes its figure with --out and asserts its claims) and
# the short examples of docs/examples/; emps.py needs the EMPS benchmark record (not shipped: see
# docs/measured-data.md) and runs when the record is found, as in the test suite.
from gallery_scraper import EMPS  # noqa: E402

sphinx_gallery_conf = {
    "examples_dirs": [str(ROOT / "analysis"), "examples"],
    "gallery_dirs": ["gallery/analysis", "gallery/examples"],
    "filename_pattern": r"/(fig_.*|emps|plot_.*)\.py" if EMPS.is_file() else r"/(fig_.*|plot_.*)\.py",
    "ignore_pattern": r"(_common|__init__)\.py" + ("" if EMPS.is_file() else r"|emps\.py"),
    "reset_argv": "gallery_scraper.argv",
    "image_scrapers": ("matplotlib", "gallery_scraper.written_figures"),
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "download_all_examples": False,
    "remove_config_comments": True,
    "plot_gallery": "True",
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "write_computation_times": False,  # its page loads jQuery and DataTables from CDNs
    "show_signature": False,
    "promote_jupyter_magic": False,
}

# The PyData theme (NumPy, SciPy, pandas): top navigation by section (the root toctree of index.md),
# the section's pages on the left, the page's outline on the right, a dark mode. It serves its
# fonts and icons from the site (docs/_ext/check_local.py checks every page and style sheet).
html_theme = "pydata_sphinx_theme"
html_title = f"obsdesign {release}"
html_static_path = ["_static"]
html_css_files = ["obsdesign.css"]  # code and signature blocks wrap to the column
html_theme_options = {
    "navbar_align": "left",
    "header_links_before_dropdown": 8,  # every section in the top bar at 1400 px, no "More" menu
    "show_nav_level": 2,  # a section's task groups open in the left sidebar
    "navigation_depth": 6,  # the API reference's module pages are five levels deep
    "show_toc_level": 2,
    "secondary_sidebar_items": {"**": ["page-toc"], "index": []},
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
    "navigation_with_keys": False,
    "use_edit_page_button": False,
    "pygments_light_style": "default",
    "pygments_dark_style": "monokai",
}
# The landing page and the tutorial: full width, no section sidebar (neither has pages below it).
html_sidebars = {"index": [], "getting-started": []}
html_show_sourcelink = False
html_copy_source = False

# API signatures longer than this are written one parameter per line (no sideways scrolling).
maximum_signature_line_length = 88

# sphinx-copybutton: copy the commands and the code, not the prompts and the printed output.
copybutton_prompt_text = r">>> |\.\.\. |\$ "
copybutton_prompt_is_regexp = True
copybutton_only_copy_prompt_lines = True
copybutton_exclude = ".linenos, .gp, .go"

