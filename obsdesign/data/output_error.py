"""Dynamic friction by output error: pre-sliding ``s``, LuGre/GMS parameters and a sensor delay.

:func:`refine` simulates the plant under the logged force over windows of the record (each from
its own initial state, :mod:`obsdesign.data.oe_plant`) and fits the chosen parameters to the logged
position with :func:`scipy.optimize.least_squares`; the rest come from :func:`~obsdesign.data.identify`.
Intervals come from the Jacobian at the optimum, with the windows as independent clusters of
correlated residuals; a parameter whose direction the data do not resolve is flagged
``identifiable = False`` with the reason. See docs/measured-data.md ("Dynamic friction by output error").

Examples
--------
>>> sorted(refinable("paper"))
['Cf', 'delay', 'm', 'offset', 's', 'sigma']
>>> refinable("lugre")
('m', 'sigma', 'Cf', 'offset', 'Fs', 'vs', 'sigma0', 'sigma1')
>>> refinable("lugre", "windows")[-4:]
('sigma0', 'sigma1', 'm', 'delay')
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from ..axis import AxisSpec
from .._validate import check_choice
from ..friction.registry import FRICTION_MODELS
from .identify import Identification
from .oe_plant import PAPER_LAYOUT, select_windows, simulate_windows
from .oe_names import METHODS, MODELS, RefineFailed, default_method, refinable
from .oe_segment_refine import SegmentRefinement, refine_segments
from .oe_segments import SEGMENT, BudgetExceeded
from .oe_stats import NEAR_NULL, _grouped_jacobian, _held_sensitivity, _moments, _null_loadings, _pinv, _scan_s
from .trace import Trace

__all__ = ["RefinedParameter", "Refinement", "RefineFailed", "refine", "refinable", "default_method", "METHODS", "MODELS", "NEAR_NULL", "TRAVEL",
           "WINDOW"]


#: Default travel [m] after which the friction is taken as saturated (the windows start beyond it).
TRAVEL = 1e-3
#: Default time [s] a window starts before its first reversal and runs on after the sliding resumes.
WINDOW = 0.05
#: Largest half-width of the 95 % interval of ln(p) for a positive parameter to count as identified.
MAX_LOG_HALF_WIDTH = 0.5


@dataclass(frozen=True, kw_only=True)
class RefinedParameter:
    """One refined parameter.

    Attributes
    ----------
    name, unit : str
        Its name (of :func:`refinable`) and unit.
    value, initial : float
        The estimate and the starting value.
    std : float
        Standard error (``inf`` in a near-null direction); for a positive parameter, of ``ln(value)``
        times ``value``.
    low, high : float
        The 95 % interval (``-inf``/``inf`` when not resolved).
    identifiable : bool
        Whether the data resolve it (interval narrow enough, not at a bound, not in a null direction).
    note : str
        Why not, or ``""``.
    """

    name: str
    unit: str
    value: float
    initial: float
    std: float
    low: float
    high: float
    identifiable: bool
    note: str = ""


@dataclass(frozen=True, kw_only=True)
class Refinement:
    """Result of :func:`refine`.

    Attributes
    ----------
    model : str
        The plant friction model simulated.
    parameters : tuple of RefinedParameter
        The refined parameters, in the order asked.
    fixed : dict
        The values held, by name (from the identification and the model's defaults).
    windows, reversals, samples : int
        Windows simulated, reversals inside them, residual samples.
    rms_initial, rms : float
        RMS of measured minus simulated position [m] before and after the fit.
    condition_number : float
        Of the scaled Jacobian of the refined parameters (initial states of the windows projected out).
    evaluations : int
        Simulations of all windows (the fit and its Jacobians, the start scan).
    wall_time : float
        Seconds.
    length_unit : str
        ``'m'``, or ``'rad'`` on a rotary axis (the units of the parameters are those of the axis).
    """

    model: str
    parameters: tuple[RefinedParameter, ...]
    fixed: dict
    windows: int
    reversals: int
    samples: int
    rms_initial: float
    rms: float
    condition_number: float
    evaluations: int
    wall_time: float
    length_unit: str = "m"

    def __getitem__(self, name: str) -> RefinedParameter:
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(f"{name!r} was not refined; refined: {', '.join(p.name for p in self.parameters)}")

    def to_dict(self) -> dict:
        """JSON-ready: ``model, windows, reversals, samples, rms_initial, rms, condition_number, evaluations,
        wall_time`` and ``parameters`` (name -> ``value, initial, std, low, high, unit, identifiable, note``)."""
        out = {k: getattr(self, k) for k in ("model", "windows", "reversals", "samples", "rms_initial", "rms",
                                             "condition_number", "evaluations", "wall_time")}
        out["parameters"] = {p.name: {k: getattr(p, k) for k in ("value", "initial", "std", "low", "high", "unit",
                                                                 "identifiable", "note")} for p in self.parameters}
        return out

    def apply(self, ident: Identification) -> Identification:
        """``ident`` with a refined, identifiable ``s`` (its ``s_note`` saying so); otherwise unchanged.

        Parameters
        ----------
        ident : Identification
            The static fit the refinement started from.
        """
        if "s" not in {p.name for p in self.parameters} or not self["s"].identifiable:
            return ident
        p = self["s"]
        return replace(ident, s=p.value, s_note=f"output error over {self.windows} windows ({self.reversals} "
                                                f"reversals): 95 % interval {p.low:.4g} to {p.high:.4g} {p.unit}")

    def __str__(self) -> str:
        lines = [f"Output-error refinement ({self.model}): {self.windows} windows, {self.reversals} reversals, "
                 f"{self.samples} samples; RMS position error {self.rms_initial:.3g} -> {self.rms:.3g} {self.length_unit}; "
                 f"condition number {self.condition_number:.3g}"]
        for p in self.parameters:
            verdict = "identifiable" if p.identifiable else f"NOT identifiable: {p.note}"
            lines.append(f"  {p.name:<8} {p.value:.5g} {p.unit}  95 % [{p.low:.5g}, {p.high:.5g}]  "
                         f"(start {p.initial:.4g})  {verdict}")
        return "\n".join(lines)


def _exp(x: float) -> float:
    """``exp(x)``, ``inf`` beyond the float range (an interval of ``ln p`` too wide to print as numbers)."""
    return math.exp(x) if x < 709.0 else math.inf


class _Problem:
    """The parameter vector ``[globals..., (dx0, dv0) per window]`` and the residual."""

    def __init__(self, trace, ident, model, names, initial, travel, window, substeps):
        from scipy import signal

        self.trace, self.ident, self.model, self.names = trace, ident, model, tuple(names)
        self.axis = AxisSpec(kind=trace.units.axis)  # the units of the log's axis (kg m^2, N m, rad if rotary)
        self.dt = dt = trace.sample_time
        fs = 1.0 / dt
        sos = signal.butter(4, 0.1 * fs, fs=fs, output="sos")
        x_f = signal.sosfiltfilt(sos, trace.position)
        v_f = np.gradient(x_f, dt)
        scale = max(ident.noise_rms, ident.quantization / math.sqrt(12.0), 1e-12)
        n_win = max(1, int(round(window / dt)))
        skip = 50  # samples of the zero-phase filter's transients at both ends (5 periods of its cut-off)
        self.starts, self.lengths, self.reversals, self.dirs = select_windows(
            x_f, threshold=max(5.0 * ident.noise_rms, 2.0 * ident.quantization, 1e-9), travel=travel,
            lead=n_win, tail=n_win, skip=skip)
        self.x0, self.v0 = x_f[self.starts], v_f[self.starts]
        self.scale, self.travel, self.substeps = scale, travel, substeps
        self.values = self._base(ident, initial)
        self.rows = np.concatenate([np.arange(s, s + n) for s, n in zip(self.starts, self.lengths)]) \
            if self.starts.size else np.empty(0, np.int64)
        self.meas = trace.position[self.rows]
        self.out = np.empty(self.rows.size)
        self.evaluations = 0
        self.deadline: float | None = None

    def _base(self, ident, initial):
        asym = ident.model == "asymmetric"
        q = {"m": ident.m, "offset": ident.offset, "delay": 0.0,
             "Cf": ident.Cf_pos if asym else ident.Cf, "Cf_neg": ident.Cf_neg if asym else ident.Cf,
             "sigma": ident.sigma_pos if asym else ident.sigma, "sigma_neg": ident.sigma_neg if asym else ident.sigma}
        if self.model == "paper":
            q.update(s=ident.s if ident.s is not None else 1.0 / (0.1 * self.travel), beta=0.0, kappa=1.0)
        else:
            info = FRICTION_MODELS[self.model]
            q.update({k: v for k, v in info.defaults().items() if k not in q})
            q["Fs"] = q["Cf"]  # the static fit has no Stribeck term: start without one
        for k, v in (initial or {}).items():
            q[k] = float(v)
        return q

    # -- parameter transforms ------------------------------------------------------------------
    def spec(self, name):
        """``(unit, low, high, log)`` of a refined name."""
        if name == "m":
            return self.axis.mass_unit, 1e-9, 1e9, True
        if name == "delay":
            return "s", 0.0, 10.0 * self.dt, False
        if name == "offset":
            return self.axis.force_unit, -1e6, 1e6, False
        info = FRICTION_MODELS[self.model]
        spec = {p.name: p for p in info.parameters}[name]
        low = spec.low
        if name == "s":
            low = max(low, 1.0 / self.travel)
        return self.axis.unit(spec.unit), low, spec.high, low > 0

    def to_theta(self, name, value):
        return math.log(value) if self.spec(name)[3] else value

    def from_theta(self, name, theta):
        return math.exp(theta) if self.spec(name)[3] else theta

    def assign(self, q, values):
        """``q`` with ``values`` set; ``Cf`` and ``sigma`` move their negative-side values in proportion."""
        for name, value in values.items():
            if name in ("Cf", "sigma"):
                q[name + "_neg"] = value * self.values[name + "_neg"] / self.values[name]
            if name == "Cf" and "Fs" in q and "Fs" not in self.names:  # a held stiction level keeps its ratio
                q["Fs"] = value * self.values["Fs"] / self.values["Cf"]
            q[name] = value
        return q

    def pack(self, q):
        if self.model == "paper":
            return np.array([q[k] for k in PAPER_LAYOUT], dtype=np.float64)
        info = FRICTION_MODELS[self.model]
        given = {p.name for p in info.parameters}
        return info.pack({k: v for k, v in q.items() if k in given})

    # -- simulation ----------------------------------------------------------------------------
    def simulate(self, q, dx0, dv0):
        self.evaluations += 1
        code = FRICTION_MODELS.code(self.model)
        ok = simulate_windows(code, self.pack(q), self.trace.force, self.starts, self.lengths, self.x0 + dx0,
                              self.v0 + dv0, self.dirs, q["m"], self.dt, self.substeps, self.travel, self.out)
        x = self.out.copy()
        delay = q["delay"] / self.dt
        if delay > 0.0:
            k, f = int(math.floor(delay)), delay - math.floor(delay)
            pos = 0
            for n in self.lengths:
                seg = x[pos:pos + n].copy()
                for j in range(n):
                    a, b = max(j - k, 0), max(j - k - 1, 0)
                    x[pos + j] = (1.0 - f) * seg[a] + f * seg[b]
                pos += n
        return x, ok

    def residual(self, p):
        if self.deadline is not None and time.perf_counter() > self.deadline:
            raise BudgetExceeded
        g = len(self.names)
        q = self.assign(dict(self.values), {n: self.from_theta(n, t) for n, t in zip(self.names, p[:g])})
        w = self.starts.size
        dx0 = p[g:g + w] * self.scale
        dv0 = p[g + w:g + 2 * w] * self.scale / self.dt
        try:
            x, ok = self.simulate(q, dx0, dv0)
        except ValueError:  # a combination the model refuses (Fs below Cf): as bad as a diverged run
            return np.full(self.meas.size, 1e6)
        r = (self.meas - x) / self.scale
        return np.where(np.isfinite(r), r, 1e6)


def refine(trace: Trace, ident: Identification, *, parameters: tuple[str, ...] = ("s",), model: str = "paper",
           initial: dict | None = None, travel: float = TRAVEL, window: float = WINDOW,
           substeps: int = 10, segment: float = SEGMENT, time_budget: float | None = None,
           progress: bool = False, method: str | None = None) -> Refinement | SegmentRefinement:
    """Refine dynamic friction parameters (and a sensor delay) by output error against the logged position.

    Parameters
    ----------
    trace : Trace
        The record (open or closed loop: the logged force is the input the plant received).
    ident : Identification
        The static fit of the same trace (:func:`obsdesign.data.identify`): mass, viscous and Coulomb
        friction, offset, noise level; the values not refined are held at it.
    parameters : tuple of str
        Names of :func:`refinable` for ``model``.
    model : str
        A name of :data:`MODELS`, the plant friction model: the paper's pre-sliding memory (eq:2:3:1-2:3:5, static viscous
        friction), LuGre or GMS (:mod:`obsdesign.friction`).
    initial : dict, optional
        Starting values by name (default: the identification, ``s`` from it or scanned, the model's
        registry defaults, ``Fs = Cf``, delay 0).
    travel : float
        Travel [m] after which the friction is saturated: windows start and end that far into a
        gross-sliding stroke, and ``s >= 1/travel``.
    window : float
        Time [s] a window starts before its reversal and runs on after the friction saturated.
    substeps : int
        Heun substeps of the plant per sample (``paper``, ``gms``).
    segment : float
        Segment length [s] of the segment fit (``lugre``: :mod:`obsdesign.data.oe_segments`).
    time_budget : float, optional
        Seconds: ``lugre`` stops with the best fit so far (and says so); ``paper``/``gms`` raise
        :class:`RefineFailed`.
    progress : bool
        A progress bar with an ETA on stderr.
    method : str, optional
        A name of :data:`METHODS` (default: :func:`default_method`).

    Returns
    -------
    Refinement or SegmentRefinement
        ``lugre``: the segment fit (:func:`obsdesign.data.oe_segments.refine_segments`), the others the windows'.

    Raises
    ------
    ValueError
        An unknown model or parameter, a bad travel/window/substeps, a record with no window.
    RefineFailed
        A numerical failure of the fit, or the time budget ran out before a first fit.

    Notes
    -----
    Residual: ``(x_meas - x_sim) / eta`` on every sample of every window, ``eta`` the identification's
    noise RMS (at least the quantization's ``q / sqrt 12``). Per window the initial displacement and
    velocity are fitted too (2 nuisance parameters; a row depends only on its own window's, so the
    finite-difference Jacobian costs ``len(parameters) + 2`` simulations). Positive parameters are fitted as ``ln p``. A
    fitted ``s`` starts from the best of a log-spaced scan over ``[1/travel, 1e7]``. The cost is not
    convex (a simulated window can slide onto another branch), so the parameters are freed one at a
    time in the order given, each stage starting from the last optimum: put the best-determined first.

    Covariance of the refined parameters, after projecting out each window's nuisance columns
    (``J_w``): ``A^-1 B A^-1 G/(G-1)`` with ``A = sum J_w' J_w`` and ``B = sum (J_w' r_w)(J_w' r_w)'``
    over the ``G`` windows (residuals correlated within a window, independent between windows); the
    larger of it and the white-noise ``s^2 A^-1`` is used, with Student's t on ``G - 1`` degrees of freedom.
    The held ``m, sigma, Cf, offset`` are uncertain too: their standard errors from ``ident`` are carried
    into each refined parameter's variance through its sensitivity to them at the optimum.
    """

    t_start = time.perf_counter()
    if not isinstance(trace, Trace):
        raise TypeError(f"trace: expected a Trace, found {type(trace).__name__}")
    if not isinstance(ident, Identification):
        raise TypeError(f"ident: expected an Identification (obsdesign.data.identify), found {type(ident).__name__}")
    model = check_choice("model", model, MODELS)
    names = tuple(parameters) if not isinstance(parameters, str) else (parameters,)
    method = default_method(model) if method is None else check_choice("method", method, METHODS)
    allowed = refinable(model, method)
    if not names or len(set(names)) != len(names) or any(n not in allowed for n in names):
        raise ValueError(f"parameters: expected distinct names of {', '.join(allowed)} (model {model!r}), "
                         f"found {', '.join(map(str, names)) or 'none'}")
    for label, value, high in (("travel", travel, 1.0), ("window", window, 100.0), ("segment", segment, 100.0)):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 < value <= high:
            raise ValueError(f"{label}: expected a number in (0, {high:g}], found {value!r}")
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or not 1 <= substeps <= 1000:
        raise ValueError(f"substeps: expected an integer in [1, 1000], found {substeps!r}")
    if time_budget is not None and (isinstance(time_budget, bool) or not isinstance(time_budget, (int, float))
                                    or not 0 < time_budget < math.inf):
        raise ValueError(f"time_budget: expected a positive number of seconds, found {time_budget!r}")
    if method == "segments":
        if segment / trace.sample_time < 20:
            raise ValueError(f"segment: expected at least 20 samples ({20 * trace.sample_time:g} s), found {segment:g} s")
        try:
            return refine_segments(trace, ident, parameters=names, segment=float(segment), time_budget=time_budget,
                                   progress=progress)
        except BudgetExceeded:
            raise RefineFailed(f"the time budget of {time_budget:g} s ran out before a first fit: give more "
                               f"(--time-budget) or a shorter record (--window)") from None
        except (ArithmeticError, np.linalg.LinAlgError) as e:
            raise RefineFailed(f"the segment fit failed numerically ({type(e).__name__}: {e})") from None
    try:
        return _refine_windows(trace, ident, names, model, initial, travel, window, substeps, time_budget, t_start)
    except BudgetExceeded:
        raise RefineFailed(f"the time budget of {time_budget:g} s ran out (the {model} windows' fit has no partial "
                           f"result: give more time or a shorter record with --window)") from None
    except (ArithmeticError, np.linalg.LinAlgError) as e:
        raise RefineFailed(f"the {model} windows' fit failed numerically ({type(e).__name__}: {e})") from None


def _refine_windows(trace, ident, names, model, initial, travel, window, substeps, time_budget, t_start):
    from scipy import optimize, stats

    prob = _Problem(trace, ident, model, names, initial, float(travel), float(window), int(substeps))
    prob.deadline = None if time_budget is None else t_start + time_budget
    if prob.starts.size == 0:
        raise ValueError(f"trace: no window to simulate: expected a reversal between strokes of gross sliding "
                         f"longer than travel = {travel:g} {prob.axis.length_unit}, found none in {trace.source!r}")
    g, w = len(names), prob.starts.size
    if "s" in names and (initial is None or "s" not in initial):
        prob.values["s"] = _scan_s(prob, g, w)
    theta0 = np.array([prob.to_theta(n, prob.values[n]) for n in names] + [0.0] * (2 * w))
    bounds = [(prob.to_theta(n, prob.spec(n)[1]) if prob.spec(n)[3] else prob.spec(n)[1],
               prob.to_theta(n, prob.spec(n)[2])) for n in names]
    lo = np.array([b[0] for b in bounds] + [-np.inf] * (2 * w))
    hi = np.array([b[1] for b in bounds] + [np.inf] * (2 * w))
    theta0[:g] = np.clip(theta0[:g], lo[:g] + 1e-9 * (1 + abs(lo[:g])), hi[:g] - 1e-9 * (1 + abs(hi[:g])))
    r0 = prob.residual(theta0)
    theta = theta0
    win = np.repeat(np.arange(w), prob.lengths)
    for k in range(1, g + 1):  # continuation: one more parameter free per stage, each from the last optimum
        idx = np.r_[np.arange(k), np.arange(g, g + 2 * w)]

        last: dict = {}

        def fun(sub, idx=idx, base=theta, last=last):
            full = base.copy()
            full[idx] = sub
            last["x"], last["f"] = sub.copy(), prob.residual(full)
            return last["f"]

        fit = optimize.least_squares(fun, theta[idx], jac=_grouped_jacobian(fun, last, k, w, win),
                                     bounds=(lo[idx], hi[idx]), x_scale="jac", method="trf", tr_solver="exact",
                                     xtol=1e-12, max_nfev=60 * (k + 2))
        theta = theta.copy()
        theta[idx] = fit.x
    fit.x = theta
    J = np.asarray(fit.jac)
    r = fit.fun
    A, B, rss, cond = _moments(prob, J, r, g, w)
    dof = max(r.size - g - 2 * w, 1)
    white = rss / dof * _pinv(A)
    cluster = w / max(w - 1, 1) * _pinv(A) @ B @ _pinv(A)
    cov = np.where(np.diag(white)[:, None] >= np.diag(cluster)[None, :], white, cluster) \
        if g == 1 else (white if np.trace(white) >= np.trace(cluster) else cluster)
    held = _held_sensitivity(prob, theta, J, A, g, w)
    var = np.diag(cov) + held
    null = _null_loadings(A)
    tq = float(stats.t.ppf(0.975, max(w - 1, 1)))
    out = []
    for i, name in enumerate(names):
        unit, low, high, log = prob.spec(name)
        theta = float(fit.x[i])
        value = prob.from_theta(name, theta)
        sd = math.sqrt(var[i]) if math.isfinite(var[i]) else math.inf
        half = tq * sd
        note = ""
        width = hi[i] - lo[i]
        at_bound = bool(fit.active_mask[i] != 0) or (width < 1e3 and min(theta - lo[i], hi[i] - theta) < 1e-6 * width)
        if null[i]:
            note = f"in a near-null direction of the Jacobian (singular value below {NEAR_NULL:g} of the largest)"
            half = sd = math.inf
        elif at_bound:
            note = f"at the bound of its range [{low:g}, {high:g}] {unit}"
        elif log and half > MAX_LOG_HALF_WIDTH:
            note = f"95 % interval wider than a factor {math.exp(MAX_LOG_HALF_WIDTH):.2f} either way"
        elif not log and name == "delay" and half > prob.dt:
            note = "95 % interval wider than one sample"
        elif not log and name != "delay" and half > abs(value):
            note = "95 % interval includes 0"
        lo_v, hi_v = ((_exp(theta - half), _exp(theta + half)) if log else (theta - half, theta + half)) \
            if math.isfinite(half) else (-math.inf, math.inf)
        out.append(RefinedParameter(name=name, unit=unit, value=value, initial=float(prob.values[name]),
                                    std=sd * (value if log else 1.0), low=lo_v, high=hi_v,
                                    identifiable=not note, note=note))
    fixed = {k: v for k, v in prob.values.items() if k not in names}
    return Refinement(model=model, parameters=tuple(out), fixed=fixed, windows=w, reversals=int(prob.reversals),
                      samples=int(r.size), rms_initial=float(np.sqrt(np.mean(r0**2))) * prob.scale,
                      rms=float(np.sqrt(np.mean(r**2))) * prob.scale, condition_number=cond,
                      evaluations=prob.evaluations, wall_time=time.perf_counter() - t_start,
                      length_unit=prob.axis.length_unit)
