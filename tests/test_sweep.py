"""Sweeps: identical results locally, on a real Dask cluster and after an interrupted run."""

import contextlib
import csv
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import obsdesign as od
from obsdesign.cli import main

DASK = Path(sys.executable).parent / "dask"
SWEEP = ["--preset", "vcm", "--scenario", "constant", "--duration", "0.3", "--vary", "rho=1.5:4:3",
         "--uncertain", "Cf=0.3:0.4", "--uncertain", "sigma=15:25", "--samples", "3", "--seed", "11"]


def cli(*args):
    return subprocess.run([sys.executable, "-m", "obsdesign", *args], capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def local_results(tmp_path_factory):
    out = tmp_path_factory.mktemp("local")
    proc = cli("sweep", *SWEEP, "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    return (out / "results.csv").read_text()


@pytest.mark.slow
def test_local_results_file(local_results):
    rows = list(csv.DictReader(local_results.splitlines()))
    assert len(rows) == 9 and [int(r["run"]) for r in rows] == list(range(9))
    assert sorted({float(r["rho"]) for r in rows}) == [1.5, 2.75, 4.0]
    assert all(0.3 <= float(r["Cf"]) <= 0.4 and 15 <= float(r["sigma"]) <= 25 for r in rows)
    assert all(r["status"] == "ok" and r["error"] == "" and r["stable"] == "true" for r in rows)
    # Open loop, constant 1 N: steady sliding, so the friction estimate converges to Cf.
    assert len({r["Cf"] for r in rows}) == 9  # every run its own draw


@pytest.mark.slow
def test_in_process_equals_process_pool(local_results, tmp_path):
    assert main(["sweep", *SWEEP, "--out", str(tmp_path), "--workers", "1"]) == 0
    assert (tmp_path / "results.csv").read_text() == local_results


@contextlib.contextmanager
def dask_cluster(tmp_path):
    """A real scheduler and two single-threaded workers on 127.0.0.1."""
    sched_file = tmp_path / "scheduler.json"
    procs = [subprocess.Popen([str(DASK), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                               "--scheduler-file", str(sched_file)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    try:
        deadline = time.time() + 60
        while not sched_file.exists() and time.time() < deadline:
            time.sleep(0.2)
        address = json.loads(sched_file.read_text())["address"]
        procs.append(subprocess.Popen([str(DASK), "worker", address, "--nworkers", "2", "--nthreads", "1",
                                       "--host", "127.0.0.1", "--no-dashboard"],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        from distributed import Client

        with Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=120)
        yield address
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()


@pytest.mark.slow
@pytest.mark.skipif(not DASK.exists(), reason="dask[distributed] not installed")
def test_dask_cluster_gives_identical_results(local_results, tmp_path):
    with dask_cluster(tmp_path) as address:
        assert address.startswith("tcp://127.0.0.1:")
        proc = cli("sweep", *SWEEP, "--out", str(tmp_path / "dask"), "--scheduler", address)
        assert proc.returncode == 0, proc.stderr
        assert (tmp_path / "dask" / "results.csv").read_text() == local_results
        # Through the API with an executor object as well.
        from distributed import Client

        with Client(address) as client:
            res = od.sweep(od.load_preset("vcm"), "constant", vary={"rho": (1.5, 4.0, 3)},
                           uncertain={"Cf": (0.3, 0.4), "sigma": (15.0, 25.0)}, samples=3, seed=11, duration=0.3,
                           executor=client, out_dir=tmp_path / "api")
        assert (tmp_path / "api" / "results.csv").read_text() == local_results
        assert res.best("rho")[0] in (1.5, 2.75, 4.0)


@pytest.mark.slow
def test_interrupted_sweep_resumes_to_the_same_file(tmp_path):
    # 200 runs (several seconds), so the SIGINT always arrives while the sweep is running.
    args = ["sweep", "--preset", "vcm", "--scenario", "positioning", "--duration", "3.5", "--vary", "rho=1.5:4:10",
            "--samples", "20",
            "--uncertain", "Cf=0.3:0.4", "--seed", "3", "--workers", "1"]
    full = tmp_path / "full"
    assert cli(*args, "--out", str(full)).returncode == 0
    part = tmp_path / "part"
    # SIGINT as the default in the child: a suite started in the background (where the shell ignores
    # SIGINT, and children inherit that) still tests the sweep's interrupt
    proc = subprocess.Popen([sys.executable, "-m", "obsdesign", *args, "--out", str(part)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    results = part / "results.csv"
    deadline = time.time() + 120
    while time.time() < deadline:
        if results.exists() and results.read_text().count("\n") >= 6:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1].startswith("obsdesign sweep: interrupted")
    done = results.read_text().count("\n") - 1
    assert 5 <= done < 200
    with results.open("a") as fh:
        fh.write("199,9,19,12345,4.0,0.3")  # a torn row, as if killed mid-write
    resumed = cli(*args, "--out", str(part), "--resume")
    assert resumed.returncode == 0, resumed.stderr
    assert json.loads(resumed.stdout)["resumed_runs"] == done
    assert results.read_text() == (full / "results.csv").read_text()


def test_failing_and_diverging_runs_are_isolated(tmp_path):
    res = od.sweep(od.load_preset("vcm"), "constant", vary={"rho": (0.3, 2.0, 2)}, uncertain={"m": (-1.0, 1.0)},
                   samples=6, seed=1, duration=1.0, workers=1, out_dir=tmp_path)
    status = [(r["rho"], r["m"] > 0, r["status"]) for r in res.rows]
    assert {s for rho, pos, s in status if not pos} == {"failed"}  # negative mass: invalid draw
    assert {s for rho, pos, s in status if pos and rho == 0.3} == {"diverged"}
    assert {s for rho, pos, s in status if pos and rho == 2.0} == {"ok"}
    failed = next(r for r in res.rows if r["status"] == "failed")
    assert failed["error"].startswith("ValueError: plant.m: expected a finite number > 0, found -")
    text = (tmp_path / "results.csv").read_text()
    assert len(list(csv.DictReader(text.splitlines()))) == 12


@pytest.mark.parametrize(
    "args, match",
    [
        (["--vary", "rho=1:2"], "--vary: expected NAME=LO:HI:N, found 'rho=1:2'"),
        (["--vary", "rho=1:2:x"], "--vary rho: expected an integer N >= 1, found 'x'"),
        (["--vary", "rho=1:2:0"], "--vary rho: expected an integer N >= 1, found '0'"),
        (["--vary", "mass=1:2:3"], "--vary: unknown parameter 'mass'"),
        (["--uncertain", "Cf=0.4"], "--uncertain: expected NAME=LO:HI, found 'Cf=0.4'"),
        (["--uncertain", "Cf=0.4:0.3"], "--uncertain Cf: expected LO <= HI, found 0.4 > 0.3"),
        (["--uncertain", "Cf=nan:1"], "--uncertain Cf: expected a finite number, found 'nan'"),
        (["--samples", "0"], "argument --samples: expected an integer >= 1, found '0'"),
        (["--resume"], "argument --resume: no results.csv"),
    ],
)
def test_bad_sweep_syntax_exits_2(args, match, tmp_path, capsys):
    assert main(["sweep", "--scenario", "constant", "--out", str(tmp_path / "o"), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and match in err[0]
    assert not (tmp_path / "o").exists()


def test_killed_worker_is_reported_and_resumable(tmp_path, monkeypatch, capsys):
    """A local worker process that dies ends the sweep with one line; --resume finishes it."""
    import concurrent.futures
    import importlib
    from concurrent.futures.process import BrokenProcessPool

    sweep_mod = importlib.import_module("obsdesign.sweeps.run")

    args = ["sweep", "--scenario", "constant", "--duration", "0.2", "--vary", "rho=1.5:4:4", "--out", str(tmp_path)]
    real = sweep_mod._run_batch
    calls = {"n": 0}

    def dying(cfg, scenario, batch, options):
        calls["n"] += 1
        if calls["n"] == 1:
            raise BrokenProcessPool("a child process terminated abruptly")
        return real(cfg, scenario, batch, options)

    class InlinePool(concurrent.futures.Executor):  # runs tasks here, fails like a killed worker
        def submit(self, fn, *a):
            fut = concurrent.futures.Future()
            try:
                fut.set_result(fn(*a))
            except BaseException as e:  # noqa: BLE001
                fut.set_exception(e)
            return fut

    monkeypatch.setattr(sweep_mod, "_run_batch", dying)
    real_executor = sweep_mod.Executor
    monkeypatch.setattr(sweep_mod, "Executor", lambda executor, workers: real_executor(InlinePool(), None))
    assert main([*args]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "a worker failed (BrokenProcessPool)" in err[0]
    assert main([*args, "--resume"]) == 0
    rows = list(csv.DictReader((tmp_path / "results.csv").read_text().splitlines()))
    assert [int(r["run"]) for r in rows] == [0, 1, 2, 3] and {r["status"] for r in rows} == {"ok"}


def test_resume_refuses_other_settings(tmp_path, capsys):
    base = ["sweep", "--scenario", "constant", "--duration", "0.2", "--vary", "rho=1.5:4:2", "--workers", "1",
            "--out", str(tmp_path)]
    assert main(base) == 0
    before = (tmp_path / "results.csv").read_text()
    capsys.readouterr()
    assert main([*base, "--seed", "5", "--resume"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "resume: the sweep in" in err[0] and "different settings" in err[0]
    assert (tmp_path / "results.csv").read_text() == before


def test_tracking_sweep_fills_every_band_column():
    res = od.sweep(od.load_preset("vcm"), "tracking", vary={"rho": (2.0, 4.0, 2)}, duration=2.0, workers=1)
    bands = [c for c in res.columns if c.startswith("rms_error_")]
    assert len(bands) == 4
    for row in res.rows:
        sim = od.simulate(od.load_preset("vcm").override(rho=row["rho"]), "tracking", duration=2.0, seed=row["seed"],
                          keep_trace=False).metrics["rms_error_per_band"]
        assert [row[c] for c in bands] == list(sim.values())
