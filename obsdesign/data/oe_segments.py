"""Segment output error: LuGre friction and the rigid-body parameters fitted to the logged position.

The record is cut into segments of ``L`` samples. Each segment is simulated under the logged force
(held over a sample, or interpolated when logged as it acted; the position compared ``d`` samples later,
the timing and delay :func:`~obsdesign.data.identify` found, :mod:`obsdesign.data.timing`) from its own
initial position, velocity and bristle force, three nuisance parameters per segment estimated with the
rest. A free inertia integrates any force error into a position error that grows without bound over a
whole record; over a segment it cannot, and the fit of the mass, viscous, Coulomb and offset terms is not
biased by the low-pass filter the equation-error fit (IDIM-LS) needs. The nuisances are projected out of
the normal equations per segment (a Schur complement), so a Levenberg-Marquardt step costs the
simulations of the global parameters plus three.

The bristle parameters (``sigma0``, ``sigma1``) make the cost non-convex: each one asked for is profiled
over its plausible range (the other parameters refitted at every point), and it is called identifiable only
when the profile has one minimum and the profile's interval lies inside the range; otherwise the profile
interval is reported instead.

Examples
--------
>>> segment_bounds(1000, 400, skip=50).tolist()
[[50, 400], [450, 400]]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .oe_segment_sim import SUBSTEP_RULE as SUBSTEP_RULE
from .oe_segment_sim import BudgetExceeded as BudgetExceeded
from .oe_segment_sim import _Budget, _Segments
from .oe_segment_sim import segment_bounds as segment_bounds
from .oe_segment_sim import simulate_segments as simulate_segments
from .oe_segment_sim import substeps as substeps
from .oe_stats import segment_covariance

__all__ = ["SEGMENT", "DYNAMIC", "STATIC", "UNITS", "DAMPING_STARTS", "PROFILE_POINTS", "PROFILE_ITERATIONS",
           "SUBSTEP_RULE", "SegmentFit", "segment_bounds", "substeps", "simulate_segments",
           "fit_segments", "profile_fits", "summarize", "BudgetExceeded"]

#: Default segment length [s] of the final stage (the review's 0.1 s: the bound converged there).
SEGMENT = 0.1
#: The stages before it, as fractions of it (short segments first: robust to a poor start).
_STAGES = (0.1, 0.25, 1.0)
#: Starts of the bristle damping ratio ``sigma1 / (2 sqrt(sigma0 m))`` of the first stage (the best is kept):
#: from one start (0.5) a 1 kHz linear log ended with sigma1 4.7 times the truth and the mass +0.26 %; the
#: stages run from each start and the lowest final cost wins (chosen after the first stage, the short segments
#: picked a worse basin).
DAMPING_STARTS = (0.03, 0.3, 3.0)
#: Iterations of the refit of each alternative reading of the log's timing (fewer than the fit's own: an
#: alternative that fits better all the same is clearly better). With 6, on a 1 kHz linear log (held input,
#: no delay) that identify read as "as logged", the true reading had not converged from the wrong one's
#: optimum (BIC +91, the refit's mass -0.05 %) and the fit, 14.6 times the noise, was called identifiable
#: with a mass +0.47 % (9 standard errors); with 20 the true reading wins by BIC -410.
ALTERNATIVE_ITERATIONS = 20
#: The rigid-body and static friction parameters, always fitted.
STATIC = ("m", "sigma", "Cf", "offset")
#: The note of a bristle parameter fitted but not profiled (not asked for): on the 4 kHz rotary benchmark axis its
#: Jacobian standard error was 6.5 (sigma0) and 2.5 (sigma1) times the exact linearized one under the current's
#: noise (their information sits in about 5 of 119 segments), and sigma0's interval covered 5 of 8 draws.
UNPROFILED = "fitted, not profiled: its Jacobian interval can be several times too narrow; ask for it to profile it"
#: The bristle parameters, profiled when asked for.
DYNAMIC = ("sigma0", "sigma1")
#: Points of a profile over a parameter's plausible range.
PROFILE_POINTS = 11
#: Levenberg-Marquardt iterations at each point of a profile (each starts from its neighbour's optimum).
PROFILE_ITERATIONS = 6
#: Units of the parameters on a linear axis driven by a force (converted with :meth:`obsdesign.axis.AxisSpec.unit`).
UNITS = {"m": "kg", "sigma": "N s/m", "Cf": "N", "offset": "N", "Fs": "N", "vs": "m/s", "sigma0": "N/m",
         "sigma1": "N s/m"}
_LOG = {"m", "Cf", "Fs", "vs", "sigma0"}


@dataclass(frozen=True, kw_only=True)
class SegmentFit:
    """Result of :func:`fit_segments` (values in SI; ``units`` gives the axis's).

    Attributes
    ----------
    names : tuple of str
        The fitted global parameters.
    values, std, intervals, identifiable, notes : dict
        By name: estimates, standard errors, 95 % intervals (the profile's where one was computed and the
        parameter is not identified), whether identifiable, and why not (or ``""``).
    profiles : dict
        Name -> ``(grid, cost)`` of each profiled parameter (cost: the weighted RSS).
    segment_samples, segments : int
        ``L`` and the number of segments of the final stage.
    rms, noise : float
        RMS of the position residual and the noise level it is weighted by [m or rad].
    evaluations : int
        Simulations of the whole record.
    stopped : str
        ``""``, or why the fit stopped before it finished (the time budget).
    alternatives : dict
        Label -> ``segments x ln(MS_alternative / MS_fit)`` of each other reading of the log's timing tried
        (negative: the alternative fits better, though refitted with fewer iterations).
    substeps : int
        Heun sub-steps a sample of the final fit's simulation.
    """

    names: tuple
    values: dict
    std: dict
    intervals: dict
    identifiable: dict
    notes: dict
    profiles: dict
    segment_samples: int
    segments: int
    rms: float
    noise: float
    evaluations: int
    stopped: str
    alternatives: dict
    substeps: int = 0


def _theta(name, value):  # the fitted coordinate: ln p for a positive parameter
    return math.log(value) if name in _LOG else value


def _value(name, theta):  # its inverse
    return math.exp(min(theta, 700.0)) if name in _LOG else theta


def _scale(name, q):
    """Finite-difference step of ``name`` in its fitted coordinate (relative for a log one)."""
    if name in _LOG:
        return 1e-4
    size = {"sigma": max(abs(q["sigma"]), 1e-3 * q["Cf"]), "offset": max(abs(q["offset"]), q["Cf"]),
            "sigma1": max(abs(q["sigma1"]), math.sqrt(q["sigma0"] * q["m"]))}[name]
    return 1e-4 * size


def _gauss_newton(seg, names, q, nu, *, iterations):
    """Levenberg-Marquardt over ``names`` and the nuisances; returns ``(q, nu, cost, moments)``."""
    q = dict(q)
    nu = nu.copy()
    seg.n_sub = substeps(q["sigma0"], q["m"], seg.dt)
    lam = 1e-3
    r = seg.residual(q, nu)
    cost = float(np.sum(r * r))
    mom = None
    for _ in range(iterations):
        Jg = np.empty(r.shape + (len(names),))
        for j, n in enumerate(names):
            h = _scale(n, q)
            qq = dict(q)
            qq[n] = _value(n, _theta(n, q[n]) + h)
            Jg[..., j] = (seg.residual(qq, nu) - r) / h
        Jn = np.empty(r.shape + (3,))
        for j in range(3):
            h = 1e-3 * max(1.0, float(np.max(np.abs(nu[:, j]))))
            step = nu.copy()
            step[:, j] += h
            Jn[..., j] = (seg.residual(q, step) - r) / h
        A = np.einsum("slg,slh->gh", Jg, Jg)
        B = np.einsum("slg,sln->sgn", Jg, Jn)
        C = np.einsum("slm,sln->smn", Jn, Jn)
        bg = np.einsum("slg,sl->g", Jg, r)
        bn = np.einsum("sln,sl->sn", Jn, r)
        mom = (A, B, C, Jg, Jn)
        improved = False
        for _try in range(8):
            Cd = C + lam * (np.einsum("snn->sn", C)[:, :, None] * np.eye(3) + 1e-12 * np.eye(3))
            Cinv = np.linalg.inv(Cd)
            S = A + lam * np.diag(np.diag(A)) - np.einsum("sgn,snm,shm->gh", B, Cinv, B)
            rhs = bg - np.einsum("sgn,snm,sm->g", B, Cinv, bn)
            try:
                dg = -np.linalg.solve(S + 1e-12 * np.trace(S) * np.eye(len(names)) / max(len(names), 1), rhs)
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            dn = -np.einsum("snm,sm->sn", Cinv, bn + np.einsum("sgn,g->sn", B, dg))
            qq = {**q, **{n: _value(n, _theta(n, q[n]) + d) for n, d in zip(names, dg)}}
            r_new = seg.residual(qq, nu + dn)
            c_new = float(np.sum(r_new * r_new))
            if c_new < cost:
                q, nu, r, improved = qq, nu + dn, r_new, True
                drop = (cost - c_new) / max(cost, 1e-300)
                cost = c_new
                lam = max(lam / 5.0, 1e-9)
                break
            lam *= 10.0
        if not improved or drop < 1e-7:
            break
    return q, nu, cost, r, mom


def _smooth(x, dt):
    """Zero-phase low-passed position (a tenth of the rate) and its derivative: the segments' first states."""
    from scipy import signal

    sos = signal.butter(4, 0.1 / dt, fs=1.0 / dt, output="sos")
    x_f = signal.sosfiltfilt(sos, x)
    return x_f, np.gradient(x_f, dt)


def _bristle_start(seg, q):
    """Nuisances at the segments' smoothed states, the bristle force at the sliding level in the direction of motion."""
    nu = np.zeros((seg.starts.size, 3))
    nu[:, 2] = np.where(np.abs(seg.v0) > 1e-9, np.sign(seg.v0), 0.0)
    return nu


def fit_segments(x_meas, force, *, dt, hold, noise, start, free, profile=(), segment=SEGMENT, time_budget=None,
                 bar=None, ranges=None, alternatives=None):
    """Fit LuGre and the rigid body by segment output error (see the module's notes).

    Parameters
    ----------
    x_meas, force : ndarray
        Position [m or rad] aligned with the force [N or N m] (the delay taken out).
    dt : float
        Sample time [s].
    hold : bool
        Whether the force is held over a sample (else interpolated).
    noise : float
        Position noise RMS [m or rad] the residual is weighted by.
    start : dict
        Starting values of ``m, sigma, Cf, offset, Fs, vs, sigma0, sigma1``.
    free : tuple of str
        The global parameters fitted.
    profile : tuple of str
        Those of ``free`` profiled over ``ranges[name]``.
    segment : float
        Final segment length [s].
    time_budget : float, optional
        Seconds; when they run out the best fit so far is returned with ``stopped`` set.
    bar : tqdm or None
        Progress bar updated per simulation.
    ranges : dict
        Name -> ``(low, high)`` of each profiled parameter.
    alternatives : dict, optional
        Label -> ``(x_meas, force, hold)``: other readings of the log's timing, each refitted from the optimum
        with :data:`ALTERNATIVE_ITERATIONS` iterations and compared by mean square residual.

    Returns
    -------
    SegmentFit
    """

    budget = _Budget(time_budget, bar)
    skip = 50
    x_f, v_f = _smooth(x_meas, dt)
    checked: dict = {}
    final = max(20, int(round(segment / dt)))
    n_sub = substeps(start["sigma0"], start["m"], dt)
    stopped, best, seg, partial, profiles = "", None, None, [], {}

    def chain(q):
        """The stages from ``q``: segments of L/10, L/4, then L, each from the last optimum."""
        for frac in _STAGES:
            length = max(20, int(round(final * frac)))
            sg = _Segments(x_meas, force, x_f, v_f, dt, length, skip, hold, noise, n_sub, budget)
            fit = _gauss_newton(sg, free, q, _bristle_start(sg, q), iterations=30 if frac == 1.0 else 12)
            q = fit[0]
            partial[:] = [fit, sg]
        for _ in range(2):  # the substeps follow the bristle stiffness found: refit where they changed
            if substeps(q["sigma0"], q["m"], dt) == sg.n_sub:
                break
            fit = _gauss_newton(sg, free, q, fit[1], iterations=30)
            q = fit[0]
            partial[:] = [fit, sg]
        return fit, sg

    crit = 2.0 * math.sqrt(start["sigma0"] * start["m"])
    starts = [{**start, "sigma1": zeta * crit} for zeta in DAMPING_STARTS] if "sigma1" in free else [dict(start)]
    try:
        for q0 in starts:  # multi-start over the bristle damping; the lowest final cost wins
            fit, sg = chain(q0)
            if best is None or fit[2] < best[2]:
                best, seg = fit, sg
        held = [best]
        try:
            profile_fits(seg, free, held, profile, ranges, profiles)
        finally:
            best = held[0]
        ms = best[2] / best[3].size
        for label, (xa, ua, ha) in (alternatives or {}).items():
            sa = _Segments(xa, ua, *_smooth(xa, dt), dt, seg.length, skip, ha, noise, seg.n_sub, budget)
            fa = _gauss_newton(sa, free, best[0], _bristle_start(sa, best[0]), iterations=ALTERNATIVE_ITERATIONS)
            checked[label] = float(seg.starts.size * math.log(max(fa[2] / fa[3].size, 1e-300) / max(ms, 1e-300)))
    except BudgetExceeded:
        stopped = f"stopped at the time budget of {time_budget:g} s with the best fit so far"
        if best is None and partial and partial[0][4] is not None:
            best, seg = partial
        if best is None or best[4] is None:
            raise
    return summarize(seg, best, free, profiles, noise=noise, dt=dt, evaluations=budget.count, stopped=stopped,
                     alternatives=checked)


def profile_fits(seg, free, held, profile, ranges, profiles):
    """Profile each of ``profile`` over ``ranges[name]`` (the other parameters of ``free`` refitted at every point,
    each from its neighbour's optimum) into ``profiles``, and keep the best fit in ``held``: both are filled in
    place as each profile ends, so a time budget that runs out keeps what was done.

    Parameters
    ----------
    seg : _Segments
        The segments of the final stage.
    free : tuple of str
        The fitted global parameters.
    held : list
        ``[best]``: the best fit (``_gauss_newton``'s tuple ``(q, nu, cost, r, moments)``), replaced where a
        profile's point refits to a lower cost.
    profile : tuple of str
        The parameters of ``free`` to profile.
    ranges : dict
        Name -> ``(low, high)`` of each profiled parameter (a geometric grid of :data:`PROFILE_POINTS` where
        ``low > 0``).
    profiles : dict
        Filled: name -> ``(grid, cost)`` (cost: the weighted RSS).
    """
    best = held[0]
    for name in profile:
        lo, hi = ranges[name]
        logg = lo > 0
        grid = np.geomspace(lo, hi, PROFILE_POINTS) if logg else np.linspace(lo, hi, PROFILE_POINTS)
        rest = tuple(n for n in free if n != name)
        costs = np.empty(grid.size)
        qa, nua = dict(best[0]), best[1]
        here = max(best[0][name], 1e-300)
        order = np.argsort(np.abs(np.log(grid / here)) if logg else np.abs(grid - here))
        fitted = {}
        for k in order:
            near = min(fitted, key=lambda j: abs(j - k)) if fitted else None
            qs, nus = (fitted[near][0], fitted[near][1]) if near is not None else (qa, nua)
            qs = {**qs, name: float(grid[k])}
            qk, nuk, ck, _r, _m = _gauss_newton(seg, rest, qs, nus, iterations=PROFILE_ITERATIONS)
            fitted[k] = (qk, nuk)
            costs[k] = ck
        profiles[name] = (grid, costs)
        k = int(np.argmin(costs))
        if costs[k] < best[2] * (1 - 1e-6):  # a better basin than the start's: refit from it
            q2, nu2, c2, r2, m2 = _gauss_newton(seg, free, fitted[k][0], fitted[k][1], iterations=30)
            if c2 < best[2]:
                best = held[0] = (q2, nu2, c2, r2, m2)


def summarize(seg, best, free, profiles, *, noise, dt, evaluations, stopped="", alternatives=None):
    """The :class:`SegmentFit` of ``best`` on ``seg``: the covariance and intervals, the profiles read (one
    minimum within the interval and inside the range, else the profile's interval), and the notes.

    Parameters
    ----------
    seg : _Segments
        The segments the fit ran on.
    best : tuple
        ``_gauss_newton``'s ``(q, nu, cost, r, moments)``.
    free : tuple of str
        The fitted global parameters.
    profiles : dict
        Name -> ``(grid, cost)`` (:func:`profile_fits`).
    noise : float
        The position noise RMS the residual is weighted by [m or rad].
    dt : float
        Sample time [s].
    evaluations : int
        Simulations run (reported).
    stopped : str
        Why the fit stopped early (the time budget), or ``""``: every parameter is then not identified.
    alternatives : dict, optional
        Label -> BIC of each other reading of the log's timing tried (reported).

    Returns
    -------
    SegmentFit
    """
    from scipy import stats

    checked = alternatives or {}
    q, nu, cost, r, mom = best
    seg.n_sub = substeps(q["sigma0"], q["m"], dt)  # the rule at the estimate (what a refit would use)
    if not np.all(np.abs(r) < 1e6):
        raise FloatingPointError("the model could not be simulated from the start (IDIM-LS's estimate) on every "
                                 "segment")
    var, white = segment_covariance(free, r, mom)
    tq = float(stats.t.ppf(0.975, max(r.shape[0] - 1, 1)))
    design = {}
    values, std, intervals, ident, notes = {}, {}, {}, {}, {}
    for i, n in enumerate(free):
        sd = math.sqrt(var[i]) if np.isfinite(var[i]) else math.inf
        design[n] = var[i] / white[i] if white[i] > 0 else 1.0
        th = _theta(n, q[n])
        lo_v, hi_v = (_value(n, th - tq * sd), _value(n, th + tq * sd))
        values[n] = q[n]
        std[n] = sd * (q[n] if n in _LOG else 1.0)
        intervals[n] = (lo_v, hi_v)
        ident[n], notes[n] = True, ""
        if n == "sigma1" and q[n] <= 0.0:  # the model runs a negative damping as 0: the cost is flat below it
            values[n] = 0.0
            intervals[n] = (0.0, max(hi_v, tq * sd) if math.isfinite(sd) else math.inf)
            ident[n], notes[n] = False, "at its lower bound 0 (a damping is not negative): the data do not pin it"
            continue
        if n == "sigma1":  # a damping is not negative
            intervals[n] = (max(lo_v, 0.0), hi_v)
        if not math.isfinite(sd) or (n in _LOG and tq * sd > 0.5):
            ident[n], notes[n] = False, "95 % interval wider than a factor 1.65 either way"
        elif n not in _LOG and n != "offset" and tq * sd > abs(q[n]):
            ident[n], notes[n] = False, "95 % interval includes 0"
    if stopped:
        for n in free:
            ident[n], notes[n] = False, "the fit stopped at the time budget before it converged"
    s2 = cost / max(r.size - len(free) - 3 * r.shape[0], 1)
    for name, (grid, costs) in profiles.items():
        thr = float(np.min(costs)) + stats.chi2.ppf(0.95, 1) * s2 * max(design.get(name, 1.0), 1.0)
        inside = costs <= thr
        k = int(np.argmin(costs))
        minima = [j for j in range(grid.size) if inside[j] and (j == 0 or costs[j] <= costs[j - 1]) and
                  (j == grid.size - 1 or costs[j] <= costs[j + 1])]  # those within the interval it reports
        runs = np.flatnonzero(np.diff(np.r_[0, inside.astype(int), 0]) == 1).size
        low = grid[max(int(np.flatnonzero(inside)[0]) - 1, 0)]
        high = grid[min(int(np.flatnonzero(inside)[-1]) + 1, grid.size - 1)]
        edge = inside[0] or inside[-1]
        if stopped:
            continue
        if len(minima) > 1 or runs > 1 or edge:
            why = ("the profile has several minima" if len(minima) > 1 or runs > 1
                   else "the profile stays within the threshold at the edge of the range")
            ident[name] = False
            notes[name] = f"{why}: the data do not pin it; the profile interval is the honest one"
            intervals[name] = (min(float(low) if not inside[0] else float(grid[0]), values[name]),
                               max(float(high) if not inside[-1] else float(grid[-1]), values[name]))
        else:
            lo_i, hi_i = intervals[name]  # the union: the Jacobian's was 2.5 to 6.5 times too narrow (RESULTS.md)
            intervals[name] = (min(lo_i, float(low)), max(hi_i, float(high))) if ident[name] else (float(low),
                                                                                                    float(high))
            if not grid[k - 1] <= values[name] <= grid[k + 1] and not notes[name].startswith("at its lower bound"):
                ident[name] = False
                notes[name] = "the fit did not end in the profile's minimum"
            lo_i, hi_i = intervals[name]
            intervals[name] = (min(lo_i, values[name]), max(hi_i, values[name]))
    for name in (n for n in DYNAMIC if n in free and n not in profiles and ident[n]):
        ident[name], notes[name] = False, UNPROFILED
    return SegmentFit(names=tuple(free), values=values, std=std, intervals=intervals, identifiable=ident,
                      notes=notes, profiles=profiles, segment_samples=seg.length, segments=int(seg.starts.size),
                      rms=float(np.sqrt(np.mean(r * r))) * noise, noise=noise, evaluations=evaluations,
                      stopped=stopped, alternatives=checked, substeps=seg.n_sub)
