"""Margins of a discrete loop: python-control's, checked for the gain crossovers it misses, and the one
assembly of a sampled PID loop (``C z^-d H`` with ``S``, ``T``, ``PS``, ``CS``), shared by
:mod:`obsdesign.design.sampled_loop` (the PID's design model) and :mod:`obsdesign.design.plant_loop` (the
simulated plant), with the drive's delay both read the same way (:func:`drive_delay`).
"""

from __future__ import annotations

import math
import warnings
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import control as ct

__all__ = ["loop_margins", "gain_crossovers", "closed_loop", "drive_delay"]


def loop_margins(L: ct.TransferFunction) -> tuple[float, float, float, float, float]:
    """``(gm, pm_deg, w_gc, w_pc, delay margin [s])`` of a discrete loop ``L``.

    python-control's ``stability_margins``; where it finds no gain crossover although ``|L|`` crosses 1
    below the Nyquist frequency (seen on high-gain PID loops: an "infinite" phase margin printed for a loop
    with a crossover, stable or not), the crossovers are found on ``|L(exp(j w dt))|`` itself
    (:func:`gain_crossovers`) and the smallest phase margin among them is reported.

    Parameters
    ----------
    L : control.TransferFunction
        The discrete open loop.
    """
    import control as ct

    with warnings.catch_warnings():  # its 'frd' fallback refines on the exact response: accurate here
        warnings.filterwarnings("ignore", message="stability_margins: Falling back")
        gm, pm, _, wpc, wgc, _ = ct.stability_margins(L)
        _, pms, _, _, wgcs, _ = ct.stability_margins(L, returnall=True)
    if not (math.isfinite(wgc) and wgc > 0):
        num, den = (np.atleast_1d(np.squeeze(x)) for x in ct.tfdata(L))
        found = gain_crossovers(num, den, float(L.dt))
        if found:
            pm, wgc = min(found)
            pms, wgcs = [p for p, _ in found], [w for _, w in found]
    dms = [math.radians(float(p)) / float(w) for p, w in zip(np.atleast_1d(pms), np.atleast_1d(wgcs)) if w > 0]
    dm = max(0.0, min(dms)) if dms else math.inf
    return float(gm), float(pm), float(wgc), float(wpc), dm


def gain_crossovers(num, den, dt: float, points: int = 20001, *, delta: bool = False) -> list[tuple[float, float]]:
    """The gain crossovers of the discrete loop ``L(z) = num(z) / den(z)``: ``(phase margin [deg], w [rad/s])``.

    ``|L(exp(j w dt))| - 1`` changes sign between neighbours of a log grid from ``1e-6 pi/dt`` to the Nyquist
    frequency ``pi/dt``; each bracket is bisected to the float resolution of ``w``; the phase margin is
    ``180 deg + arg L`` wrapped into (-180, 180].

    Parameters
    ----------
    num, den : array_like
        Coefficients in ``z``, highest power first.
    dt : float
        Sample time [s].
    points : int
        Grid points.
    delta : bool
        ``num`` and ``den`` are polynomials in ``delta = z - 1`` instead of ``z``, evaluated at
        ``expm1(j w dt)``: well conditioned where poles and zeros crowd ``z = 1`` (``w dt`` small).

    Returns
    -------
    list of (float, float)
        One pair per crossover, in increasing ``w`` (empty: ``|L|`` does not cross 1).

    Examples
    --------
    An integrator with one sample of delay, ``L = 0.2 / ((z - 1) z)`` at ``dt = 0.1``: ``|z - 1| = 0.2`` at
    ``w = (2/dt) asin(0.1)``, where ``arg L = -(90 deg + 1.5 w dt)``:

    >>> [(p, w)] = gain_crossovers([0.2], [1.0, -1.0, 0.0], 0.1)
    >>> w_c = 20.0 * math.asin(0.1)
    >>> abs(w - w_c) < 1e-12, abs(p - (90.0 - math.degrees(1.5 * w_c * 0.1))) < 1e-9
    (True, True)
    """
    num, den = np.asarray(num, dtype=float), np.asarray(den, dtype=float)
    w_nyq = math.pi / dt

    def L(w):
        z = (np.expm1 if delta else np.exp)(1j * np.asarray(w) * dt)
        return np.polyval(num, z) / np.polyval(den, z)

    w = np.logspace(math.log10(w_nyq) - 6.0, math.log10(w_nyq), points)
    w[-1] = w_nyq
    excess = np.abs(L(w)) - 1.0
    found = []
    for i in np.flatnonzero(np.sign(excess[:-1]) * np.sign(excess[1:]) < 0):
        lo, hi = float(w[i]), float(w[i + 1])
        up = excess[i] > 0
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if mid in (lo, hi):
                break
            if (abs(L(mid)) - 1.0 > 0) == up:
                lo = mid
            else:
                hi = mid
        wc = 0.5 * (lo + hi)
        pm = (180.0 + math.degrees(float(np.angle(L(wc)))) + 180.0) % 360.0 - 180.0
        found.append((pm, wc))
    return found


def closed_loop(C, H, d: int) -> dict:
    """The sampled loop of the discrete PID ``C`` around the discrete plant ``H`` with ``d`` samples of delay:
    ``C``, ``H``, ``L = C z^-d H`` and ``S``, ``T``, ``PS``, ``CS`` (python-control systems; the one assembly,
    also of :func:`obsdesign.design.plant_loop.plant_loop`).

    Parameters
    ----------
    C, H : control.TransferFunction
        The discrete PID and the discrete plant, of one sample time.
    d : int
        The drive's delay [samples].

    Returns
    -------
    dict of str to control.TransferFunction
    """
    import control as ct

    dt = C.dt
    Cd = C * ct.tf([1.0], [1.0] + [0.0] * d, dt)  # C z^-d
    L = Cd * H
    one = ct.tf([1.0], [1.0], dt)
    return {"C": C, "H": H, "L": L, "S": ct.feedback(one, L), "T": ct.feedback(L, one), "PS": ct.feedback(H, Cd),
            "CS": ct.feedback(Cd, H)}


def drive_delay(cfg, delay_samples=None) -> int:
    """The drive's delay ``d`` [samples] a loop view closes the loop with: the config's
    ``[hardware] delay_samples``, or ``delay_samples`` given (another delay around the same gains).

    Read by :func:`obsdesign.design.sampled_loop.sampled_loop` and
    :func:`obsdesign.design.plant_loop.plant_loop` (the time-domain loop reads the config's,
    :attr:`obsdesign.loop.LoopInputs.delay_samples`).

    Parameters
    ----------
    cfg : Config
        The design.
    delay_samples : int, optional
        An integer in [0, 10000]; None: the config's.

    Examples
    --------
    >>> import obsdesign as od
    >>> drive_delay(od.load_preset("vcm").override(delay_samples=2)), drive_delay(od.load_preset("vcm"), 1)
    (2, 1)
    >>> drive_delay(od.load_preset("vcm"), -1)
    Traceback (most recent call last):
    ...
    ValueError: delay_samples: expected an integer >= 0 and <= 10000, found -1
    """
    if delay_samples is None:
        return cfg.hardware.delay_samples
    from .._validate import MAX_DELAY_SAMPLES, check_integer

    return check_integer("delay_samples", delay_samples, minimum=0, maximum=MAX_DELAY_SAMPLES)
