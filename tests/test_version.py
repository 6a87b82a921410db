"""One version, one license, one citation: ``obsdesign/_version.py`` is the only place the
version is written, and everything that shows it (``obsdesign.__version__``,
``obsdesign --version``, the installed metadata, CITATION.cff, CHANGELOG.md) agrees with it."""

from __future__ import annotations

import importlib.metadata
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import obsdesign
from obsdesign._version import __version__

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))


def test_the_version_is_a_release_number():
    assert re.fullmatch(r"\d+\.\d+\.\d+", __version__), __version__


def test_pyproject_reads_the_version_from_the_one_module():
    project = PYPROJECT["project"]
    assert "version" not in project and "version" in project["dynamic"]
    assert PYPROJECT["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "obsdesign._version.__version__"}


def test_the_version_string_is_written_once_in_the_package():
    writes = [p.relative_to(ROOT) for p in (ROOT / "obsdesign").rglob("*.py")
              if re.search(r"^__version__\s*=", p.read_text(encoding="utf-8"), re.M)]
    assert writes == [Path("obsdesign/_version.py")]


def test_package_command_and_metadata_agree():
    proc = subprocess.run([sys.executable, "-m", "obsdesign", "--version"], capture_output=True, text=True,
                          check=True)
    assert obsdesign.__version__ == __version__
    assert proc.stdout.strip() == f"obsdesign {__version__}"
    # the installed distribution's metadata (built from _version.py by setuptools)
    assert importlib.metadata.version("obsdesign") == __version__


def test_license_file_is_the_license_pyproject_names():
    assert PYPROJECT["project"]["license"] == "MIT"
    assert PYPROJECT["project"]["license-files"] == ["LICENSE"]
    text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert text.startswith("MIT License\n")
    assert re.search(r"^Copyright \(c\) \d{4} obsdesign developers$", text, re.M)
    assert "THE SOFTWARE IS PROVIDED \"AS IS\", WITHOUT WARRANTY OF ANY KIND" in text


def test_no_invented_project_address():
    # a placeholder host would be an address nobody owns; there is no real one yet
    assert "urls" not in PYPROJECT["project"]


def test_citation_names_this_version_and_the_paper():
    text = (ROOT / "CITATION.cff").read_text(encoding="utf-8")
    assert re.search(r"^cff-version: 1\.2\.0$", text, re.M)
    assert re.search(r"^version: (\S+)$", text, re.M).group(1) == __version__
    assert "Reduced-order asymptotic observer of nonlinear friction for precise motion control" in text
    assert re.search(r"family-names: Ruderman\s+given-names: Michael", text)


def test_changelog_has_an_unreleased_section_and_one_for_this_version():
    headings = re.findall(r"^## \[?([^\]\s]+)\]?", (ROOT / "CHANGELOG.md").read_text(encoding="utf-8"), re.M)
    assert headings[0] == "Unreleased"
    assert headings[1] == __version__
