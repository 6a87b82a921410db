"""The HTML report: self-contained, escaped, and its explorer works in a real browser."""

import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import obsdesign as od
from obsdesign.cli import main
from obsdesign.report.html import render_report, write_report


@pytest.fixture(scope="module")
def report_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("report") / "report.html"
    write_report(od.load_preset("vcm"), path)
    return path


@pytest.mark.slow
def test_report_is_self_contained(report_file):
    html = report_file.read_text()
    assert "<script src" not in html and "<link" not in html and "<img" not in html
    refs = re.findall(r'(?:src|href)="([^"]*)"', html)
    assert refs and all(r.startswith("#") for r in refs)  # only in-document references (SVG glyphs)
    urls = set(re.findall(r"https?://[^\s\"'<>]+", html))
    # XML namespace names only: identifiers, never fetched
    assert urls <= {"http://www.w3.org/1998/Math/MathML", "http://www.w3.org/2000/svg", "http://www.w3.org/1999/xlink"}


@pytest.mark.slow
def test_report_contents(report_file):
    html = report_file.read_text()
    assert html.count("<svg") >= 7  # eigenvalues, |S|, noise, convergence, experiments, loops, explorer
    assert html.count("<math") >= 20  # the derivation as MathML
    for needle in ("eq:3:3:7", "Proposition 1: L_1 &gt; -sigma/m", "PID gain kp", "reproduced", "function gains(m, sigma, kappa, rho)"):
        assert needle in html
    pid = od.pid_from_config(od.load_preset("vcm"))
    assert f"<td>{pid.kp:.4g}</td>" in html  # one number format: 4 significant digits
    assert not re.search(r"\d\.\d{4}e[+-]\d\d", html)  # no 5-digit mantissas such as 1.0000e-06
    for needle in ('<nav class="toc">', 'id="claims"', "Loop view of L = C H", "overshoot (step up, down)",
                   "partly reproduced", "consistent", 'class="bmatrix"'):
        assert needle in html


@pytest.mark.slow
def test_values_from_a_config_are_escaped():
    cfg = od.load_preset("table1").override(rho=1.5)
    import dataclasses

    evil = dataclasses.replace(cfg, name='<script>alert("x")</script>')
    html = render_report(evil, source_label="config <b>file</b>")
    assert '<script>alert("x")</script>' not in html
    assert "&lt;script&gt;alert(&#34;x&#34;)&lt;/script&gt;" in html and "config &lt;b&gt;file&lt;/b&gt;" in html


