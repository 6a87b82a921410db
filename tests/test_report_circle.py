"""The report's circle (ballbar) test: its numbers are those of an independent ``circle_modes`` call,
its picture is inline, a feed the axis cannot drive is a note, and ``--no-circle`` leaves it out."""

from __future__ import annotations

import re

import numpy as np
import pytest

import obsdesign as od
from obsdesign.cli import main
from obsdesign.report import html as report_html
from obsdesign.report.circle_section import FEEDS, RADIUS, circle_section
from obsdesign.sim.circle import circle_modes

NOISY = od.load_preset("vcm").override(noise_rms=2e-7)


def _spread(rows, mode, feed):
    """Mean, min and max of the glitch peak of one mode and feed, computed here."""
    g = np.array([r["glitch_peak"] for r in rows if r["mode"] == mode and r["feed"] == feed])
    return g.mean(), g.min(), g.max(), g.size


@pytest.mark.slow  # the circle runs twice, two feeds by two seeds by two directions (8 s)
def test_section_numbers_are_those_of_circle_modes():
    feeds, seeds = (6.32e-3, 2e-2), (0, 1)
    sec = circle_section(NOISY, feeds=feeds, seeds=seeds)
    rows = circle_modes(NOISY, feeds=feeds, directions=("ccw", "cw"), seeds=seeds, radius=RADIUS)
    assert sec["seeds"] == seeds and sec["noisy"] and not sec["notes"]
    assert [r["mode"] for r in sec["rows"]] == list(dict.fromkeys(r["mode"] for r in rows))
    for row in sec["rows"]:
        for feed, cell in zip(feeds, row["cells"]):
            mean, low, high, n = _spread(rows, row["mode"], feed)
            assert n == 4  # two seeds, two directions
            assert (cell["mean"], cell["min"], cell["max"]) == pytest.approx((mean, low, high), rel=1e-12)
            assert low < high  # with noise the runs differ
    # the picture: one polar panel per mode, at the figure feed, each titled with its run's peak
    fig = sec["figure"]
    assert len(fig.axes) == len(sec["rows"])
    ccw0 = {r["mode"]: r["glitch_peak"] for r in rows if r["feed"] == 2e-2 and r["direction"] == "ccw"
            and r["seed"] == 0}
    for ax, mode in zip(fig.axes, ccw0):
        assert ax.get_title().startswith(f"{mode}\npeak {ccw0[mode] * 1e6:.1f} um")
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_without_random_noise_one_seed_runs():
    sec = circle_section(od.load_preset("vcm"), feeds=(2e-2,), seeds=(0, 1, 2))
    assert sec["seeds"] == (0,) and not sec["noisy"]
    assert sec["figure"] is not None


def test_a_feed_the_axis_cannot_drive_is_a_note():
    sec = circle_section(od.load_preset("vcm"), feeds=(2e-2, 5.0), figure_feed=5.0)
    assert sec["figure"] is None and len(sec["notes"]) == 1
    assert sec["notes"][0].startswith("5000 mm/s: feed: expected a path velocity the axis can drive")
    assert all(row["cells"][0] is not None and row["cells"][1] is None for row in sec["rows"])


def _cells(html):
    """The circle table of a rendered report: mode -> [(mean, min, max)] in um."""
    part = html[html.index('<h3 id="circle">'):]
    part = part[:part.index("</table>")]
    out = {}
    for mode, cells in re.findall(r"<tr><td>([a-z]+)</td>(.*?)</tr>", part):
        out[mode] = [tuple(float(v) for v in m) for m in re.findall(r"<td>(\S+) \((\S+) to (\S+)\)</td>", cells)]
    return out, part


@pytest.mark.slow
def test_report_shows_the_circle_test_of_the_axis(tmp_path):
    cfg = od.load_preset("vcm")
    html = report_html.render_report(cfg)
    cells, part = _cells(html)
    rows = circle_modes(cfg, feeds=FEEDS, directions=("ccw", "cw"), seeds=(0,), radius=RADIUS)
    assert list(cells) == list(dict.fromkeys(r["mode"] for r in rows))
    for mode, shown in cells.items():
        assert len(shown) == len(FEEDS)
        for feed, got in zip(FEEDS, shown):
            mean, low, high, _ = _spread(rows, mode, feed)
            assert got == pytest.approx((mean * 1e6, low * 1e6, high * 1e6), rel=6e-4)  # 4 significant digits
    assert "noise seeds 0" in part and "ccw and cw" in part
    section = html[html.index('<h3 id="circle">'):]
    section = section[:section.index("<h2")]
    assert section.count("<svg") == 1 and "Ballbar picture at 20 mm/s" in section  # inline, as the other figures
    assert "<img" not in html and "<script src" not in html  # still self-contained


@pytest.mark.slow
def test_no_circle_flag_leaves_the_section_out(tmp_path, monkeypatch):
    def forbidden(*args, **kwargs):
        raise AssertionError("the circle test ran with --no-circle")

    from obsdesign.report import page
    from obsdesign.sim import circle as sim_circle

    for module, name in ((page, "circle_section"), (page, "feed_runs"), (sim_circle, "circle_modes")):
        monkeypatch.setattr(module, name, forbidden)
    out = tmp_path / "r.html"
    assert main(["report", "--no-circle", "--quiet", "-o", str(out)]) == 0
    assert 'id="circle"' not in out.read_text()
