"""Hostile user text never becomes code: exports (Python, C, Octave, JS, LaTeX) and the HTML report.

Each generated artifact is run by its real tool (CPython import, gcc -Werror, node, octave,
headless Chromium) with config names and sweep figures built to break out of their context.
"""

import base64
import dataclasses
import importlib.util
import json
import re
import shutil
import subprocess

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
        if len(name) < 8 or re.fullmatch(r"[A-Za-z0-9 _.,+-]*", name):
            continue  # too short to search for, or harmless anywhere
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


@pytest.mark.slow
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


# ----------------------------------------------------------------------------------------------
# The report with hostile sweep figures, opened in headless Chromium.
CHROMIUM, DRIVER = shutil.which("chromium"), shutil.which("chromedriver")
MARK = "document.documentElement.setAttribute('data-pwned', '{id}')"


def _hostile_svgs(base: str) -> list[str]:
    """SVG documents that run script or fetch ``base/<id>`` by every trick of the review (E6-E14) and more."""
    run = lambda i: MARK.format(id=i)  # noqa: E731
    return [
        f'<svg xmlns="http://www.w3.org/2000/svg"><script>{run("e6")}</script></svg>',
        f'<svg xmlns="http://www.w3.org/2000/svg"><SCRIPT>{run("e8")}</SCRIPT></svg>',
        f'<svg xmlns="http://www.w3.org/2000/svg" onload ="{run("e9")}"><rect width="9" height="9"/></svg>',
        "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\">"
        "<a href='javascript:document.documentElement.dataset.pwned=\"e10\"'>"
        "<rect width='99' height='99'/></a></svg>",
        f'<svg xmlns="http://www.w3.org/2000/svg"><foreignObject width="9" height="9">'
        f'<img xmlns="http://www.w3.org/1999/xhtml" src="{base}/e11" onerror\t="{run("e11")}"/></foreignObject></svg>',
        f'<svg xmlns="http://www.w3.org/2000/svg"><foreignObject><iframe xmlns="http://www.w3.org/1999/xhtml" '
        f'src={base}/e12></iframe></foreignObject></svg>',
        f'<svg xmlns="http://www.w3.org/2000/svg"><style>@import url({base}/e13);</style></svg>',
        f'<svg xmlns="http://www.w3.org/2000/svg"></svg></figure><ScRiPt>{run("e14")}</ScRiPt><figure><svg>',
        f'<svg xmlns="http://www.w3.org/2000/svg"><image href="{base}/x1" width="9" height="9"/>'
        f'<use href="{base}/x2#a"/><rect fill="url({base}/x3#p)" width="9" height="9"/></svg>',
        f'<svg xmlns="http://www.w3.org/2000/svg"><style>rect {{ fill: url("{base}/x4"); }} '
        f'@font-face {{ font-family: q; src: url({base}/x5); }} text {{ font-family: q; }}</style>'
        f'<rect width="9" height="9"/><text>x</text></svg>',
        f'<svg xmlns="http://www.w3.org/2000/svg"><animate attributeName="href" values="javascript:{run("x6")}"/>'
        f'<set attributeName="onmouseover" to="{run("x7")}"/></svg>',
        f'<?xml version="1.0"?><!DOCTYPE svg [<!ENTITY x SYSTEM "{base}/x8">]>'
        f'<svg xmlns="http://www.w3.org/2000/svg"><text>&x;</text></svg>',
        f'<svg xmlns="http://www.w3.org/2000/svg"><iframe srcdoc="&lt;script&gt;parent.{run("x9")}&lt;/script&gt;"/>'
        f'<img src=x onerror={run("x10")}></svg>',
        f"<svg/onload={run('x11')}>",
        f'<svg xmlns="http://www.w3.org/2000/svg"><meta http-equiv="refresh" content="0;url={base}/x12"/></svg>',
    ]


class _Recorder:
    """A local HTTP server on 127.0.0.1 that records every path requested (and answers 404)."""

    def __enter__(self):
        import http.server
        import threading

        paths = self.paths = []

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_GET(self):  # noqa: N802
                paths.append(self.path)
                self.send_response(404)
                self.end_headers()

            def log_message(self, *args):
                pass

        self.server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.base = f"http://127.0.0.1:{self.server.server_address[1]}"
        threading.Thread(target=self.server.serve_forever, daemon=True).start()
        return self

    def __exit__(self, *exc):
        self.server.shutdown()
        self.server.server_close()


def _chrome():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-sync",
                 "--disable-background-networking", "--disable-component-update", "--window-size=1280,900"):
        opts.add_argument(flag)
    driver = webdriver.Chrome(service=Service(DRIVER), options=opts)
    driver.set_page_load_timeout(30)
    return driver


def _visit(driver, path, server, wait=2.0):
    import time

    driver.get(path.as_uri())
    driver.execute_script("window.scrollTo(0, document.body.scrollHeight);")
    time.sleep(wait)  # bounded: give any fetch or timer the time to fire
    return driver.execute_script("return document.documentElement.getAttribute('data-pwned');"), list(server.paths)


