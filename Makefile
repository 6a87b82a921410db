# Both targets create or reuse the local virtual environment .venv/ themselves.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: test test-fast report bench screenshot clean

$(PY):
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,distributed]'
	touch $(STAMP)

# Both test runs spread the cases over every core (pytest-xdist, `-n auto`: one worker process per core).
test: $(STAMP)
	$(PY) -m pytest -n auto

# The quick loop while editing: everything but the cases marked @pytest.mark.slow (meant for under
# 2 minutes on an idle 2-core machine; docs/development.md says what is marked slow and why).
test-fast: $(STAMP)
	$(PY) -m pytest -n auto -m "not slow"

report: $(STAMP)
	$(VENV)/bin/obsdesign report --preset vcm -o report.html

bench: $(STAMP)
	$(PY) benchmarks/run.py --write

screenshot: $(STAMP)
	OBSDESIGN_SCREENSHOT=docs/img/report.png $(PY) -m pytest -q tests/test_report.py -k chromium

clean:
	rm -rf $(VENV) build *.egg-info

# Lint (not part of `make test` yet): ruff with the [tool.ruff] rules of pyproject.toml and mypy with
# its [tool.mypy] configuration (the package), from the same .venv with the `lint` extra installed
# beside the test tools.
.PHONY: lint wheel-smoke
LINT_STAMP := $(VENV)/.installed-lint

$(LINT_STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,distributed,lint]'
	touch $(LINT_STAMP)

lint: $(LINT_STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy

# Build the sdist and wheel, check them, install the wheel outside the repository and run it there.
wheel-smoke:
	.ci/wheel-smoke.sh

# The documentation site: Sphinx into docs/_build/html, warnings as errors; the gallery and the
# notebooks run at build time, and the build fails when a page loads anything from another host
# (docs/_ext/check_local.py). From the same .venv with the `docs` extra. Then the built site is
# checked (tests/test_docs_site.py, headless Chromium where installed): every page reachable from
# the navigation, the landing page's install line and first example above the fold at 1400 x 900,
# no signature block wider than its column.
.PHONY: docs
DOCS_STAMP := $(VENV)/.installed-docs

$(DOCS_STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,distributed,docs]'
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	rm -rf docs/_build/html docs/_build/doctrees docs/_build/gallery-out docs/gallery docs/api
	MPLBACKEND=agg $(PY) -m sphinx -b html -W --keep-going -q docs docs/_build/html
	OBSDESIGN_DOCS_SITE=docs/_build/html $(PY) -m pytest -q -p no:randomly -p no:cacheprovider tests/test_docs_site.py
	@echo "docs: docs/_build/html/index.html"
