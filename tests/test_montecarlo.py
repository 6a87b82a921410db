"""The streamed Monte-Carlo study: its statistics against an exact computation, resume, worst cases."""

import concurrent.futures
import json
import math
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from scipy.stats import binomtest

import obsdesign as od
from obsdesign.cli import main
from obsdesign.sweeps import montecarlo as mc
from obsdesign.sweeps.plan import make_plan, plan_runs
from obsdesign.sweeps.pool import Executor
from obsdesign.sweeps.sketch import Moments, QuantileSketch

CFG = od.load_preset("vcm")
# m drawn partly negative (an invalid mass: the run fails), rho partly below 1 (some runs diverge); the
# constant force for 0.5 s: quick. Seed 4 gives 20 ok, 2 diverged, 1 failed.
STUDY = dict(uncertain={"Cf": (0.2, 0.5), "m": (-0.2, 0.8), "rho": (0.3, 2.0)}, samples=23, seed=4, duration=0.5,
             batch=5)
CRITERIA = ["rms_error<=0.009", "max_error<=0.017"]


# --- the sketch and the moments against numpy --------------------------------------------------------------

@pytest.mark.parametrize("kind", ["lognormal", "normal", "with_zeros", "constant", "tiny"])
def test_sketch_quantiles_within_alpha_of_numpy(kind):
    rng = np.random.default_rng(1)
    values = {"lognormal": rng.lognormal(-10, 2, 5000), "normal": rng.normal(0.3, 1.0, 5000),
              "with_zeros": np.r_[np.zeros(700), rng.exponential(1e-6, 3000), -rng.exponential(1e3, 300)],
              "constant": np.full(50, 2.5e-3), "tiny": np.array([4.0])}[kind]
    alpha = 1e-3
    sk = QuantileSketch(alpha)
    for chunk in np.array_split(values, 7):  # in batches, as the study feeds it
        sk.add(chunk)
    for q in (0.0, 0.001, 0.01, 0.1, 0.5, 0.9, 0.99, 0.999, 1.0):
        exact = np.quantile(values, q, method="lower")
        assert abs(sk.quantile(q) - exact) <= alpha * abs(exact), (q, sk.quantile(q), exact)
    assert sk.count == values.size and sk.nonfinite == 0


def test_sketch_memory_does_not_grow_with_the_count():
    rng = np.random.default_rng(2)
    sk = QuantileSketch(1e-3)
    sk.add(rng.uniform(1.0, 10.0, 1000))
    small = sk.buckets
    for _ in range(50):
        sk.add(rng.uniform(1.0, 10.0, 10_000))
    # one decade holds log(10) / log(gamma) ~ 1151 buckets, however many values
    assert sk.buckets <= math.ceil(math.log(10) / math.log((1 + 1e-3) / (1 - 1e-3))) + 1
    assert small <= sk.buckets and sk.count == 501_000


def test_sketch_merge_equals_one_sketch_and_counts_nonfinite():
    rng = np.random.default_rng(3)
    a, b = rng.lognormal(size=300), np.r_[rng.lognormal(size=200), np.nan, np.inf]
    one, left, right = QuantileSketch(), QuantileSketch(), QuantileSketch()
    one.add(np.r_[a, b]), left.add(a), right.add(b)
    left.merge(right)
    assert [left.quantile(q) for q in (0.1, 0.5, 0.9)] == [one.quantile(q) for q in (0.1, 0.5, 0.9)]
    assert left.nonfinite == 2 and left.count == 500
    with pytest.raises(ValueError, match="alpha: expected 0 < alpha < 1, found 0"):
        QuantileSketch(0)
    with pytest.raises(ValueError, match="other: expected a sketch of alpha 0.001, found 0.01"):
        left.merge(QuantileSketch(0.01))
    assert math.isnan(QuantileSketch().quantile(0.5))


