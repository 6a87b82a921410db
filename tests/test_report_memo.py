"""The report's kept figures and studies (issue 37): a kept value is the bytes and numbers of a fresh computation.

Each test computes the value with the memo off (``OBSDESIGN_CACHE=off``: the fresh computation), then
fills the memo and reads it back, and compares the three; a figure read back that is not matplotlib's
SVG (a script, an event handler, an outside link) is refused and drawn again.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import obsdesign as od
from obsdesign import _memo
from obsdesign.report import figures, kept
from obsdesign.report.markup import is_figure_svg


@pytest.fixture
def memo_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("OBSDESIGN_CACHE_DIR", str(tmp_path / "memo"))
    monkeypatch.delenv("OBSDESIGN_CACHE", raising=False)
    return tmp_path / "memo"


def _three(monkeypatch, compute):
    """``compute()`` with the memo off, then filling it, then read back (counting the fills' entries)."""
    monkeypatch.setenv("OBSDESIGN_CACHE", "off")
    fresh = compute()
    monkeypatch.delenv("OBSDESIGN_CACHE")
    return fresh, compute(), compute()


def _counted(make, calls):
    def wrapped(*args, **kwargs):
        calls.append(1)
        return make(*args, **kwargs)

    wrapped.__qualname__ = make.__qualname__
    wrapped.__module__ = make.__module__
    return wrapped


@pytest.mark.parametrize("which", ["eigen", "bode", "loop"])
def test_a_kept_figure_is_the_drawn_figure_byte_for_byte(which, memo_dir, monkeypatch):
    from obsdesign.design import check_stability, pid_from_config
    from obsdesign.design.loop import loop_analysis
    from obsdesign.report import page

    cfg = od.load_preset("vcm")
    make, args, kwargs = {
        "eigen": lambda: (page._eigen_figure, (check_stability(cfg).design,), {}),
        "bode": lambda: (page._bode_figure, ([("|S|", pid_from_config(cfg), "S")],), {"ylabel": "|S| [m/V]"}),
        "loop": lambda: (page._loop_view_figure, (loop_analysis(cfg),), {}),
    }[which]()
    calls: list = []
    counted = _counted(make, calls)
    fresh, filled, read = _three(monkeypatch, lambda: kept.kept_svg(counted, *args, units=cfg.units, **kwargs))
    assert fresh == figures.inline_svg(make(*args, **kwargs), cfg.units)  # the page's drawing, independently
    assert fresh == filled == read and len(calls) == 2  # the third came from disk
    assert is_figure_svg(read)


def test_the_key_sees_the_data_the_units_and_the_function_but_not_a_wall_time():
    cfg = od.load_preset("vcm")
    y = {"x": np.arange(4.0), "sim_wall_s": 0.1}
    key = kept.figure_key(np.sum, (y,), {}, cfg.units)
    assert kept.figure_key(np.sum, ({"x": np.arange(4.0), "sim_wall_s": 0.2},), {}, cfg.units) == key
    assert kept.figure_key(np.sum, ({"x": np.arange(4.0) + 1e-300, "sim_wall_s": 0.1},), {}, cfg.units) != key
    assert kept.figure_key(np.sum, (y,), {}, None) != key
    assert kept.figure_key(np.max, (y,), {}, cfg.units) != key
    with pytest.raises(TypeError, match="module-level"):
        kept.figure_key(lambda: None, (), {})
    with pytest.raises(TypeError, match="cannot digest"):
        kept.figure_key(np.sum, (iter([1]),), {})


def test_the_key_sees_the_matplotlibrc(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    keys = [kept.figure_key(np.sum, (1.0,), {})]
    (tmp_path / "matplotlibrc").write_text("lines.linewidth: 3\n")
    keys.append(kept.figure_key(np.sum, (1.0,), {}))
    monkeypatch.setenv("MPLCONFIGDIR", str(tmp_path / "elsewhere"))
    keys.append(kept.figure_key(np.sum, (1.0,), {}))
    assert len({k[2] for k in keys}) == 3 and len({k[:2] for k in keys}) == 1


def test_a_changed_rc_is_drawn_not_read(memo_dir):
    import matplotlib

    from obsdesign.design import check_stability
    from obsdesign.report import page

    cfg = od.load_preset("vcm")
    design = check_stability(cfg).design
    plain = kept.kept_svg(page._eigen_figure, design, units=cfg.units)  # kept
    with matplotlib.rc_context({"lines.linewidth": 3.0}):
        wide = kept.kept_svg(page._eigen_figure, design, units=cfg.units)
        assert wide == figures.inline_svg(page._eigen_figure(design), cfg.units)
    assert wide != plain and kept.kept_svg(page._eigen_figure, design, units=cfg.units) == plain


@pytest.mark.parametrize("bad", [
    '<svg><script>alert(1)</script></svg>',
    '<svg><g onload="alert(1)"></g></svg>',
    '<svg><g ONCLICK="x"></g></svg>',
    '<svg><foreignObject><div/></foreignObject></svg>',
    '<svg><use xlink:href="https://example.com/a.svg#x"/></svg>',
    '<svg><use href="javascript:alert(1)"/></svg>',
    '<svg><style>@import "https://example.com/x.css";</style></svg>',
    '<svg><rect style="fill: url(https://example.com/p)"/></svg>',
    '<svg><![CDATA[x]]></svg>',
    '<svg><image xlink:href="data:image/svg+xml;base64,AAAA"/></svg>',
    '<svg></svg><script>x</script>',
    '<svg><g onload=alert(1)></g></svg>',           # unquoted: an HTML parser reads a handler
    '<svg><g/onload="alert(1)"></g></svg>',         # slash-led: likewise
    '<svg><g>unclosed</svg>',
    "<p>not a figure</p>",
    7,
])
def test_a_kept_figure_that_is_not_matplotlibs_svg_is_refused(bad, memo_dir):
    assert not is_figure_svg(bad)
    cfg = od.load_preset("vcm")
    from obsdesign.design import check_stability
    from obsdesign.report import page

    design = check_stability(cfg).design
    key = kept.figure_key(page._eigen_figure, (design,), {}, cfg.units)
    _memo.memo("report_figure", key, lambda: bad)  # signed with the folder's secret: only the schema can refuse it
    with pytest.warns(_memo.MemoWarning, match="does not have the shape"):
        svg = kept.kept_svg(page._eigen_figure, design, units=cfg.units)
    assert svg == figures.inline_svg(page._eigen_figure(design), cfg.units)


def test_kept_circle_rows_equal_a_fresh_run(memo_dir, monkeypatch):
    from obsdesign.report.circle_section import feed_runs

    cfg = od.load_preset("vcm")
    # 20 mm/s (the shortest contour) as a feed that is not the picture's: its rows are kept
    fresh, filled, read = _three(monkeypatch, lambda: feed_runs(cfg, 2e-2, feeds=(2e-2,), figure_feed=6.32e-3))
    assert isinstance(fresh, list) and len(fresh) >= 4
    assert fresh == filled == read and all("result" not in r for r in read)
    assert len(list((memo_dir / "report_circle_feed").iterdir())) == 1
    # another config is another key (a run differs)
    other = feed_runs(cfg.override(rho=cfg.observer.rho * 1.5), 2e-2, feeds=(2e-2,), figure_feed=6.32e-3)
    assert len(list((memo_dir / "report_circle_feed").iterdir())) == 2
    assert [r["glitch_peak"] for r in other] != [r["glitch_peak"] for r in fresh]


def test_the_picture_feed_is_run_with_its_traces(memo_dir):
    from obsdesign.report.circle_section import feed_runs

    rows = feed_runs(od.load_preset("vcm"), 2e-2, feeds=(2e-2,), figure_feed=2e-2)
    assert all("result" in r for r in rows) and not (memo_dir / "report_circle_feed").exists()


@pytest.mark.slow
def test_the_kept_convergence_part_is_the_studys(memo_dir, monkeypatch):
    from obsdesign import studies
    from obsdesign.report.figures import inline_svg
    from obsdesign.report.html import convergence_part
    from obsdesign.report.study_figures import convergence_figure

    filled, read = convergence_part(), convergence_part()  # the fill is the fresh computation
    conv = studies.convergence_study(seeds=3)  # and once more, independently of the memo
    assert filled == read == (list(conv.claims), inline_svg(convergence_figure(conv)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert is_figure_svg(read[1])
