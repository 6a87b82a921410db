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

test: $(STAMP)
	$(PY) -m pytest

# The quick loop while editing: everything but the cases marked @pytest.mark.slow.
test-fast: $(STAMP)
	$(PY) -m pytest -m "not slow"

report: $(STAMP)
	$(VENV)/bin/obsdesign report --preset vcm -o report.html

bench: $(STAMP)
	$(PY) benchmarks/run.py --write

screenshot: $(STAMP)
	OBSDESIGN_SCREENSHOT=docs/img/report.png $(PY) -m pytest -q tests/test_report.py -k chromium

clean:
	rm -rf $(VENV) build *.egg-info