def test_moments_against_numpy():
    x = np.random.default_rng(4).normal(1e-5, 3e-6, 1001)
    m = Moments()
    for chunk in np.array_split(x, 9):
        m.add(chunk)
    assert m.count == x.size
    np.testing.assert_allclose([m.mean, m.std], [x.mean(), x.std(ddof=1)], rtol=1e-12)


# --- the plan, built lazily -------------------------------------------------------------------------------

def test_plan_runs_are_the_spawned_children():
    """Run r's draws come from the r-th child of SeedSequence(seed).spawn(n), as documented."""
    children = np.random.SeedSequence(9).spawn(30)
    for r in (0, 7, 29):
        (spec,) = plan_runs({}, {"Cf": (0.3, 0.4)}, 30, 9, r, r + 1)
        assert spec.params["Cf"] == np.random.default_rng(children[r]).uniform(0.3, 0.4)
        assert spec.seed == int(children[r].generate_state(1, np.uint32)[0])
    assert plan_runs({"rho": (1, 2, 3)}, {"Cf": (0.3, 0.4)}, 4, 1, 5, 9) == \
        make_plan({"rho": (1, 2, 3)}, {"Cf": (0.3, 0.4)}, 4, 1)[5:9]
    with pytest.raises(ValueError, match="start, stop: expected 0 <= start <= stop <= 4, found 3, 5"):
        plan_runs({}, {}, 4, 0, 3, 5)


def test_window_bounds_the_batches_in_flight():
    in_flight, most, lock = [0], [0], threading.Lock()

    def work(x):
        with lock:
            in_flight[0] += 1
            most[0] = max(most[0], in_flight[0])
        time.sleep(0.002)
        with lock:
            in_flight[0] -= 1
        return x

    pulled = []

    def lazy():
        for i in range(40):
            pulled.append(i)
            yield i

    with concurrent.futures.ThreadPoolExecutor(4) as pool:
        ex = Executor(pool, None)
        out = []
        for x in ex.map_batches(work, lazy(), window=3):
            out.append(x)
            assert len(pulled) - len(out) <= 3  # submitted, not yet collected
    assert sorted(out) == list(range(40)) and most[0] <= 3


# --- the study against the rows of an ordinary sweep ------------------------------------------------------

@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("mc")
    res = mc.monte_carlo(CFG, "constant", **STUDY, criteria=CRITERIA, worst=4,
                         out_dir=out, workers=1)
    rows = od.sweep(CFG, "constant", uncertain=STUDY["uncertain"], samples=STUDY["samples"], seed=STUDY["seed"],
                    duration=STUDY["duration"], workers=1).rows
    return res, rows, out


def test_study_statistics_equal_an_exact_computation(study):
    res, rows, _ = study
    assert res.runs == 23 and len(rows) == 23
    assert res.counts == {s: sum(r["status"] == s for r in rows) for s in ("ok", "diverged", "failed")}
    assert all(n > 0 for n in res.counts.values()), res.counts  # the draw covers every status
    ok = [r for r in rows if r["status"] == "ok"]
    for metric in ("rms_error", "max_error", "observer_rms_error_f"):
        values = np.array([r[metric] for r in ok], dtype=float)
        stats = res.metrics[metric]
        for q in mc.QUANTILES:
            exact = np.quantile(values, q, method="lower")
            assert abs(stats["quantiles"][f"{q:g}"] - exact) <= mc.ALPHA * abs(exact)
        assert stats["count"] == len(ok)
        np.testing.assert_allclose([stats["mean"], stats["std"]], [values.mean(), values.std(ddof=1)], rtol=1e-12)
        assert (stats["min"], stats["max"]) == (values.min(), values.max())
    fails = sum(not (r["status"] == "ok" and r["rms_error"] <= 0.009 and r["max_error"] <= 0.017) for r in rows)
    assert 3 < fails < 23 and res.failures == fails and res.failure_probability == fails / 23
    ci = binomtest(fails, 23).proportion_ci(confidence_level=0.95, method="exact")
    assert res.interval == (ci.low, ci.high)


