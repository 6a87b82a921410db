"""The plant of the output-error refinement: windows of a record, simulated under the logged force (numba).

A *window* is a stretch of a record that starts in gross sliding (the friction saturated in the
direction of motion, so its state is known without the history) and runs through the reversals that
follow until the axis slides again. Each window is simulated from its own initial displacement and
velocity under the logged force, with the plant step of the closed-loop simulator
(:mod:`obsdesign.sim.kernel`: Heun substeps, the input held over a sample, the paper's pre-sliding
branch or a model of :mod:`obsdesign.friction`), so the double integrator of the axis cannot drift
over the whole record.

Examples
--------
>>> import numpy as np
>>> x = np.concatenate([np.linspace(0, 1e-2, 50), np.linspace(1e-2, 0.0, 50)[1:]])
>>> extremes(x, 1e-4).tolist()                # start, the top, the end
[0, 49, 98]
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..friction.kernels import friction_advance, friction_init, friction_n_state, friction_plant_step
from ..friction.presliding import track_reversal
from ..friction.registry import FRICTION_MODELS
from ..sim.kernel import _plant_rhs_asym

__all__ = ["PAPER_LAYOUT", "simulate_windows", "extremes", "select_windows"]

#: The paper plant's parameter array (that of :func:`obsdesign.loop.plant.plant_friction_arrays`).
PAPER_LAYOUT = ("Cf", "Cf_neg", "sigma", "sigma_neg", "offset", "s", "beta", "kappa")
_PAPER = FRICTION_MODELS.code("paper")
#: Steps of the friction state's run-in along the gross sliding before a window (models other than paper).
_RUN_IN_STEPS = 400


@njit(cache=True, error_model="numpy")
def simulate_windows(code, pp, force, starts, lengths, x0, v0, dirs, m, dt, n_sub, run_in, out):
    """Simulate each window ``[starts[i], starts[i] + lengths[i])`` under ``force``; write ``x`` to ``out``.

    Parameters
    ----------
    code : int
        Friction model code (:data:`obsdesign.friction.FRICTION_MODELS`).
    pp : ndarray
        Its parameters: the paper's :data:`PAPER_LAYOUT`, or the array of
        :meth:`~obsdesign.friction.FrictionModelInfo.pack` (which holds the offset).
    force : ndarray
        The logged actuator force [N], held from sample ``n`` to ``n + 1``.
    starts, lengths : ndarray of int64
        Windows, in samples.
    x0, v0 : ndarray
        Initial displacement [m] and velocity [m/s] of each window.
    dirs : ndarray
        Direction (+1 or -1) of the gross sliding each window starts in, in which its friction is
        saturated (0: from rest, no saturation). Not the sign of ``v0``: a window starts near the end of
        a stroke, where the speed can be below the noise of a velocity estimate.
    m, dt : float
        Mass [kg], sample time [s].
    n_sub : int
        Heun substeps per sample.
    run_in : float
        Travel [m] of gross sliding before the window after which the friction is saturated: the paper
        branch starts that far behind ``x0``; another model's state is advanced along it.
    out : ndarray
        ``sum(lengths)`` displacements [m], window after window, at the sample instants.

    Returns
    -------
    bool
        False if a simulation diverged (its samples are then NaN).
    """
    h = dt / n_sub
    ok = True
    pos = 0
    fst = np.zeros(max(friction_n_state(code, pp), 1))
    for i in range(starts.shape[0]):
        x = x0[i]
        v = v0[i]
        d = dirs[i]
        p_dir, p_xr, p_fr = d, x - d * run_in, -d
        if code != _PAPER:
            friction_init(code, pp, fst, x - d * run_in)
            if d != 0.0:
                speed = max(abs(v), 1e-9)
                hb = run_in / _RUN_IN_STEPS / speed
                for j in range(_RUN_IN_STEPS):
                    friction_advance(code, pp, fst, x - d * run_in * (1.0 - (j + 1.0) / _RUN_IN_STEPS), d * speed,
                                     hb)
        for k in range(lengths[i]):
            out[pos + k] = x
            if not abs(x) < 1e3 or not abs(v) < 1e6:
                for j in range(k, lengths[i]):
                    out[pos + j] = np.nan
                ok = False
                break
            u = force[starts[i] + k]
            if code != _PAPER:
                x, v = friction_plant_step(code, pp, fst, x, v, u, m, h, n_sub)
                continue
            for _ in range(n_sub):
                k1v, _w = _plant_rhs_asym(x, v, 0.0, u, p_dir, p_xr, p_fr, m, pp[0], pp[1], pp[5], pp[2], pp[3],
                                          0.0, pp[4])
                xp = x + h * v
                vp = v + h * k1v
                k2v, _w = _plant_rhs_asym(xp, vp, 0.0, u, p_dir, p_xr, p_fr, m, pp[0], pp[1], pp[5], pp[2], pp[3],
                                          0.0, pp[4])
                x += 0.5 * h * (v + vp)
                v += 0.5 * h * (k1v + k2v)
                p_dir, p_xr, p_fr = track_reversal(v, x, p_dir, p_xr, p_fr, pp[5])
        pos += lengths[i]
    return ok


@njit(cache=True, error_model="numpy")
def extremes(x, threshold):
    """Indices of the start, the alternating turning points of ``x`` and the end.

    Parameters
    ----------
    x : ndarray
        Displacement [m].
    threshold : float
        Back-travel [m] that confirms a turning point.

    Notes
    -----
    A turning point is accepted once ``x`` has come back from it by more than ``threshold``
    (the hysteresis of the observer's ``estimated`` schedule), so noise does not count.
    """
    out = [0]
    direction = 0.0
    ext = 0
    for i in range(1, x.shape[0]):
        if direction == 0.0:
            if abs(x[i] - x[0]) > threshold:
                direction = 1.0 if x[i] > x[0] else -1.0
                ext = i
            continue
        if direction * (x[i] - x[ext]) > 0.0:
            ext = i
        elif direction * (x[ext] - x[i]) > threshold:
            out.append(ext)
            direction = -direction
            ext = i
    out.append(x.shape[0] - 1)
    return np.array(out, dtype=np.int64)


def select_windows(x_f: np.ndarray, *, threshold: float, travel: float, lead: int, tail: int,
                   skip: int) -> tuple[np.ndarray, np.ndarray, int, np.ndarray]:
    """Windows ``(starts, lengths, reversals, directions)`` of a filtered displacement ``x_f``.

    Parameters
    ----------
    x_f : ndarray
        Zero-phase filtered displacement [m].
    threshold : float
        Hysteresis [m] of the turning points (:func:`extremes`).
    travel : float
        Travel [m] that makes a stroke gross (the friction saturated).
    lead, tail : int
        Samples a window starts before its stroke's end, and runs on after the friction saturated again.
    skip : int
        Samples left out at both ends of the record.

    Notes
    -----
    A stroke (between turning points, :func:`extremes`) is *gross* when it travels more than
    ``travel`` [m]. A window starts in a gross stroke that is followed by a reversal, where it has
    travelled ``travel`` and at most ``lead`` samples before its end; it runs through the strokes
    that follow to the sample where the next gross stroke has travelled ``travel``, plus ``tail``
    samples (within that stroke). ``reversals`` counts the turning points inside the windows;
    ``directions`` holds the sign (+1/-1) of the gross stroke each window starts in.
    ``skip`` samples at both ends of the record are not used (filter transients).
    """
    ext = extremes(x_f, threshold)
    ext = ext[(ext >= skip) & (ext <= x_f.size - 1 - skip)]
    if ext.size < 3:
        return np.empty(0, np.int64), np.empty(0, np.int64), 0, np.empty(0)
    gross = np.abs(np.diff(x_f[ext])) > travel
    starts: list[int] = []
    ends: list[int] = []
    dirs: list[float] = []
    reversals = 0
    k = 0
    while k < gross.size - 1:
        if not gross[k]:
            k += 1
            continue
        a, b = ext[k], ext[k + 1]
        far = np.flatnonzero(np.abs(x_f[a:b + 1] - x_f[a]) >= travel)
        start = max(a + int(far[0]), b - lead)
        j = k + 1
        while j < gross.size and not gross[j]:
            j += 1
        if j < gross.size:
            a2, b2 = ext[j], ext[j + 1]
            far2 = np.flatnonzero(np.abs(x_f[a2:b2 + 1] - x_f[a2]) >= travel)
            end = min(a2 + int(far2[0]) + tail, b2)
        else:
            end = ext[-1]
        if starts and start < ends[-1]:
            start = ends[-1]
        if end - start > 2:
            starts.append(start)
            ends.append(end)
            dirs.append(1.0 if x_f[b] > x_f[a] else -1.0)
            reversals += j - k
        k = j
    s = np.array(starts, dtype=np.int64)
    return s, np.array(ends, dtype=np.int64) - s, reversals, np.array(dirs)