def _hostile_folders(tmp_path, svgs):
    """A sweep folder and a compare folder whose figures are the hostile SVGs (valid otherwise)."""
    from obsdesign.comparison import COLUMNS
    from obsdesign.sweeps.summary import make_summary

    sweep_dir, compare_dir = tmp_path / "sweep", tmp_path / "compare"
    sweep_dir.mkdir()
    compare_dir.mkdir()
    summary = make_summary([{"status": "ok", "rho": 2.0, "rms_error": 1e-5}], ["rho"], metric="rms_error",
                           resumed_runs=0, wall_s=1.0)
    (sweep_dir / "summary.json").write_text(json.dumps(summary), encoding="utf-8")
    (sweep_dir / "summary_map.svg").write_text("".join(svgs), encoding="utf-8")
    (sweep_dir / "summary_distributions.svg").write_text(svgs[-1], encoding="utf-8")
    row = dict(zip(COLUMNS, ["paper", "paper", "positioning", "1"] + ["1e-3"] * (len(COLUMNS) - 5) + ["ok"]))
    (compare_dir / "compare.csv").write_text(",".join(COLUMNS) + "\n" + ",".join(row.values()) + "\n",
                                             encoding="utf-8")
    (compare_dir / "summary.json").write_text(json.dumps({"seeds": 1, "summary": []}), encoding="utf-8")
    (compare_dir / "compare.svg").write_text("".join(svgs), encoding="utf-8")
    return sweep_dir, compare_dir


@pytest.fixture(scope="module")
def hostile_report(tmp_path_factory):
    """The report of hostile sweep and compare folders (payloads aimed at an address that is never served)."""
    from obsdesign.report.html import render_report

    tmp_path = tmp_path_factory.mktemp("hostile")
    svgs = _hostile_svgs("http://127.0.0.1:9")
    sweep_dir, compare_dir = _hostile_folders(tmp_path, svgs)
    return svgs, render_report(od.load_preset("vcm"), sweep_dir=sweep_dir, compare_dir=compare_dir)


@pytest.mark.slow
def test_rendered_report_holds_no_markup_from_the_folders(hostile_report):
    """Review 2026-12-01 rep-meta-raw, rep-meta-fo, rep-script-uc, rep-breakout: --compare inlined compare.svg."""
    svgs, html = hostile_report
    for svg in svgs:
        assert svg not in html
    tags = [t.lower() for t in re.findall(r"<\s*(script|meta|base|form|iframe|object|embed|link)\b", html, re.I)]
    assert tags == ["meta", "meta", "script"]  # charset, the policy, the explorer: nothing else, in any case
    assert html.lower().count("http-equiv") == 1 and "refresh" not in html.lower()
    assert "127.0.0.1:9" not in html  # every payload is inside a base64 data: address
    images = re.findall(r'<img src="([^"]*)"', html)
    assert len(images) == 3 and all(src.startswith("data:image/svg+xml;base64,") for src in images)
    assert base64.b64decode(images[2].split(",", 1)[1]).decode("utf-8") == "".join(svgs)  # compare.svg, as is
    policy = re.search(r'http-equiv="Content-Security-Policy" content="([^"]*)"', html).group(1)
    for directive in ("default-src 'none'", "base-uri 'none'", "form-action 'none'", "img-src data:"):
        assert directive in policy


@pytest.mark.parametrize("extra, element", [
    ("<SCRIPT>x()</SCRIPT>", "script"),
    ("</figure><ScRiPt>x()</ScRiPt><svg>", "script"),
    ('<meta http-equiv="refresh" content="0;url=http://127.0.0.1:9/x">', "meta"),
    ("< META http-equiv=refresh content=0>", "meta"),
    ('<base href="http://127.0.0.1:9/">', "base"),
    ('<form action="http://127.0.0.1:9/"><input name=q></form>', "form"),
])
def test_page_guard_refuses_an_extra_element_by_name(extra, element):
    from obsdesign.cli._errors import exit_status
    from obsdesign.report.html import _CSP_MARK, ReportContentError, _with_csp

    page = (f'<html><head><meta charset="utf-8"><meta http-equiv="Content-Security-Policy" content="{_CSP_MARK}">'
            f'</head><body><h2 id="comparison">x</h2><figure>{extra}</figure><script>var a = 1;</script></body></html>')
    assert "sha256-" in _with_csp(page.replace(extra, ""))
    with pytest.raises(ReportContentError, match=f"extra <{element}> element .* in section 'comparison'") as info:
        _with_csp(page)
    assert exit_status(info.value) == 2


