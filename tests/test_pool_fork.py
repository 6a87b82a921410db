"""The local pool forks its workers where that is safe, and stays able to (no thread left behind)."""

from __future__ import annotations

import subprocess
import sys

import pytest

CHECK = """
import concurrent.futures.process as p
import threading
import obsdesign as od
from obsdesign.sim import kernel
methods, warmed = [], []
orig = p.ProcessPoolExecutor.__init__
def init(self, *a, **k):
    methods.append(k["mp_context"].get_start_method())
    warmed.append(len(kernel.run_loop.overloads))  # the loaded kernel the forked workers inherit
    orig(self, *a, **k)
p.ProcessPoolExecutor.__init__ = init
cfg = od.load_preset("vcm")
rows = []
for _ in range(2):
    res = od.sweep(cfg, "positioning", vary={"rho": (2.0, 4.0, 4)}, samples=1, workers=2)
    rows.append([r["rms_error"] for r in res.rows])
serial = od.sweep(cfg, "positioning", vary={"rho": (2.0, 4.0, 4)}, samples=1, workers=1)
print(methods, all(n > 0 for n in warmed), len(warmed), rows[0] == rows[1] == [r["rms_error"] for r in serial.rows],
      threading.active_count())
"""


@pytest.mark.slow  # a sweep on a forked pool in a fresh interpreter (4-5 s)
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the pool forks on Linux only")
def test_sweep_forks_warmed_workers_and_gives_the_serial_rows():
    out = subprocess.run([sys.executable, "-c", CHECK], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    methods, warm_ok, n_warm, same, _threads = out.stdout.rsplit(maxsplit=4)
    assert methods == "['fork', 'fork']"  # the second sweep in the same process forks too
    assert warm_ok == "True" and n_warm == "2" and same == "True"


def test_a_thread_in_the_process_means_spawn():
    import threading

    from obsdesign.sweeps.pool import can_fork

    stop = threading.Event()
    t = threading.Thread(target=stop.wait)
    t.start()
    try:
        assert not can_fork()
    finally:
        stop.set()
        t.join()
