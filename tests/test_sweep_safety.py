"""Sweep folders are safe: lock, no silent overwrite, checked resume, up-front validation,
workers that die with the sweep, prompt SIGINT, and a bounded --scheduler check."""

import contextlib
import csv
import fcntl
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

import obsdesign as od
from obsdesign.cli import main

SMALL = ["sweep", "--scenario", "constant", "--duration", "0.2", "--vary", "rho=1.5:4:2", "--uncertain",
         "Cf=0.3:0.4", "--samples", "2", "--seed", "4", "--workers", "1"]
# A sweep of a few seconds on 2 workers (for the process tests).
LONG = ["sweep", "--scenario", "positioning", "--vary", "rho=1.5:6:20", "--uncertain", "Cf=0.25:0.45",
        "--samples", "20", "--seed", "7", "--workers", "2"]


def cli(*args, timeout=300):
    return subprocess.run([sys.executable, "-m", "obsdesign", *args], capture_output=True, text=True, timeout=timeout)


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """A finished small sweep: (folder, results.csv text)."""
    out = tmp_path_factory.mktemp("done")
    assert main([*SMALL, "--out", str(out)]) == 0
    return out, (out / "results.csv").read_text()


def copy_of(finished, tmp_path):
    src, _ = finished
    dst = tmp_path / "sw"
    dst.mkdir()
    for name in ("results.csv", "sweep.json", ".checksums"):
        (dst / name).write_bytes((src / name).read_bytes())
    return dst


# -- no silent overwrite ---------------------------------------------------------------------------------

def test_rerun_without_resume_is_refused_and_keeps_the_rows(finished, tmp_path, capsys):
    out = copy_of(finished, tmp_path)
    before = (out / "results.csv").read_text()
    capsys.readouterr()
    assert main([*SMALL, "--out", str(out)]) == 2
    line = one_line(capsys.readouterr().err)
    assert "holds the results of a sweep" in line and "--resume" in line and "--force" in line
    assert (out / "results.csv").read_text() == before
    # another sweep into the folder: refused too
    assert main([*SMALL[:-4], "--seed", "9", "--workers", "1", "--out", str(out)]) == 2
    assert (out / "results.csv").read_text() == before


def test_force_replaces_and_resume_and_force_conflict(finished, tmp_path, capsys):
    out = copy_of(finished, tmp_path)
    (out / "summary.json").write_text("{}")
    cfg = od.load_preset("vcm")
    res = od.sweep(cfg, "constant", vary={"rho": (2.0, 3.0, 3)}, duration=0.2, workers=1, out_dir=out, force=True)
    rows = list(csv.DictReader((out / "results.csv").read_text().splitlines()))
    assert [float(r["rho"]) for r in rows] == [2.0, 2.5, 3.0] and len(res.rows) == 3
    assert not (out / "summary.json").exists()  # the old sweep's summary is gone with it
    with pytest.raises(ValueError, match="resume, force: expected at most one of them, found both"):
        od.sweep(cfg, "constant", duration=0.2, workers=1, out_dir=out, force=True, resume=True)


# -- lock ------------------------------------------------------------------------------------------------

@pytest.mark.slow
def test_a_second_sweep_in_a_locked_folder_fails_at_once(tmp_path):
    out = tmp_path / "busy"
    out.mkdir()
    with open(out / ".lock", "w") as fh:  # hold the lock as a running sweep would
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        t0 = time.monotonic()
        proc = cli(*SMALL, "--out", str(out))
        assert proc.returncode == 2
        assert "locked by a running sweep" in one_line(proc.stderr)
        assert time.monotonic() - t0 < 30
        assert not (out / "results.csv").exists()
    # released: the same command now runs
    assert cli(*SMALL, "--out", str(out)).returncode == 0


