"""Write the shipped example log from a simulation with known parameters.

Run ``python -m obsdesign.datasets.make_example_log [OUTPUT.csv]`` to write it again (default:
``example_log.csv`` beside this module, the file :func:`obsdesign.datasets.example_log` returns).
The same seed and parameters give the same file.

The axis is the ``vcm`` preset (paper section 4) with the parameters of :data:`AXIS` instead of
the paper's: mass ``m = 0.8`` kg, viscous coefficient ``sigma = 12`` N s/m, Coulomb level
``Cf = 0.9`` N with pre-sliding factor ``s = 2e4`` 1/m (50 um of pre-sliding), no load; the
sensor adds 0.2 um RMS of noise (band-limited to 1 kHz) and rounds to the 1 um encoder. The
sensitivity-based PID of the config tracks a chirp reference (:data:`REFERENCE`, 0.5 to 4 Hz,
peak velocity 0.1 m/s) for :data:`DURATION` seconds, running at the config's 10 kHz. The log
keeps every :data:`LOG_EVERY`-th sample (a 1 kHz data logger) of the time, the measured
displacement ``x_meas`` (what an encoder reports) and the force ``u`` the controller commanded.

Identification of this closed-loop record is biased a little: the loop feeds measurement noise
back into the force. ``identify`` leaves out the 50 um of pre-sliding after each reversal (the gross-sliding
model does not hold there) and recovers the mass, viscous and Coulomb parameters within 0.2 %, each 95 %
interval holding its truth (the tests state the tolerance).

Examples
--------
>>> import tempfile, pathlib
>>> import numpy as np
>>> with tempfile.TemporaryDirectory() as d:
...     path = write_csv(pathlib.Path(d) / "log.csv", np.array([0.0, 1e-3]), np.array([0.0, 2e-6]),
...                      np.array([0.5, -0.25]))
...     print(path.read_text(encoding="utf-8"), end="")
t,x,u
0.000,0.000000,0.5
0.001,0.000002,-0.25
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path
from typing import Sequence

import numpy as np

__all__ = ["AXIS", "SENSOR", "REFERENCE", "DURATION", "LOG_EVERY", "SEED", "simulate_log", "write_csv", "main"]

#: Parameters of the simulated axis (overrides of the ``vcm`` preset), the truth of the log.
AXIS = {"m": 0.8, "sigma": 12.0, "Cf": 0.9, "s": 2e4, "G": 0.0}
#: Sensor of the simulated axis: noise RMS [m] (the preset's 1 kHz band, 1 um encoder).
SENSOR = {"noise_rms": 2e-7}
#: Chirp reference of the PID loop: start and end frequency [Hz] and peak velocity [m/s].
REFERENCE = {"f0": 0.5, "f1": 4.0, "peak_velocity": 0.1}
#: Length of the record [s].
DURATION = 8.0
#: The log keeps every LOG_EVERY-th controller sample (10 kHz -> 1 kHz).
LOG_EVERY = 10
#: Seed of the sensor noise.
SEED = 1


def simulate_log() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Simulate the axis of :data:`AXIS` under PID control and return the logged columns.

    Returns
    -------
    t, x, u : ndarray, shape (DURATION / (LOG_EVERY dt),)
        Time [s], measured displacement [m] (noisy, quantized) and commanded force [N].
    """
    from ..params import load_preset
    from ..sim import Chirp, simulate

    cfg = load_preset("vcm").override(**AXIS, **SENSOR)
    res = simulate(cfg, Chirp(**REFERENCE), controller="pid", duration=DURATION, seed=SEED)
    keep = slice(None, None, LOG_EVERY)
    return res.t[keep], res.x_meas[keep], res.u[keep]


def write_csv(path: str | os.PathLike, t: np.ndarray, x: np.ndarray, u: np.ndarray) -> Path:
    """Write ``t, x, u`` as CSV with the header ``t,x,u`` (through a temporary file, then renamed).

    Time is written to 1 ms (``%.3f`` s: exact for a 1 kHz log), displacement to 1 nm
    (``%.6f`` m: the encoder's 1 um steps exactly), force to 6 significant digits.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file to write.
    t, x, u : ndarray, shape (n,)
        Time [s], displacement [m], force [N].

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    path = Path(path)
    rows = "".join(f"{a:.3f},{b:.6f},{c:.6g}\n" for a, b, c in zip(t, x, u))
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
        f.write("t,x,u\n" + rows)
    os.chmod(tmp, 0o644)  # mkstemp makes it private; the log is an ordinary data file
    os.replace(tmp, path)
    return path


def main(argv: Sequence[str] | None = None) -> int:
    """Write the example log (``python -m obsdesign.datasets.make_example_log [OUTPUT.csv]``).

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments (default: ``sys.argv[1:]``).

    Returns
    -------
    int
        0.
    """
    parser = argparse.ArgumentParser(prog="python -m obsdesign.datasets.make_example_log",
                                     description="Write the example log from a simulation with known parameters.")
    parser.add_argument("output", nargs="?", default=str(Path(__file__).with_name("example_log.csv")),
                        help="CSV file to write (default: the package's example_log.csv)")
    args = parser.parse_args(argv)
    path = write_csv(args.output, *simulate_log())
    print(f"{path}: {path.stat().st_size / 1e3:.0f} kB")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