@pytest.mark.slow
@pytest.mark.parametrize("folder_kind", ["sweep", "compare"])
@pytest.mark.skipif(not (CHROMIUM and DRIVER), reason="headless Chromium not installed")
def test_report_with_hostile_folder_figures_runs_and_fetches_nothing(tmp_path, folder_kind):
    pytest.importorskip("selenium")
    from obsdesign.report.html import render_report

    with _Recorder() as server:
        svgs = _hostile_svgs(server.base)
        sweep_dir, compare_dir = _hostile_folders(tmp_path, svgs)
        folders = {"sweep_dir": sweep_dir} if folder_kind == "sweep" else {"compare_dir": compare_dir}
        html = render_report(od.load_preset("vcm"), **folders)
        for svg in svgs:
            assert svg not in html
        report = tmp_path / "report.html"
        report.write_text(html, encoding="utf-8")
        # Defense in depth: the same report with the payloads pasted raw into its body (as if an
        # escaping bug let them through) is held by the Content-Security-Policy alone. A policy
        # cannot stop a navigation (<meta http-equiv="refresh">), so that payload is left out here;
        # only the base64 embedding (and the page guard) keeps it out.
        raw = tmp_path / "raw.html"
        pasted = "".join(svg for svg in svgs if "refresh" not in svg)
        raw.write_text(html.replace("</body>", pasted + f'<img src="{server.base}/raw">'
                                    f"<script>{MARK.format(id='raw')}</script></body>"), encoding="utf-8")
        # Control: without the policy the detector sees both the script and the fetch.
        control = tmp_path / "control.html"
        control.write_text(f'<html><body><img src="{server.base}/control"><script>{MARK.format(id="control")}'
                           "</script></body></html>", encoding="utf-8")
        driver = _chrome()
        try:
            assert _visit(driver, control, server) == ("control", ["/control"])
            server.paths.clear()
            assert _visit(driver, report, server) == (None, [])
            assert driver.current_url == report.as_uri()  # no meta refresh navigated away
            assert driver.execute_script("return document.getElementById('verdict').textContent") == "stable"
            assert _visit(driver, raw, server) == (None, [])
            assert driver.execute_script("return document.getElementById('verdict').textContent") == "stable"
        finally:
            driver.quit()


def test_report_refuses_a_sweep_folder_with_a_figure_that_is_not_svg(tmp_path):
    from obsdesign.report.html import _sweep_section

    for name, text in (("summary.json", "{"), ("summary.json", "[]"), ("summary_map.svg", "<html>")):
        folder = tmp_path / name / str(len(text))
        folder.mkdir(parents=True)
        (folder / "summary.json").write_text(json.dumps({"runs": 0, "ok": 0, "diverged": 0, "failed": 0,
                                                         "resumed_runs": 0, "wall_s": 0.0, "metric": "rms_error",
                                                         "best": {}}), encoding="utf-8")
        for svg in ("summary_map.svg", "summary_distributions.svg"):
            (folder / svg).write_text("<svg></svg>", encoding="utf-8")
        (folder / name).write_text(text, encoding="utf-8")
        with pytest.raises(ValueError, match=str(folder / name).replace("\\", "\\\\")):
            _sweep_section(folder)


@pytest.mark.parametrize("kind, name, content", [
    ("sweep", "summary.json", b"[" * 100_000 + b"]" * 100_000),  # fs-deep: was a RecursionError (exit 3)
    ("compare", "summary.json", b"[" * 100_000 + b"]" * 100_000),
    ("compare", "compare.svg", b"<html>no figure</html>"),  # fs-c-nosvg: was 'substring not found'
    ("compare", "compare.svg", b"\xff\xfe<svg>"[:2] + b"x" * 5000),  # fs-c-latin
    ("compare", "compare.csv", b"plant,\xff\n"),  # fs-c-csvbin: was a bare UnicodeDecodeError
    ("compare", "summary.json", b"{'summary': []}"),  # fs-c-json: was a bare JSONDecodeError
    ("compare", "compare.csv", b"root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1::/:/bin/sh\n"),  # fs-c-passwd
])
def test_report_folder_errors_name_their_file(tmp_path, kind, name, content):
    from obsdesign.report.comparison_section import comparison_section
    from obsdesign.report.html import _sweep_section

    sweep_dir, compare_dir = _hostile_folders(tmp_path, ['<svg xmlns="http://www.w3.org/2000/svg"></svg>'])
    folder = sweep_dir if kind == "sweep" else compare_dir
    (folder / name).write_bytes(content)
    read = _sweep_section if kind == "sweep" else comparison_section
    with pytest.raises(ValueError, match=f"^{kind}: '{re.escape(str(folder / name))}'"):
        read(folder)


def test_report_cli_refuses_a_deeply_nested_summary_in_one_line(tmp_path, capsys):
    from obsdesign.cli import main

    sweep_dir, _ = _hostile_folders(tmp_path, ['<svg xmlns="http://www.w3.org/2000/svg"></svg>'])
    (sweep_dir / "summary.json").write_bytes(b"[" * 100_000 + b"]" * 100_000)
    assert main(["report", "--quiet", "--sweep", str(sweep_dir), "-o", str(tmp_path / "r.html")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"obsdesign: error: sweep: {str(sweep_dir / 'summary.json')!r} is not valid UTF-8 JSON (nested too deeply)"]
    assert not (tmp_path / "r.html").exists()