@pytest.mark.slow
def test_two_concurrent_sweeps_one_wins_the_other_refuses(tmp_path):
    out = tmp_path / "cc"
    first = subprocess.Popen([sys.executable, "-m", "obsdesign", *LONG, "--out", str(out)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.time() + 120
        while not (out / "results.csv").exists() and time.time() < deadline:
            time.sleep(0.05)
        second = cli(*SMALL, "--out", str(out), "--force")
        assert second.returncode == 2 and "locked by a running sweep" in one_line(second.stderr)
    finally:
        first.send_signal(signal.SIGINT)
        first.communicate(timeout=60)
    # the folder holds the first sweep's rows under the first sweep's settings
    assert '"seed": 7' in (out / "sweep.json").read_text()


# -- resume checks ---------------------------------------------------------------------------------------

def _edit_last_row(out: Path, column: str, value: str) -> None:
    path = out / "results.csv"
    lines = path.read_text().split("\n")
    header = lines[0].split(",")
    fields = lines[-2].split(",")
    fields[header.index(column)] = value
    lines[-2] = ",".join(fields)
    path.write_text("\n".join(lines))


@pytest.mark.parametrize(
    "column, value, match",
    [
        ("run", "9999", r"line 5: run '9999' is not a run of this sweep \(expected 0 to 3\)"),
        ("run", "x7", r"line 5: run 'x7' is not a run of this sweep"),
        ("status", "bogus", r"line 5: run 3: status 'bogus' is not one of ok, diverged, failed"),
        ("seed", "12345", r"line 5: run 3: seed '12345' differs from the planned"),
        ("rho", "1.5", r"line 5: run 3: rho '1.5' differs from the planned '4.0'"),
        ("rms_error", "abc", r"line 5: run 3: rms_error 'abc' is not a number"),
        ("rms_error", "12345.0", r"line 5: run 3: the row differs from the one the sweep wrote"),
    ],
)
def test_resume_refuses_a_corrupt_row_naming_file_and_line(finished, tmp_path, capsys, column, value, match):
    out = copy_of(finished, tmp_path)
    _edit_last_row(out, column, value)
    before = (out / "results.csv").read_text()
    capsys.readouterr()
    assert main([*SMALL, "--out", str(out), "--resume"]) == 2
    line = one_line(capsys.readouterr().err)
    assert "results.csv" in line
    import re

    assert re.search(match, line), line
    assert (out / "results.csv").read_text() == before


def test_a_row_without_its_digest_is_recomputed(finished, tmp_path):
    out = copy_of(finished, tmp_path)
    sums = (out / ".checksums").read_text().split("\n")
    (out / ".checksums").write_text("\n".join(sums[:2] + [""]))  # digests of runs 0, 1 only
    assert main([*SMALL, "--out", str(out), "--resume"]) == 0
    assert (out / "results.csv").read_text() == finished[1]
    import json

    assert json.loads((out / "summary.json").read_text())["resumed_runs"] == 2


@pytest.mark.parametrize("manifest, match", [(None, "sweep.json' is missing"), ("{oops", "sweep.json' is corrupt"),
                                             ("[]", "sweep.json' is corrupt")])
def test_resume_names_a_missing_or_corrupt_manifest(finished, tmp_path, capsys, manifest, match):
    out = copy_of(finished, tmp_path)
    if manifest is None:
        (out / "sweep.json").unlink()
    else:
        (out / "sweep.json").write_text(manifest)
    capsys.readouterr()
    assert main([*SMALL, "--out", str(out), "--resume"]) == 2
    assert match in one_line(capsys.readouterr().err)


def test_resume_names_the_setting_that_differs(finished, tmp_path, capsys):
    out = copy_of(finished, tmp_path)
    capsys.readouterr()
    assert main([*SMALL[:-4], "--seed", "5", "--workers", "1", "--out", str(out), "--resume"]) == 2
    assert "(differs in: seed)" in one_line(capsys.readouterr().err)


# -- validation before any run ---------------------------------------------------------------------------

@pytest.mark.parametrize(
    "kw, exc, match",
    [
        ({"vary": {"rho": (1, 2, 0)}}, ValueError, "vary rho N: expected an integer >= 1, found 0"),
        ({"vary": {"rho": (1, 2, 2.5)}}, ValueError, "vary rho N: expected an integer >= 1, found 2.5"),
        ({"vary": {"rho": (1, 2, -1)}}, ValueError, "vary rho N: expected an integer >= 1, found -1"),
        ({"vary": {"rho": "abc"}}, TypeError, r"vary rho: expected \(LO, HI, N\), found 'abc'"),
        ({"vary": {"rho": (1, float("nan"), 2)}}, ValueError, "vary rho HI: expected a finite number"),
        ({"uncertain": {"Cf": (0.5, 0.3)}}, ValueError, "uncertain Cf: expected LO <= HI, found 0.5 > 0.3"),
        ({"vary": {"rho": (1, 2, 2)}, "uncertain": {"rho": (3, 4)}}, ValueError, "'rho' is varied already"),
        ({"chunk": 0}, ValueError, "chunk: expected an integer >= 1, found 0"),
        ({"chunk": -1}, ValueError, "chunk: expected an integer >= 1, found -1"),
        ({"workers": 0}, ValueError, "workers: expected an integer >= 1, found 0"),
        ({"samples": 2.0}, ValueError, "samples: expected an integer >= 1, found 2.0"),
        ({"samples": "3"}, ValueError, "samples: expected an integer >= 1, found '3'"),
        ({"controller": "open-loop"}, ValueError, "controller: scenario 'positioning' needs 'pid' or 'pid\\+observer'"),
        ({"controller": "magic"}, ValueError, "controller: expected one of open-loop, pid, pid\\+observer"),
        ({"vary": {"rho": (1, 2, 10**7)}}, ValueError, "vary, samples: expected at most 1000000 runs in all, found 10000000"),
    ],
)
def test_api_validates_before_any_run(tmp_path, kw, exc, match):
    kw = {"workers": 1, **kw}
    t0 = time.monotonic()
    with pytest.raises(exc, match=match):
        od.sweep(od.load_preset("vcm"), "positioning", duration=3.5, out_dir=tmp_path / "o", **kw)
    assert not (tmp_path / "o").exists()
    assert time.monotonic() - t0 < 5


@pytest.mark.parametrize(
    "args, match",
    [
        (["--vary", "rho=1:2:2", "--uncertain", "rho=3:4"], "'rho' is given with --vary too"),
        (["--vary", "rho=1:2:2", "--vary", "rho=3:4:2"], "--vary rho: expected each parameter once, found it twice"),
        (["--uncertain", "Cf=0.1:0.2", "--uncertain", "Cf=0.3:0.4"], "--uncertain Cf: expected each parameter once"),
        (["--vary", "rho=1:2:²"], "--vary rho: expected an integer N >= 1, found '²'"),
        (["--metric", "status"], "argument --metric: expected one of stable, rms_error"),
        (["--metric", "rms_eror"], "found 'rms_eror'"),
        (["--resume", "--force"], "argument --force: not allowed with argument --resume"),
    ],
)
def test_cli_refuses_before_any_run(args, match, tmp_path, capsys):
    out = tmp_path / "o"
    code = main(["sweep", "--scenario", "constant", "--duration", "0.2", "--workers", "1", "--out", str(out), *args])
    assert code == 2
    assert match in one_line(capsys.readouterr().err)
    assert not out.exists()


# -- processes -------------------------------------------------------------------------------------------

def _children(pid: int) -> set[int]:
    """All descendants of ``pid`` (from /proc)."""
    parents = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    found, frontier = set(), {pid}
    while frontier:
        frontier = {p for p, pp in parents.items() if pp in frontier} - found
        found |= frontier
    return found


def _alive(pid: int) -> bool:
    try:
        return (Path("/proc") / str(pid) / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _interruptible() -> None:
    """In the child: SIGINT as the default (a suite started in the background inherits an ignored
    SIGINT from the shell, and Python keeps an ignored SIGINT ignored)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start_long(out: Path, min_rows: int = 3):
    """The LONG sweep, once it has written ``min_rows`` rows; stderr goes to a file (no pipe that
    a leaked worker could hold open)."""
    err = open(out.parent / f"{out.name}.stderr", "w")
    proc = subprocess.Popen([sys.executable, "-m", "obsdesign", *LONG, "--out", str(out)],
                            stdout=subprocess.DEVNULL, stderr=err, text=True, preexec_fn=_interruptible)
    err.close()
    deadline = time.time() + 180
    results = out / "results.csv"
    while time.time() < deadline:
        if results.exists() and results.read_text().count("\n") > min_rows:
            break
        assert proc.poll() is None, (out.parent / f"{out.name}.stderr").read_text()
        time.sleep(0.05)
    return proc


def _reap(pids) -> list[int]:
    """The pids still alive after 10 s; killed, so that a failure does not leak them."""
    deadline = time.time() + 10
    while time.time() < deadline and any(_alive(p) for p in pids):
        time.sleep(0.1)
    left = [p for p in pids if _alive(p)]
    for p in left:
        os.kill(p, signal.SIGKILL)
    return left


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_killing_the_sweep_leaves_no_worker_behind(tmp_path, sig):
    proc = _start_long(tmp_path / "k")
    kids = _children(proc.pid)
    assert len(kids) >= 2  # the two pool workers (and the resource tracker)
    proc.send_signal(sig)
    proc.wait(timeout=30)
    assert _reap(kids) == []


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_sigint_to_the_parent_alone_stops_within_3_s_and_keeps_rows(tmp_path):
    out = tmp_path / "i"
    proc = _start_long(out)
    kids = _children(proc.pid)
    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout=60)
    finally:
        left = _reap(kids)
    elapsed = time.monotonic() - t0
    err = (tmp_path / "i.stderr").read_text()
    assert proc.returncode == 130, err
    assert elapsed < 3.0, elapsed
    assert one_line(err).startswith("obsdesign sweep: interrupted")
    rows = list(csv.DictReader((out / "results.csv").read_text().splitlines()))
    assert 3 <= len(rows) < 400 and {r["status"] for r in rows} == {"ok"}
    assert left == []


# -- --scheduler at a port that is not a Dask scheduler --------------------------------------------------

@contextlib.contextmanager
def tiny_server(reply: bytes | None, lifetime: float = 40.0):
    """A TCP server on 127.0.0.1 that accepts, sends ``reply`` (or nothing) and keeps the connection open."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(8)
    srv.settimeout(0.2)
    stop = threading.Event()
    conns = []

    def serve():
        end = time.time() + lifetime
        while not stop.is_set() and time.time() < end:
            try:
                conn, _ = srv.accept()
            except OSError:
                continue
            conns.append(conn)
            if reply is not None:
                try:
                    conn.sendall(reply)
                except OSError:
                    pass

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    finally:
        stop.set()
        thread.join(5)
        for c in conns:
            c.close()
        srv.close()


@pytest.mark.slow
@pytest.mark.parametrize("reply, match", [(None, "sent no Dask handshake within 5 s"),
                                          (b"HTTP/1.1 400 Bad Request\r\n\r\n", "not a Dask handshake")])
def test_scheduler_that_is_not_dask_ends_within_15_s(tmp_path, reply, match):
    pytest.importorskip("distributed")
    with tiny_server(reply) as address:
        t0 = time.monotonic()
        proc = cli(*SMALL, "--out", str(tmp_path / "d"), "--scheduler", address, timeout=60)
        elapsed = time.monotonic() - t0
    assert proc.returncode == 2
    line = one_line(proc.stderr)
    assert line.startswith("obsdesign sweep: argument --scheduler:") and match in line and address in line
    assert elapsed < 15
    assert not (tmp_path / "d").exists()


@pytest.mark.slow
def test_scheduler_port_that_is_closed_is_one_line(tmp_path):
    pytest.importorskip("distributed")
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()  # nothing listens there now
    proc = cli(*SMALL, "--out", str(tmp_path / "d"), "--scheduler", f"tcp://127.0.0.1:{port}", timeout=60)
    assert proc.returncode == 2 and "cannot reach" in one_line(proc.stderr)


DASK = Path(sys.executable).parent / "dask"


@pytest.mark.slow
@pytest.mark.skipif(not DASK.exists(), reason="dask[distributed] not installed")
def test_a_dask_cluster_without_workers_ends_the_sweep(tmp_path, monkeypatch):
    """All workers gone: before, the sweep waited forever; now it ends after STALL_S without a worker."""
    import importlib
    import json

    from distributed import Client

    pool = importlib.import_module("obsdesign.sweeps.pool")
    monkeypatch.setattr(pool, "STALL_S", 3.0)
    sched_file = tmp_path / "scheduler.json"
    sched = subprocess.Popen([str(DASK), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                              "--scheduler-file", str(sched_file)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 60
        while not sched_file.exists() and time.time() < deadline:
            time.sleep(0.2)
        address = json.loads(sched_file.read_text())["address"]
        with Client(address, timeout="30s") as client:
            t0 = time.monotonic()
            with pytest.raises(pool.NoWorkersError, match="no worker for 3 s with 1 batches pending"):
                od.sweep(od.load_preset("vcm"), "constant", vary={"rho": (2.0, 3.0, 2)}, duration=0.2,
                         executor=client, out_dir=tmp_path / "o")
            assert time.monotonic() - t0 < 20
    finally:
        sched.terminate()
        sched.wait(30)


def test_dask_cpu_settings_are_dask_keys_that_check_less_often():
    """dask.config.set takes any key without complaint: a misspelt one would change nothing. Each key of
    DASK_CPU_SETTINGS is in distributed's own defaults, of the default's kind, and each interval is
    longer than the default (the point of the settings); the profiler is off."""
    pytest.importorskip("distributed")
    import dask
    from dask.utils import parse_timedelta

    from obsdesign.sweeps.pool import DASK_CPU_SETTINGS

    assert DASK_CPU_SETTINGS["distributed.worker.profile.enabled"] is False
    for key, value in DASK_CPU_SETTINGS.items():
        default = dask.config.get(key)  # KeyError for a key distributed does not know
        if isinstance(default, bool):
            assert isinstance(value, bool), key
        else:
            assert parse_timedelta(value) > parse_timedelta(default), (key, value, default)
    with dask.config.set(DASK_CPU_SETTINGS):
        assert all(dask.config.get(key) == value for key, value in DASK_CPU_SETTINGS.items())
