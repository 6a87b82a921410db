#!/usr/bin/env bash
# Wheel smoke test: build the sdist and the wheel from a copy of the checkout (`python -m build`
# builds the wheel from the sdist, so a file missing from the sdist fails here), check both with
# `twine check --strict`, install the wheel into a fresh virtual environment in a temporary
# directory outside the repository, and run the installed command there: `report`, a C export
# (compiled when a C compiler is present), an FMU and an ST block. Any error fails the script; it prints the time of each step.
#
#   .ci/wheel-smoke.sh                      # PYTHON=python3.11 by default
#   WHEEL_SMOKE_TOOLS=/path/to/venv .ci/wheel-smoke.sh   # reuse a venv holding build and twine
#   KEEP=1 .ci/wheel-smoke.sh               # keep the temporary directory (its path is printed)
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
PYTHON="${PYTHON:-python3.11}"
work="$(mktemp -d "${TMPDIR:-/tmp}/obsdesign-wheel.XXXXXX")"
if [ "${KEEP:-0}" = 1 ]; then echo "wheel-smoke: keeping $work"; else trap 'rm -rf "$work"' EXIT; fi
case "$work/" in "$repo"/*) echo "wheel-smoke: the temporary directory $work is inside the repository" >&2; exit 2;; esac
unset PYTHONPATH  # the installed wheel, never the checkout

t0=$SECONDS
step() { echo "wheel-smoke: [$((SECONDS - t0)) s] $*"; }

step "copy the checkout's files (tracked and new, not ignored) to $work/src"
mkdir -p "$work/src" "$work/dist" "$work/run"
git -C "$repo" ls-files -z --cached --others --exclude-standard \
    | (cd "$repo" && xargs -0 sh -c 'for f; do [ -e "$f" ] && printf "%s\0" "$f"; done' _) \
    | tar -C "$repo" --null -T - -cf - | tar -C "$work/src" -xf -

if [ -n "${WHEEL_SMOKE_TOOLS:-}" ]; then
    tools="$WHEEL_SMOKE_TOOLS"
else
    step "build tools (build, twine) in a fresh venv"
    "$PYTHON" -m venv "$work/tools"
    tools="$work/tools"
    "$tools/bin/python" -m pip install --quiet build twine
fi

step "python -m build (sdist, then the wheel from the sdist)"
"$tools/bin/python" -m build --outdir "$work/dist" "$work/src" > "$work/build.log" 2>&1 \
    || { cat "$work/build.log" >&2; exit 1; }
ls -l "$work/dist"
sdist=$(ls "$work"/dist/obsdesign-*.tar.gz)
wheel=$(ls "$work"/dist/obsdesign-*.whl)

step "twine check --strict"
"$tools/bin/python" -m twine check --strict "$sdist" "$wheel"

step "the wheel holds the package data and the license"
"$tools/bin/python" - "$wheel" <<'PY'
import sys, zipfile
names = set(zipfile.ZipFile(sys.argv[1]).namelist())
need = ["obsdesign/py.typed", "obsdesign/datasets/example_log.csv", "obsdesign/presets/vcm.toml"]
missing = [n for n in need if n not in names]
missing += [] if any(n.endswith(".dist-info/licenses/LICENSE") for n in names) else ["*.dist-info/licenses/LICENSE"]
if missing:
    sys.exit(f"wheel-smoke: the wheel lacks {', '.join(missing)}")
PY

step "fresh venv outside the repository; pip install the wheel"
"$PYTHON" -m venv "$work/venv"
"$work/venv/bin/python" -m pip install --quiet "$wheel"

cd "$work/run"
step "obsdesign --version and the installed files"
version=$("$work/venv/bin/python" -c 'import importlib.metadata as m; print(m.version("obsdesign"))')
[ "$("$work/venv/bin/obsdesign" --version)" = "obsdesign $version" ]
"$work/venv/bin/python" - "$work/venv" <<'PY'
import pathlib, sys
import obsdesign as od
where = pathlib.Path(od.__file__).resolve()
if not where.is_relative_to(pathlib.Path(sys.argv[1]).resolve()):
    sys.exit(f"wheel-smoke: obsdesign imported from {where}, not from the fresh venv")
log = od.datasets.example_log()
if not log.is_file() or log.read_text(encoding="utf-8").splitlines()[0] != "t,x,u":
    sys.exit(f"wheel-smoke: the example log {log} is missing or has no t,x,u header")
print(f"obsdesign {od.__version__} from {where.parent}")
PY

step "obsdesign report --preset vcm -o report.html"
"$work/venv/bin/obsdesign" report --preset vcm -o report.html
[ -s report.html ] && grep -q "</html>" report.html

step "obsdesign export --format c -o gen/"
"$work/venv/bin/obsdesign" export --format c -o gen/
ls gen/
ls gen/*.c gen/*.h > /dev/null
if command -v cc > /dev/null; then
    step "cc -std=c99 -Wall -Werror -c gen/*.c"
    for f in gen/*.c; do cc -std=c99 -Wall -Werror -c "$f" -o "${f%.c}.o"; done
fi

step "obsdesign export --what controller --format fmu, st -o tools/ (the FMU and PLC templates ship)"
"$work/venv/bin/obsdesign" export --what controller --format fmu -o tools/
"$work/venv/bin/obsdesign" export --what controller --format st -o tools/
"$work/venv/bin/python" -c "import zipfile; assert 'modelDescription.xml' in zipfile.ZipFile('tools/obsdesign_controller.fmu').namelist()"
grep -q "END_FUNCTION_BLOCK" tools/obsdesign_controller.st

step "passed: sdist $(du -k "$sdist" | cut -f1) kB, wheel $(du -k "$wheel" | cut -f1) kB; total $((SECONDS - t0)) s"