def test_report_cli_bad_output(tmp_path, capsys):
    assert main(["report", "-o", str(tmp_path / "missing" / "r.html"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "argument -o/--output: directory" in err[0]
    assert list(tmp_path.iterdir()) == []


CHROMIUM, DRIVER = shutil.which("chromium"), shutil.which("chromedriver")


def _browser():
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        return None
    if not (CHROMIUM and DRIVER):
        return None
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--host-resolver-rules=MAP * ~NOTFOUND", "--window-size=1280,900"):
        opts.add_argument(flag)
    return webdriver.Chrome(service=Service(DRIVER), options=opts)


@pytest.mark.slow
@pytest.mark.skipif(not (CHROMIUM and DRIVER) and os.environ.get("CI") != "true",
                    reason="headless Chromium not installed (CI installs it)")
def test_explorer_in_headless_chromium(report_file, tmp_path):
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    driver = _browser()
    assert driver is not None, "Chromium, chromedriver and selenium are required in CI"
    try:
        driver.get(report_file.as_uri())
        shot = Path(os.environ.get("OBSDESIGN_SCREENSHOT", tmp_path / "report.png"))
        driver.save_screenshot(str(shot))
        assert shot.stat().st_size > 10_000
        verdict = driver.find_element(By.ID, "verdict")
        slider = driver.find_element(By.ID, "s-rho")
        assert verdict.text == "stable"  # rho = 4
        driver.execute_script("arguments[0].scrollIntoView();", slider)
        slider.send_keys(Keys.HOME)  # drag to the minimum, rho = 0.5
        assert driver.find_element(By.ID, "o-rho").text.startswith("0.5")
        assert verdict.text == "unstable"
        for value, expected in (("1.02", "stable"), ("0.98", "unstable"), ("1.1", "stable")):
            driver.execute_script("arguments[0].value = arguments[1];"
                                  "arguments[0].dispatchEvent(new Event('input'));", slider, value)
            assert verdict.text == expected, value
        failing = [li.text for li in driver.find_elements(By.CSS_SELECTOR, "#verdicts li.fail")]
        assert failing == []
        slider.send_keys(Keys.HOME)
        failing = [li.text for li in driver.find_elements(By.CSS_SELECTOR, "#verdicts li.fail")]
        assert any("Proposition 1: L2 <" in t for t in failing)
        assert driver.get_log("browser") == [] if hasattr(driver, "get_log") else True
    finally:
        driver.quit()


@pytest.mark.slow
def test_report_includes_a_sweep_summary(tmp_path, capsys):
    sweep_dir = tmp_path / "sweep"
    assert main(["sweep", "--scenario", "constant", "--duration", "0.2", "--vary", "rho=1.5:3:2", "--workers", "1",
                 "--out", str(sweep_dir)]) == 0
    html = render_report(od.load_preset("vcm"), sweep_dir=sweep_dir)
    assert "Design sweep" in html and "2 runs: 2 ok, 0 diverged, 0 failed." in html
    assert html.count("<svg") >= 7 and html.count('<img src="data:image/svg+xml;base64,') == 2
    capsys.readouterr()
    assert main(["report", "--sweep", str(tmp_path), "-o", str(tmp_path / "r.html"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "sweep: expected a folder written by 'obsdesign sweep'" in err[0]
    assert not (tmp_path / "r.html").exists()


def test_identical_figures_are_identical_files(tmp_path):
    """Review L6: the summary SVGs of two identical sweeps differed (a date and random ids)."""
    import matplotlib.pyplot as plt

    from obsdesign.report.figures import save_figure

    for name in ("a.svg", "b.svg"):
        fig, ax = plt.subplots()
        ax.plot([0, 1, 2], [1, 3, 2], label="x")
        ax.legend()
        save_figure(fig, tmp_path / name)
    assert (tmp_path / "a.svg").read_bytes() == (tmp_path / "b.svg").read_bytes()
    assert b"<dc:date>" not in (tmp_path / "a.svg").read_bytes()


@pytest.mark.slow
# python-control notes that it computes these margins on a frequency grid ('frd'): expected here
@pytest.mark.filterwarnings("ignore:stability_margins.*frd:UserWarning")
def test_the_report_shows_the_sampled_loop_beside_the_continuous_one(tmp_path):
    """The loop view carries the sampled loop's margins (an independent python-control computation of
    the same discrete loop: c2d ZOH of the plant, the discrete filtered-derivative PID) and says which
    system each table is about."""
    import math
    import re

    import control as ct

    from obsdesign.cli import main
    from obsdesign.sampled import sampled_controller

    out = tmp_path / "r.html"
    assert main(["report", "--preset", "vcm", "-o", str(out)]) == 0
    page = out.read_text(encoding="utf-8")
    assert "continuous idealisation" in page and "ZOH plant, discrete PID with derivative filter N=10" in page
    cfg = od.load_preset("vcm")
    c = sampled_controller(cfg, controller="pid")
    dt, a = cfg.observer.dt, c.alpha_d
    z = ct.tf([1.0, 0.0], [1.0], dt)
    C = c.kp + c.ki * dt * z / (z - 1) + c.kd * (1 - a) / dt * (z - 1) / (z - a)
    H = ct.c2d(ct.tf([cfg.phi], [cfg.pid.tau, 1.0, 0.0]), dt, "zoh")
    pm = ct.stability_margins(C * H)[1]
    i = page.index("Below, the loop that runs")
    cells = re.findall(r"<td>([^<]*)</td>", page[i:i + 3000])
    shown = float(cells[1].split()[0])  # phase margin [deg], 4 significant digits
    assert math.isclose(shown, pm, rel_tol=1e-3), (shown, pm)


HELPER_CHECK = """
import re, sys, threading
import obsdesign as od
from obsdesign.report.html import render_report
strip = re.compile(r" in [0-9.]+ s\\.</p>")
assert threading.active_count() == 1
serial = strip.sub("", render_report(od.load_preset("vcm"), workers=1))
assert threading.active_count() == 1  # no tqdm monitor thread without a bar: the next report can fork
import concurrent.futures.process as p
forked = []
orig = p.ProcessPoolExecutor.__init__
p.ProcessPoolExecutor.__init__ = lambda self, *a, **k: (forked.append(1), orig(self, *a, **k))[1]
parallel = strip.sub("", render_report(od.load_preset("vcm"), workers=2))
print(len(forked), serial == parallel, len(serial))
"""


@pytest.mark.slow
def test_the_page_is_the_same_with_and_without_the_helper_process():
    """workers=2 forks a helper for the Table 1 study and the circle's two slowest feeds; the page it gives
    is the one computed in one process, byte for byte but for the render time (in a fresh process:
    a thread left by another test would keep the helper from forking)."""
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", HELPER_CHECK], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    forked, same, size = out.stdout.split()
    assert forked == "1" and same == "True" and int(size) > 100_000


def test_workers_is_checked():
    with pytest.raises(ValueError, match="workers: expected an integer >= 1, found 0"):
        render_report(od.load_preset("vcm"), workers=0)
    with pytest.raises(ValueError, match="workers: expected an integer >= 1, found 1.5"):
        render_report(od.load_preset("vcm"), workers=1.5)


def test_envelope_keeps_each_columns_extremes_in_time_order():
    import numpy as np

    from obsdesign.report.figures import envelope

    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(0.5, 1.5, 100_003))
    y = np.cumsum(rng.standard_normal(t.size))
    te, ye = envelope(t, y, columns=500)
    k = -(-t.size // 500)
    for c in range(0, t.size // k, 37):  # every column's extremes, from the series itself
        sl = slice(c * k, (c + 1) * k)
        assert sorted(ye[2 * c:2 * c + 2]) == [y[sl].min(), y[sl].max()]
    idx = np.searchsorted(t, te)
    assert np.array_equal(t[idx], te) and np.array_equal(y[idx], ye)  # samples of the input, in time order
    assert np.all(np.diff(idx) >= 0)
    short = np.arange(10.0)
    assert envelope(short, short)[1] is not None and len(envelope(short, short)[0]) == 10
    y[5] = np.nan  # a diverged run is drawn as it is
    assert len(envelope(t, y, columns=500)[0]) == t.size


@pytest.mark.slow  # five closed-loop runs (5 s); the report's page test covers the same reuse end to end
def test_the_friction_loops_reuse_the_experiments_run_exactly():
    """The report draws the friction loops from the experiments' positioning run with the observer: the
    study of that run equals the study that simulates it again, array for array; another config's
    experiments are refused."""
    from obsdesign import studies

    cfg = od.load_preset("vcm")
    exp = studies.experiments_study(cfg)
    reused, fresh = studies.friction_loops_study(cfg, experiments=exp), studies.friction_loops_study(cfg)
    assert reused.claims == fresh.claims
    for name in ("x", "estimate", "model_f", "model_fc", "true_f"):
        assert np.array_equal(getattr(reused, name), getattr(fresh, name)), name
    import dataclasses

    key = ("positioning", "pid+observer")
    other = dataclasses.replace(exp, runs={**exp.runs, key: dataclasses.replace(exp.runs[key],
                                                                                config=cfg.override(rho=3.0))})
    with pytest.raises(ValueError, match="experiments: expected the experiments study of the config 'vcm'"):
        studies.friction_loops_study(cfg, experiments=other)


# -- the page as a document (issue 39): tables that cannot be misread, unique ids, legible figures, print --

#: Run in the page: table cells holding a number (with its unit) or one word that render on more than one
#: line, ids held by more than one element, figure texts below the smallest size on screen [CSS px], and the
#: inline figures whose text is drawn as outlines (its size cannot be checked).
PAGE_CHECK = r"""
const minPx = arguments[0], out = {wrapped: [], duplicate: [], small: [], outlined: 0, cells: 0, texts: 0};
const word = /^(\S+|[-+]?\d[\d.,eE+-]*\s\S+)$/;
document.querySelectorAll("td, th").forEach(function (cell) {
  const text = cell.textContent.trim();
  if (!text || !word.test(text) || cell.querySelector("math")) return;  // MathML is laid out in two dimensions
  out.cells++;
  const range = document.createRange(); range.selectNodeContents(cell);
  const tops = new Set();
  Array.from(range.getClientRects()).forEach(function (r) { if (r.width > 0) tops.add(Math.round(r.top)); });
  if (tops.size > 1) out.wrapped.push(text);
});
const seen = {};
document.querySelectorAll("[id]").forEach(function (el) { seen[el.id] = (seen[el.id] || 0) + 1; });
Object.keys(seen).forEach(function (id) { if (seen[id] > 1) out.duplicate.push(id); });
document.querySelectorAll("svg").forEach(function (svg) {
  if (svg.querySelector("g[id$='figure_1']") && !svg.querySelector("text")) out.outlined++;
});
document.querySelectorAll("svg text").forEach(function (t) {
  const m = t.getScreenCTM(); if (!m) return;
  const scale = Math.sqrt(m.a * m.a + m.b * m.b);
  const parts = t.querySelectorAll("tspan").length ? t.querySelectorAll("tspan") : [t];
  parts.forEach(function (p) {
    if (!p.textContent.trim()) return;
    out.texts++;
    const px = parseFloat(getComputedStyle(p).fontSize) * scale;
    if (px < minPx) out.small.push(p.textContent.trim().slice(0, 40) + ": " + px.toFixed(1) + " px");
  });
});
return out;
"""


def check_page(path: Path, min_px: float = 9.95) -> dict:
    """:data:`PAGE_CHECK` of a page opened in headless Chromium at 1400 x 900 (the width the issue was seen at)."""
    driver = _browser()
    assert driver is not None, "Chromium, chromedriver and selenium are required in CI"
    try:
        driver.set_window_size(1400, 900)
        driver.get(path.as_uri())
        return driver.execute_script(PAGE_CHECK, min_px)
    finally:
        driver.quit()


def print_pdf(path: Path, out: Path) -> Path:
    """The page printed to PDF by headless Chromium (``--print-to-pdf``, no browser header or footer)."""
    import subprocess
    import tempfile

    with tempfile.TemporaryDirectory() as profile:
        subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                        "--disable-component-update", "--disable-sync", "--no-first-run", f"--user-data-dir={profile}",
                        "--no-pdf-header-footer", f"--print-to-pdf={out}", path.as_uri()],
                       capture_output=True, timeout=300, check=True)
    return out


def pdf_pages(pdf: Path) -> list[str]:
    """The text of each page (poppler's ``pdftotext -layout``)."""
    import subprocess

    text = subprocess.run(["pdftotext", "-layout", str(pdf), "-"], capture_output=True, text=True, check=True).stdout
    return text.split("\f")[:-1]


PDFTOTEXT = shutil.which("pdftotext")
needs_browser = pytest.mark.skipif(not (CHROMIUM and DRIVER) and os.environ.get("CI") != "true",
                                   reason="headless Chromium not installed (CI installs it)")
needs_poppler = pytest.mark.skipif(not PDFTOTEXT and os.environ.get("CI") != "true",
                                   reason="poppler-utils (pdftotext) not installed (CI installs it)")


@pytest.fixture(scope="module")
def axis_report(tmp_path_factory):
    """The report of an identified axis (the shipped example log: identify -o, then report --config) with its
    data section and a small comparison folder (compare --out, then report --compare)."""
    folder = tmp_path_factory.mktemp("axis")
    log = folder / "log.csv"
    shutil.copy(od.datasets.example_log(), log)
    columns = ["--position", "x", "--input", "u", "--time", "t"]
    assert main(["identify", str(log), *columns, "-o", str(folder / "axis.toml")]) == 0
    assert main(["compare", "--config", str(folder / "axis.toml"), "--plants", "paper,lugre", "--estimators",
                 "paper,eso", "--scenarios", "positioning", "--seeds", "1", "--workers", "1",
                 "--out", str(folder / "cmp")]) == 0
    out = folder / "axis.html"
    assert main(["report", "--config", str(folder / "axis.toml"), "--data", str(log), *columns,
                 "--compare", str(folder / "cmp"), "--no-circle", "-o", str(out), "--quiet"]) == 0
    return out


def test_figures_share_no_id_and_keep_their_bytes():
    """Two inline figures carry no common id (matplotlib numbers figure_1, axes_1, ... in every figure and its
    marker and clip-path ids repeat), every reference points at an id of its own figure, and the same figure
    gives the same bytes."""
    import matplotlib.pyplot as plt

    from obsdesign.report.figures import inline_svg

    def fig(n):
        f, ax = plt.subplots()
        ax.plot([0, 1, 2], [1, n, 2], "o-", label="x")
        ax.legend()
        return f

    a, a_again, b = inline_svg(fig(3)), inline_svg(fig(3)), inline_svg(fig(4))
    assert a == a_again
    ids = [re.findall(r'\bid="([^"]+)"', s) for s in (a, b)]
    assert ids[0] and ids[1] and not set(ids[0]) & set(ids[1]) and len(set(ids[0])) == len(ids[0])
    for svg, own in zip((a, b), ids):
        refs = re.findall(r'href="#([^"]+)"', svg) + re.findall(r"url\(#([^)]+)\)", svg)
        assert refs and set(refs) <= set(own)


def test_inline_figures_are_legible_at_the_page_width():
    """A 15 in figure with 5 pt legend text and a log axis: drawn at most the page's 1050 px wide, every
    text (an exponent of a log tick label included) at least 10 px on screen, the legend below the axes."""
    import matplotlib.pyplot as plt

    from obsdesign.report.figures import MIN_TEXT_PX, PAGE_WIDTH_PX, inline_svg

    fig, ax = plt.subplots(figsize=(15, 5))
    ax.loglog([1, 10, 100], [1, 100, 10], label="a curve with a long label")
    ax.legend(fontsize=5, loc="center")
    ax.set_title("title", fontsize=4)
    svg = inline_svg(fig)
    width_pt = float(re.search(r'<svg[^>]*\bwidth="([0-9.]+)pt"', svg).group(1))
    shown_px = min(width_pt * 96 / 72, PAGE_WIDTH_PX)
    scale = shown_px / (width_pt * 96 / 72)  # the page draws the SVG at its width, at most the column's
    sizes = [float(s) for s in re.findall(r"font-size: ([0-9.]+)px", svg)]  # user units: 1 pt = 4/3 CSS px
    assert width_pt * 96 / 72 <= PAGE_WIDTH_PX + 0.5 and sizes
    assert min(sizes) * 96 / 72 * scale >= MIN_TEXT_PX - 1e-6, min(sizes)
    assert "<text" in svg and "DejaVuSans-" not in svg  # the text is text, not glyph outlines


def test_css_string_keeps_a_name_inside_its_string():
    from obsdesign.report.page import css_string

    for evil in ('x"; } body { display: none } /*', "a</style><script>alert(1)</script>", "line\nbreak \\ end"):
        text = css_string(evil)
        assert re.fullmatch(r"(?:[A-Za-z0-9]|\\[0-9a-f]{6})*", text), text
        decoded = re.sub(r"\\([0-9a-f]{6})", lambda m: chr(int(m.group(1), 16)), text)
        assert decoded == evil


@pytest.mark.slow
@needs_browser
def test_the_page_cannot_be_misread_in_chromium(report_file, axis_report):
    """In headless Chromium at 1400 px: no table cell holding a number or one word breaks over two lines,
    no two elements share an id, every figure text is at least 10 px on screen (the vcm report and the report
    of an identified axis with its data and comparison sections). On the page before issue 39 this found
    36 broken cells (kp "42 / 9"), 441 repeated ids and figure text as outlines."""
    for page in (report_file, axis_report):
        found = check_page(page)
        assert found["cells"] > 50 and found["texts"] > 200, found  # the check saw the tables and the figures
        assert found["wrapped"] == [], (page.name, found["wrapped"])
        assert found["duplicate"] == [], (page.name, found["duplicate"][:20])
        assert found["small"] == [] and found["outlined"] == 0, (page.name, found["small"][:20])


@pytest.mark.slow
@needs_browser
@needs_poppler
def test_the_printed_report_reads_page_by_page(report_file, tmp_path):
    """Printed to PDF by headless Chromium: the first page opens the report, every page carries its number and
    the provenance line, no control of the explorer is printed (its values are), the PID table's header and
    values share a page, and no page ends on a section heading."""
    pdf = print_pdf(report_file, tmp_path / "report.pdf")
    pages = pdf_pages(pdf)
    n = len(pages)
    assert 6 <= n <= 16, n  # 18 pages before the print stylesheet
    first = " ".join(pages[0].split())
    assert first.startswith("Friction observer design report") and "Verdict: every stability condition holds" in first
    assert "1. Parameters" in first
    for i, page in enumerate(pages, start=1):
        assert f"page {i} of {n}" in page, i
        assert "design report of vcm (preset vcm)" in " ".join(page.split()), i
        body = [line for line in page.splitlines() if line.strip() and "design report of" not in line]
        assert not re.match(r"\s*\d+\. [A-Z]", body[-1]), (i, body[-1])  # a heading left at the foot of a page
    text = "\f".join(pages)
    assert "reset to the config" not in text  # the explorer's button
    explorer = next((p for p in pages if "Stability explorer" in p), "")
    assert explorer, [p[:300] for p in pages]
    assert re.search(r"rho\s+4\.000", explorer) and re.search(r"kappa \[N/m\]\s+8000", explorer)  # slider values
    raw = pdf.read_bytes()
    assert b"/AcroForm" not in raw and b"/Widget" not in raw  # no form field
    pid = od.pid_from_config(od.load_preset("vcm"))
    header = next((p for p in pages if "T_I [s]" in p), "")
    assert f"{pid.kp:.4g}" in header and f"{pid.ki:.4g}" in header
