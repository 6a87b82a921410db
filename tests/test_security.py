"""Hostile user text never becomes code: exports (Python, C, Octave, JS, LaTeX) and the HTML report.

Each generated artifact is run by its real tool (CPython import, gcc -Werror, node, octave,
headless Chromium) with config names and sweep figures built to break out of their context.
"""

import base64
import dataclasses
import importlib.util
import json
import shutil
import subprocess
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import obsdesign as od
from obsdesign.export import export
from obsdesign.export.controller import controller_files
from obsdesign.export.literals import c_string, comment_text, js_string, octave_string, python_string

BS, NL = "\\", "\n"
#: Names built to leave a docstring, comment or string literal, one per known trick (and variants).
HOSTILE = [
    '"""+str(__import__("os").system("touch PWNED"))+"""',
    "'''+str(__import__('os').system('touch PWNED'))+'''",
    '"' + BS + '"""\nimport os; os.system("touch PWNED")\n"""',
    "*" + BS + NL + "/ int pwned_global; /*",
    "*/ int pwned_global; /*",
    "*??/" + NL + "/ int pwned_global; /*",  # trigraph backslash
    "x" + BS + NL + "int pwned_global;",  # splice a // comment onto the next line
    "a" + chr(0) + "b */ int pwned_global; /*",
    "line1\nint pwned_global;\n",
    "line1\rint pwned_global;\r",
    "a" + chr(0x2028) + "PWNED = 1;" + chr(0x2029) + "//",
    "a" + chr(0x85) + chr(0x0B) + chr(0x0C) + "b",
    "</script><script>document.title='PWNED'</script>",
    "%}\nsystem('touch PWNED');\n%{",
    "'); system('touch PWNED'); disp('",
    "`${globalThis.PWNED=1}`",
    "\\u0022; PWNED = 1; //",
    "\\end{document}\\immediate\\write18{touch PWNED}",
    "é漢字\U0001F600 ??= ??( ??) ??' ??< ??! ??> ??-",
    "",
    "x" * 300,
]


def _named(name: str):
    return dataclasses.replace(od.load_preset("vcm"), name=name)


def _run(cmd, cwd, **kw):
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=120, **kw)


# ----------------------------------------------------------------------------------------------
# The literal functions: every string reads back exactly in the real language.
TEXTS = st.lists(st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=24), min_size=1,
                 max_size=40)


def test_comment_text_keeps_the_safe_class_only():
    for name in HOSTILE:
        text = comment_text(name)
        assert len(text) <= 64 and all(c.isascii() and (c.isalnum() or c in " _.,+-") for c in text)


@given(TEXTS)
@settings(max_examples=40)
def test_python_string_round_trips(texts):
    for text in texts:
        literal = python_string(text)
        assert literal.isascii() and "\n" not in literal
        assert eval(compile(literal, "<literal>", "eval"), {"__builtins__": {}}) == text


@pytest.mark.skipif(not shutil.which("gcc"), reason="gcc not installed")
@given(TEXTS)
@settings(max_examples=3)
def test_c_string_round_trips_through_gcc(tmp_path_factory, texts):
    texts = texts + HOSTILE
    tmp = tmp_path_factory.mktemp("c")
    body = "\n".join(f"    {{ static const char s[] = {c_string(t)}; fwrite(s, 1, sizeof s - 1, stdout); "
                     f"putchar(0xff); }}" for t in texts)
    (tmp / "t.c").write_text(f"#include <stdio.h>\nint main(void) {{\n{body}\n    return 0;\n}}\n", encoding="ascii")
    r = _run(["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-o", "t", "t.c"], tmp)
    assert r.returncode == 0, r.stderr
    out = subprocess.run([str(tmp / "t")], capture_output=True, timeout=60).stdout
    assert out.split(b"\xff")[:-1] == [t.encode("utf-8") for t in texts]


@pytest.mark.skipif(not shutil.which("node"), reason="node not installed")
@given(TEXTS)
@settings(max_examples=3)
def test_js_string_round_trips_through_node(tmp_path_factory, texts):
    texts = texts + HOSTILE
    tmp = tmp_path_factory.mktemp("js")
    (tmp / "t.mjs").write_text("const xs = [\n" + ",\n".join(js_string(t) for t in texts)
                               + "];\nprocess.stdout.write(JSON.stringify(xs));\n", encoding="ascii")
    r = _run(["node", "t.mjs"], tmp)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout) == texts


@pytest.mark.skipif(not shutil.which("octave"), reason="octave not installed")
def test_octave_string_round_trips_through_octave(tmp_path):
    texts = [t for t in HOSTILE if all(ord(c) < 256 for c in t)] + ["a" + chr(0) + "b", "'''", "%{"]
    lines = [f"x = {octave_string(t)}; fprintf('%s\\n', sprintf('%d,', double(x)));" for t in texts]
    (tmp_path / "t.m").write_text("\n".join(lines) + "\n", encoding="ascii")
    r = _run(["octave", "--no-gui", "--norc", "--quiet", "t.m"], tmp_path)
    assert r.returncode == 0, r.stderr
    got = [[int(v) for v in line.split(",") if v] for line in r.stdout.splitlines()]
    assert got == [[ord(c) for c in t] for t in texts]
    assert not (tmp_path / "PWNED").exists()