def test_worst_cases_are_the_worst_rows_and_replay(study):
    res, rows, out = study
    key = [(math.inf if r["status"] != "ok" else r["rms_error"], -r["run"]) for r in rows]
    expected = [-k[1] for k in sorted(key, reverse=True)[:4]]
    assert [w["run"] for w in res.worst] == expected
    failed = next(r for r in rows if r["status"] == "failed")
    entry = next(w for w in res.worst if w["run"] == failed["run"])
    assert entry["m"] == failed["m"] and entry["error"] == failed["error"] and entry["rms_error"] is None
    # a worst case with its parameters runs again to the same numbers
    ok_rows = sorted((r for r in rows if r["status"] == "ok"), key=lambda r: -r["rms_error"])
    again = mc.replay(out, ok_rows[0]["run"])
    assert again["rms_error"] == ok_rows[0]["rms_error"] and again["Cf"] == ok_rows[0]["Cf"]
    with pytest.raises(ValueError, match="run: expected 0 to 22, found 23"):
        mc.replay(out, 23)


def test_montecarlo_json_is_the_result(study):
    res, _, out = study
    assert json.loads((out / "montecarlo.json").read_text()) == json.loads(json.dumps(res.to_dict()))
    assert sorted(p.name for p in (out / mc.BATCH_DIR).iterdir()) == [f"b{i:06d}.npz" for i in range(5)]


# --- resume ------------------------------------------------------------------------------------------------

def test_interrupted_study_resumes_to_the_same_numbers(study, tmp_path, monkeypatch):
    res, _, out = study
    real, written = mc._write_batch, []

    def stop_after_two(path, arrays):
        if len(written) == 2:
            raise KeyboardInterrupt
        written.append(path.name)
        real(path, arrays)

    monkeypatch.setattr(mc, "_write_batch", stop_after_two)
    kw = dict(**STUDY, criteria=CRITERIA, worst=4, out_dir=tmp_path, workers=1)
    with pytest.raises(KeyboardInterrupt):
        mc.monte_carlo(CFG, "constant", **kw)
    assert sorted(p.name for p in (tmp_path / mc.BATCH_DIR).iterdir()) == ["b000000.npz", "b000001.npz"]
    monkeypatch.setattr(mc, "_write_batch", real)
    with pytest.raises(ValueError, match="holds the results of a sweep"):
        mc.monte_carlo(CFG, "constant", **kw)
    again = mc.monte_carlo(CFG, "constant", **kw, resume=True)
    assert again.resumed_runs == 10
    assert again.to_dict() == res.to_dict()
    for i in range(5):
        with np.load(out / mc.BATCH_DIR / f"b{i:06d}.npz") as a, np.load(tmp_path / mc.BATCH_DIR / f"b{i:06d}.npz") as b:
            for k in a.files:
                np.testing.assert_array_equal(a[k], b[k])


def test_resume_refuses_other_settings_and_a_tampered_batch(study, tmp_path):
    res, _, out = study
    kw = dict(**STUDY, criteria=["rms_error<=0.009"], out_dir=tmp_path, workers=1)
    mc.monte_carlo(CFG, "constant", **{**kw, "samples": 8})
    with pytest.raises(ValueError, match=r"different settings \(differs in: samples\)"):
        mc.monte_carlo(CFG, "constant", **kw, resume=True)
    path = tmp_path / mc.BATCH_DIR / "b000001.npz"
    with np.load(path) as a:
        arrays = {k: a[k] for k in a.files}
    arrays["params"] = arrays["params"] + 1e-9
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)
    with pytest.raises(ValueError, match=r"b000001.npz': its params differ from the planned ones; delete it"):
        mc.monte_carlo(CFG, "constant", **{**kw, "samples": 8}, resume=True)
    path.write_bytes(b"not a zip")
    with pytest.raises(ValueError, match=r"b000001.npz' is not a batch file of this study"):
        mc.monte_carlo(CFG, "constant", **{**kw, "samples": 8}, resume=True)


@pytest.mark.parametrize(("kw", "match"), [
    ({"criteria": ["rms_error<1"]}, "criteria: expected NAME<=LIMIT or NAME>=LIMIT, found 'rms_error<1'"),
    ({"criteria": ["rms_error<=inf"]}, "criteria: expected a finite number as the limit"),
    ({"metric": "stable"}, "metric: expected one of rms_error"),
    ({"batch": 0}, "batch: expected an integer >= 1, found 0"),
    ({"confidence": 1.0}, r"confidence: expected a number in \(0, 1\), found 1.0"),
    ({"uncertain": {"rho": (2, 1)}}, "uncertain rho: expected LO <= HI"),
])
def test_bad_arguments_refused_before_any_run(kw, match, tmp_path):
    with pytest.raises(ValueError, match=match):
        mc.monte_carlo(CFG, "constant", **{**STUDY, **kw}, out_dir=tmp_path / "o", workers=1)
    assert not (tmp_path / "o").exists()


# --- the command line ---------------------------------------------------------------------------------------

@pytest.mark.parametrize(("args", "match"), [
    (["--vary", "rho=1:2:2", "--criterion", "rms_error<=1"], "argument --criterion: only for a streamed"),
    (["--stream", "--vary", "rho=1:2:2", "--uncertain", "Cf=0.3:0.4"], "argument --vary: a streamed Monte-Carlo"),
    (["--stream"], "argument --uncertain: a Monte-Carlo study needs"),
    (["--stream", "--uncertain", "Cf=0.3:0.4", "--criterion", "speed<=1"], "argument --criterion: unknown metric 'speed'"),
    (["--stream", "--uncertain", "Cf=0.3:0.4", "--resume"], "argument --resume: no sweep.json"),
])
def test_cli_refuses_in_one_line(args, match, tmp_path, capsys):
    assert main(["sweep", "--scenario", "constant", "--out", str(tmp_path / "o"), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and match in err[0]


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "obsdesign", "sweep", *args], capture_output=True, text=True,
                          timeout=600)