# ----------------------------------------------------------------------------------------------
# The exports end to end with hostile names.
@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """Every export format of every hostile name (one folder per name)."""
    root = tmp_path_factory.mktemp("exports")
    folders = []
    for i, name in enumerate(HOSTILE):
        folder = root / f"n{i}"
        for fmt in ("python", "c", "octave", "js", "latex"):
            export(_named(name), fmt, folder)
        for lang in ("c", "python", "octave", "js"):
            for fname, text in controller_files(_named(name), lang).items():
                (folder / fname).write_text(text, encoding="utf-8")
        folders.append((name, folder))
    return folders


def test_generated_files_hold_no_raw_name(exported):
    for name, folder in exported:
        if len(comment_text(name)) < 8 or comment_text(name) == name:
            continue
        for path in folder.iterdir():
            text = path.read_text(encoding="utf-8")
            for literal in (python_string(name), c_string(name), js_string(name), octave_string(name)):
                text = text.replace(literal, "LITERAL")  # the one escaped occurrence allowed
            assert name not in text, path.name
            assert text.isascii() or path.suffix == ".tex", path.name  # user text never adds non-ASCII


def test_python_exports_import_without_side_effects(exported, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for i, (name, folder) in enumerate(exported):
        for stem in ("obsdesign_observer", "obsdesign_controller"):
            spec = importlib.util.spec_from_file_location(f"_hostile_{stem}_{i}", folder / f"{stem}.py")
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            assert not hasattr(module, "PWNED")
        assert module.Controller().step(1e-3, 0.0) == pytest.approx(2.036116, abs=1e-6)
        observer = importlib.util.module_from_spec(
            importlib.util.spec_from_file_location(f"_hostile_obs_{i}", folder / "obsdesign_observer.py"))
        observer.__spec__.loader.exec_module(observer)
        assert observer.CONFIG_NAME == name
    assert list(tmp_path.iterdir()) == []  # nothing was created (no PWNED file)


@pytest.mark.skipif(not shutil.which("gcc"), reason="gcc not installed")
def test_c_exports_compile_strictly_and_define_nothing_injected(exported, tmp_path):
    for name, folder in exported:
        main = tmp_path / "main.c"
        main.write_text('#include <stdio.h>\n#include "obsdesign_observer.h"\n#include "obsdesign_controller.h"\n'
                        "int main(void) { static const char s[] = OBSDESIGN_OBSERVER_CONFIG_NAME;\n"
                        "  fwrite(s, 1, sizeof s - 1, stdout); return 0; }\n", encoding="ascii")
        exe = tmp_path / "a.out"
        r = _run(["gcc", "-std=c99", "-Wall", "-Wextra", "-Werror", "-I", str(folder), str(main),
                  str(folder / "obsdesign_observer.c"), str(folder / "obsdesign_controller.c"), "-lm",
                  "-o", str(exe)], tmp_path)
        assert r.returncode == 0, (name, r.stderr)
        symbols = _run(["nm", str(exe)], tmp_path).stdout
        assert "pwned" not in symbols
        assert subprocess.run([str(exe)], capture_output=True, timeout=30).stdout == name.encode("utf-8")


@pytest.mark.skipif(not shutil.which("node"), reason="node not installed")
def test_js_exports_load_in_node_without_side_effects(exported, tmp_path):
    lines = []
    for i, (name, folder) in enumerate(exported):
        lines.append(f"import * as o{i} from {json.dumps((folder / 'obsdesign_observer.mjs').as_uri())};")
        lines.append(f"import * as c{i} from {json.dumps((folder / 'obsdesign_controller.mjs').as_uri())};")
    names = ", ".join(f"o{i}.CONFIG_NAME" for i in range(len(exported)))
    lines.append(f"process.stdout.write(JSON.stringify({{names: [{names}], pwned: globalThis.PWNED ?? null, "
                 f"title: globalThis.document ?? null}}));")
    (tmp_path / "t.mjs").write_text("\n".join(lines) + "\n", encoding="utf-8")
    r = _run(["node", "t.mjs"], tmp_path)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["names"] == [name for name, _ in exported] and out["pwned"] is None


@pytest.mark.skipif(not shutil.which("octave"), reason="octave not installed")
def test_octave_exports_run_without_side_effects(exported, tmp_path):
    script = []
    for name, folder in exported:
        script.append(f"addpath('{folder}'); [L1, L2] = obsdesign_gains(0.538, 21.1, 8000, 4); "
                      f"x = obsdesign_config_name(); fprintf('%d %s\\n', numel(x), mat2str(L1 > 0)); "
                      f"rmpath('{folder}');")
    (tmp_path / "t.m").write_text("\n".join(script) + "\n", encoding="utf-8")
    r = _run(["octave", "--no-gui", "--norc", "--quiet", "t.m"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert [line.split()[1] for line in r.stdout.splitlines()] == ["true"] * len(exported)
    assert not (tmp_path / "PWNED").exists()


def test_latex_export_does_not_depend_on_the_name(exported):
    plain = next(f for n, f in exported if n == "").joinpath("obsdesign_static.tex").read_text(encoding="utf-8")
    for name, folder in exported:
        assert (folder / "obsdesign_static.tex").read_text(encoding="utf-8") == plain, name