@pytest.mark.slow
def test_killed_cli_study_resumes_to_the_uninterrupted_result(tmp_path):
    """SIGKILL in the middle of a streamed study (2 workers); --resume gives the uninterrupted numbers."""
    args = ["--scenario", "positioning", "--duration", "3.5", "--uncertain", "Cf=0.2:0.5", "--uncertain",
            "sigma=10:40", "--samples", "120", "--batch", "10", "--stream", "--criterion", "settling_time_1<=0.1",
            "--workers", "2"]
    whole = _cli(*args, "--out", str(tmp_path / "whole"))
    assert whole.returncode == 0, whole.stderr
    proc = subprocess.Popen([sys.executable, "-m", "obsdesign", "sweep", *args, "--out", str(tmp_path / "cut")],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    batches = tmp_path / "cut" / mc.BATCH_DIR
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and not (batches.is_dir() and len(list(batches.glob("b*.npz"))) >= 3):
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait(30)
    kept = len(list(batches.glob("b*.npz")))
    assert 3 <= kept < 12
    again = _cli(*args, "--out", str(tmp_path / "cut"), "--resume")
    assert again.returncode == 0, again.stderr
    summary = json.loads(again.stdout)
    assert summary["resumed_runs"] == 10 * kept
    assert (tmp_path / "cut" / "montecarlo.json").read_text() == (tmp_path / "whole" / "montecarlo.json").read_text()


def test_progress_lines_carry_the_eta_and_force_replaces_a_study(tmp_path, capsys):
    kw = dict(**{**STUDY, "samples": 10}, out_dir=tmp_path, workers=1)
    mc.monte_carlo(CFG, "constant", **kw, progress=5)
    lines = capsys.readouterr().err.strip().splitlines()
    assert [line.split(",")[0] for line in lines] == ["monte carlo: 5/10 runs", "monte carlo: 10/10 runs"]
    assert all(" s, ETA " in line for line in lines)
    # a row sweep replacing the study (--force) leaves none of its files behind
    od.sweep(CFG, "constant", uncertain={"Cf": (0.3, 0.4)}, samples=2, duration=0.2, workers=1, out_dir=tmp_path,
             force=True)
    assert not (tmp_path / "montecarlo.json").exists() and not list((tmp_path / mc.BATCH_DIR).iterdir())


@pytest.mark.slow
# The scheduler's HTTP server tries port 8787 even without a dashboard; where a parallel pytest worker's scheduler
# (tests/test_sweep.py) holds it, distributed warns, moves to another port and leaves its probe socket to the
# garbage collector: noise of the test's neighbours, not of the study.
@pytest.mark.filterwarnings("ignore:Port 8787 is already in use:UserWarning", "ignore::ResourceWarning",
                            "ignore::pytest.PytestUnraisableExceptionWarning")
def test_dask_cluster_gives_the_same_study(study, tmp_path):
    """The batches on a local Dask cluster of two workers (the windowed submission through distributed.wait)."""
    distributed = pytest.importorskip("distributed", reason="dask[distributed] not installed")
    res, _, _ = study
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        again = mc.monte_carlo(CFG, "constant", **STUDY, criteria=CRITERIA, worst=4, out_dir=tmp_path,
                               executor=client)
    assert again.to_dict() == res.to_dict()


def test_cli_streams_a_large_study_without_vary(tmp_path, monkeypatch, capsys):
    """Above STREAM_ABOVE samples without --vary the sweep is streamed (lowered here to keep it short)."""
    from obsdesign.cli import _sim

    monkeypatch.setattr(_sim, "STREAM_ABOVE", 5)
    base = ["sweep", "--scenario", "constant", "--duration", "0.2", "--uncertain", "Cf=0.3:0.4", "--workers", "1"]
    assert main([*base, "--samples", "6", "--criterion", "rms_error<=1", "--out", str(tmp_path / "s")]) == 0
    printed = json.loads(capsys.readouterr().out)
    # no failure in 6 runs: the Clopper-Pearson interval is [0, 1 - 0.025^(1/6)] in closed form
    assert printed["runs"] == 6 and printed["failures"] == 0 and printed["interval"][0] == 0.0
    assert printed["interval"][1] == pytest.approx(1 - 0.025 ** (1 / 6), rel=1e-9)
    assert (tmp_path / "s" / "montecarlo.json").is_file() and not (tmp_path / "s" / "results.csv").exists()
    assert main([*base, "--samples", "5", "--out", str(tmp_path / "r")]) == 0  # not above: rows
    assert (tmp_path / "r" / "results.csv").is_file() and not (tmp_path / "r" / "montecarlo.json").exists()


def test_sweep_warns_of_a_lag_design_on_the_physical_plant(tmp_path, capsys):
    """table1 (variant lag, beta set) tracking: sweep runs the physical plant (the API's default) where the
    lag observer's estimate is biased; simulate on that plant gives metres of error where the model plant
    gives millimetres, so the sweep says so in one line (as simulate does)."""
    lag = od.load_preset("table1")
    physical = od.simulate(lag, "tracking", duration=2.0, plant="physical", keep_trace=False).metrics["rms_error"]
    model = od.simulate(lag, "tracking", duration=2.0, plant="model", keep_trace=False).metrics["rms_error"]
    assert physical > 100 * model
    base = ["sweep", "--preset", "table1", "--scenario", "constant", "--duration", "0.1", "--samples", "2",
            "--uncertain", "Cf=0.3:0.4", "--workers", "1"]
    assert main([*base, "--stream", "--out", str(tmp_path / "a")]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert [line for line in err if "warning" in line] == [
        "obsdesign sweep: warning: the 'lag' observer follows eq:3:1, which drops the -Fv/beta term of the physical "
        "lag plant, so its friction estimate is biased here (docs/simulation.md); use --variant static for a "
        "meaningful estimate"]
    assert main([*base, "--variant", "static", "--out", str(tmp_path / "b")]) == 0
    assert "warning" not in capsys.readouterr().err
