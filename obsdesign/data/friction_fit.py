"""Bounded least squares of the inverse dynamic model, with an optional Stribeck term.

On the rows of the fit (filtered, differentiated, decimated; see :func:`obsdesign.data.identify`)
the actuator force is modelled as

    y = m a + sigma v + Cf (c - S) + Fs S + offset,    S = sign(v) exp(-(v / vs)^2),

with ``c`` the decimated ``sign(v)`` column of the IDIM-LS fit (so ``Cf`` is the Coulomb level
at speeds well above ``vs`` and ``Fs`` the level at standstill, the Stribeck curve). Without the
Stribeck term ``S = 0``. The ``asymmetric`` model replaces ``sigma v`` and ``Cf c`` by per-direction
terms, with the offset held (the data cannot separate it from the two levels).

For a given ``vs`` the model is linear: it is solved exactly under the bounds by
``scipy.optimize.lsq_linear`` (BVLS); ``vs`` is found by ``scipy.optimize.least_squares``
(trust-region reflective, bounded) on that projected residual (variable projection, Golub and
Pereyra), over ``log vs`` and started from the best ``vs`` of a logarithmic grid. Fixed parameters are moved to the left-hand side.

Examples
--------
>>> import numpy as np
>>> rng = np.random.default_rng(0)
>>> v = np.concatenate([np.linspace(-0.02, -2e-4, 500), np.linspace(2e-4, 0.02, 500)])
>>> a = rng.normal(0.0, 0.5, v.size)
>>> y = 1.8 * a + 12 * v + 2.4 * np.sign(v) + 0.6 * np.sign(v) * np.exp(-(v / 2e-3) ** 2) + 0.3
>>> fit = fit_model({"a": a, "v": v, "sign": np.sign(v)}, y, stribeck=True, vs_range=(2e-4, 0.01))
>>> {k: round(val, 4) for k, val in fit.values.items()}
{'m': 1.8, 'sigma': 12.0, 'Cf': 2.4, 'offset': 0.3, 'Fs': 3.0, 'vs': 0.002}
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["fit_model", "Fit", "PARAMETERS", "ASYMMETRIC", "PHYSICAL", "check_fix", "check_bounds",
           "stribeck_shape", "trusted_speed", "profile_interval", "NOISE_SIGMAS", "COUNTS_PER_PERIOD", "CHI2_95"]

#: Parameters of the symmetric model, in order; ``Fs`` and ``vs`` only with the Stribeck term.
PARAMETERS = ("m", "sigma", "Cf", "offset", "Fs", "vs")
#: Parameters of the asymmetric model (the offset held from the symmetric fit).
ASYMMETRIC = ("m", "sigma_pos", "sigma_neg", "Cf_pos", "Cf_neg", "Fs", "vs")
#: The physical domain of each parameter: what a bound or a fixed value may not leave.
PHYSICAL = {"m": (0.0, math.inf), "sigma": (0.0, math.inf), "Cf": (0.0, math.inf), "offset": (-math.inf, math.inf),
            "Fs": (0.0, math.inf), "vs": (0.0, math.inf), "sigma_pos": (0.0, math.inf),
            "sigma_neg": (0.0, math.inf), "Cf_pos": (0.0, math.inf), "Cf_neg": (0.0, math.inf)}
_GRID = 10
#: The slowest row of the Stribeck fit moves at least this many standard deviations of the velocity's noise.
NOISE_SIGMAS = 3.0
#: ... and at least this many encoder counts per period of the low-pass's cut-off.
COUNTS_PER_PERIOD = 2.0
#: The 95 % point of chi-square with one degree of freedom (the profile's threshold).
CHI2_95 = 3.841458820694124


def trusted_speed(velocity_noise: float, quantum: float, filter_hz: float) -> tuple[float, str]:
    """The lowest speed whose rows the Stribeck fit may use, and the rule as applied (one line).

    Rule: ``max(NOISE_SIGMAS sigma_v, COUNTS_PER_PERIOD q f_c)``. Below ``3 sigma_v`` (the standard
    deviation of the low-passed velocity's noise at the full rate, where ``sign(v)`` and the Stribeck
    column are taken) the sign of a row is a coin toss in more than one sample of a thousand; below two
    encoder counts per period of the cut-off ``f_c`` the count's staircase (of frequency ``|v| / q``)
    passes the low-pass with more than 0.4 % of its power, so the filtered velocity ripples with it.

    Parameters
    ----------
    velocity_noise : float
        ``sigma_v`` [m/s or rad/s].
    quantum : float
        The encoder step ``q`` [m or rad] (0: not quantized).
    filter_hz : float
        The cut-off ``f_c`` [Hz].

    Examples
    --------
    >>> round(trusted_speed(1e-3, 6e-6, 400.0)[0], 9)  # 3 x 1 mrad/s against 2 x 6 urad x 400 Hz = 4.8 mrad/s
    0.0048
    """
    by_noise, by_counts = NOISE_SIGMAS * velocity_noise, COUNTS_PER_PERIOD * quantum * filter_hz
    rule = (f"{NOISE_SIGMAS:g} x the velocity's noise {velocity_noise:.3g} = {by_noise:.3g}, {COUNTS_PER_PERIOD:g} "
            f"encoder counts per period of the {filter_hz:.4g} Hz cut-off = {by_counts:.3g}: the larger")
    return float(max(by_noise, by_counts)), rule


def stribeck_shape(v: np.ndarray, vs: float) -> np.ndarray:
    """``sign(v) exp(-(v/vs)^2)``: the Stribeck column per unit of ``Fs - Cf``.

    Parameters
    ----------
    v : ndarray
        Velocity [m/s].
    vs : float
        Stribeck speed [m/s].
    """
    return np.sign(v) * np.exp(-((v / vs) ** 2))


def check_fix(fix: object, names=PARAMETERS + ASYMMETRIC) -> dict[str, float]:
    """``{name: value}`` with known names and values in the physical domain (``vs`` > 0, ``m`` > 0).

    Parameters
    ----------
    fix : dict or None
        Parameter name -> value.
    names : tuple of str
        The names allowed.
    """
    if fix is None:
        return {}
    if not isinstance(fix, dict):
        raise TypeError(f"fix: expected a mapping name -> value, found {type(fix).__name__}")
    out = {}
    for name, value in fix.items():
        if name not in names:
            raise ValueError(f"fix: expected a parameter among {', '.join(dict.fromkeys(names))}, found {name!r}")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ValueError(f"fix {name}: expected a finite number, found {value!r}")
        low, high = PHYSICAL[name]
        strict = name in ("m", "vs")
        if value < low or (strict and value <= low):
            raise ValueError(f"fix {name}: expected a value {'>' if strict else '>='} {low:g} (physical), "
                             f"found {value!r}")
        out[name] = float(value)
    return out


def check_bounds(bounds: object, names=PARAMETERS + ASYMMETRIC) -> dict[str, tuple[float, float]]:
    """``{name: (lo, hi)}`` with ``lo < hi`` inside the physical domain of the parameter.

    Parameters
    ----------
    bounds : dict or None
        Parameter name -> ``(low, high)``.
    names : tuple of str
        The names allowed.
    """
    if bounds is None:
        return {}
    if not isinstance(bounds, dict):
        raise TypeError(f"bounds: expected a mapping name -> (low, high), found {type(bounds).__name__}")
    out = {}
    for name, pair in bounds.items():
        if name not in names:
            raise ValueError(f"bounds: expected a parameter among {', '.join(dict.fromkeys(names))}, found {name!r}")
        try:
            lo, hi = (float(x) for x in pair)
        except (TypeError, ValueError):
            raise ValueError(f"bounds {name}: expected a pair (low, high) of numbers, found {pair!r}") from None
        plo, phi = PHYSICAL[name]
        if math.isnan(lo) or math.isnan(hi) or not lo < hi:
            raise ValueError(f"bounds {name}: expected low < high, found ({lo:g}, {hi:g})")
        if lo < plo or hi > phi:
            raise ValueError(f"bounds {name}: expected bounds within the physical range [{plo:g}, {phi:g}], "
                             f"found ({lo:g}, {hi:g})")
        out[name] = (lo, hi)
    return out


@dataclass(frozen=True)
class Fit:
    """A bounded fit: values by name, free parameters, Jacobian and residual at the solution.

    Attributes
    ----------
    values : dict
        Every parameter of the model (fixed ones included).
    free : tuple of str
        The fitted ones, in the order of the Jacobian's columns.
    jacobian : ndarray, shape (rows, len(free))
        ``d(model)/d(free)`` at the solution.
    residual : ndarray
        ``model - y``.
    at_bound : dict
        ``name -> 'lower'|'upper'`` for a fitted parameter at (within 1e-9 relative of) a bound.
    bounds : dict
        ``name -> (lo, hi)`` used for each free parameter.
    """

    values: dict
    free: tuple
    jacobian: np.ndarray = field(repr=False)
    residual: np.ndarray = field(repr=False)
    at_bound: dict
    bounds: dict

    @property
    def rss(self) -> float:
        """Residual sum of squares."""
        return float(self.residual @ self.residual)


def _one(cols: dict) -> np.ndarray:
    """The offset column: the decimated ones of the IDIM-LS fit (1 up to the decimation filter's edges)."""
    return cols["one"] if "one" in cols else np.ones_like(cols["v"])


def _shape(cols: dict, vs: float, parts: tuple[str, ...]) -> dict[str, np.ndarray]:
    """The Stribeck columns at ``vs``: ``S``, and ``S_pos``, ``S_neg``, ``dS`` (d/dvs) when asked.

    ``cols["shape"]`` (a callable ``(vs, parts) -> dict``) computes them at the full rate and decimates
    them like the other columns (the nonlinearity before the filter, as in the force); without it
    they are evaluated on the rows' velocity.
    """
    if "shape" in cols:
        return cols["shape"](vs, parts)
    v = cols["v"]
    S = stribeck_shape(v, vs)
    out = {"S": S, "S_pos": S * (v > 0), "S_neg": S * (v < 0), "dS": S * 2.0 * v**2 / vs**3}
    return {k: out[k] for k in ("S",) + parts}


def _linear_columns(cols: dict, model: str, S: dict | None) -> dict[str, np.ndarray]:
    zero = np.zeros_like(cols["v"])
    S = {"S": zero, "S_pos": zero, "S_neg": zero} if S is None else S
    if model == "asymmetric":
        out = {"m": cols["a"], "sigma_pos": cols["v_pos"], "sigma_neg": cols["v_neg"],
               "Cf_pos": cols["pos"] - S["S_pos"], "Cf_neg": -(cols["neg"] + S["S_neg"])}
        out["Fs"] = S["S"]
        return out
    else:
        out = {"m": cols["a"], "sigma": cols["v"], "Cf": cols["sign"] - S["S"], "offset": _one(cols)}
    out["Fs"] = S["S"]
    return out


def lstsq_gram(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Least squares by the normal equations of the column-scaled ``A`` (a tall matrix with few columns:
    no LAPACK decomposition of the tall matrix, which a multi-threaded BLAS makes slow on a loaded machine)."""
    scale = np.linalg.norm(A, axis=0)
    scale[scale == 0] = 1.0
    As = A / scale
    gram = As.T @ As
    try:
        return np.linalg.solve(gram, As.T @ b) / scale
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(As, b, rcond=None)[0] / scale


def _solve_linear(X: dict, y: np.ndarray, names: tuple, fix: dict, bounds: dict):
    """Exact bounded linear least squares over the free ``names`` (OLS if interior)."""
    from scipy.optimize import lsq_linear

    rhs = y - sum((fix[n] * X[n] for n in names if n in fix), np.zeros_like(y))
    free = tuple(n for n in names if n not in fix)
    A = np.column_stack([X[n] for n in free])
    theta = lstsq_gram(A, rhs)
    lo = np.array([bounds[n][0] for n in free])
    hi = np.array([bounds[n][1] for n in free])
    if np.any(theta < lo) or np.any(theta > hi):
        scale = np.max(np.abs(A), axis=0)
        scale[scale == 0] = 1.0
        theta = lsq_linear(A / scale, rhs, bounds=(lo * scale, hi * scale), method="bvls", tol=1e-14).x / scale
    return free, theta, A @ theta - rhs


def fit_model(cols: dict, y: np.ndarray, *, model: str = "coulomb-viscous", stribeck: bool = False,
              fix: dict | None = None, bounds: dict | None = None, vs_range: tuple[float, float] = (1e-6, 1.0),
              offset: float | None = None) -> Fit:
    """Bounded fit of the model of this module to the rows ``cols`` (``a, v, sign``; asymmetric also
    ``v_pos, v_neg, pos, neg``) and the force ``y``.

    Parameters
    ----------
    cols : dict of ndarray
    y : ndarray
    model : {'coulomb-viscous', 'asymmetric'}
    stribeck : bool
        Include ``Fs`` and ``vs``.
    fix, bounds : dict, optional
        Fixed values and ``(lo, hi)`` bounds by name (checked by :func:`check_fix`,
        :func:`check_bounds`); defaults are the physical domains, ``vs`` in ``vs_range``.
    vs_range : (float, float)
        Default bounds of ``vs`` [m/s].
    offset : float, optional
        The held offset of the ``asymmetric`` model.

    Returns
    -------
    Fit
    """
    from scipy.optimize import least_squares

    fix = dict(fix or {})
    names = ASYMMETRIC if model == "asymmetric" else PARAMETERS
    lin = names[:-2] + (("Fs",) if stribeck else ())
    if not stribeck:
        fix = {k: v for k, v in fix.items() if k not in ("Fs", "vs")}
    rng = {n: PHYSICAL[n] for n in names}
    rng["vs"] = tuple(vs_range)
    rng.update(bounds or {})
    y = np.asarray(y, dtype=float) - (offset * _one(cols) if model == "asymmetric" else 0.0)

    parts = ("S_pos", "S_neg") if model == "asymmetric" else ()

    def solve_at(vs: float, deriv: tuple = ()):
        S = _shape(cols, vs, parts + deriv) if stribeck else None
        X = _linear_columns(cols, model, S)
        return (X,) + _solve_linear(X, y, lin, fix, rng) + (S,)

    if not stribeck:
        X, free, theta, resid, _ = solve_at(1.0)
        values = dict(fix, **dict(zip(free, theta)))
        jac = np.column_stack([X[n] for n in free])
    else:
        lo_vs, hi_vs = rng["vs"]
        if "vs" in fix:
            vs = fix["vs"]
        else:  # variable projection: least_squares over log(vs), the linear parameters solved at each vs
            grid = np.geomspace(lo_vs, hi_vs, _GRID)
            vs0 = min(grid, key=lambda g: float(np.sum(solve_at(g)[3] ** 2)))
            cache: dict = {}

            def at(z):
                if cache.get("z") != z[0]:
                    cache.update(z=z[0], out=solve_at(math.exp(z[0]), ("dS",)))
                return cache["out"]

            def jac_vp(z):  # Kaufman's variable-projection Jacobian: d(model)/d(log vs) off the linear span
                X, free_lin, theta, _, S = at(z)
                p = dict(fix, **dict(zip(free_lin, theta)))
                cf = p["Cf"] if model != "asymmetric" else np.where(cols["v"] > 0, p["Cf_pos"], p["Cf_neg"])
                d = (p["Fs"] - cf) * S["dS"] * math.exp(z[0])
                A = np.column_stack([X[n] for n in free_lin])
                return (d - A @ lstsq_gram(A, d))[:, None]

            sol = least_squares(lambda z: at(z)[3], [math.log(vs0)], jac=jac_vp,
                                bounds=([math.log(lo_vs)], [math.log(hi_vs)]), xtol=1e-15, ftol=1e-15,
                                gtol=1e-15, max_nfev=100)
            z = float(sol.x[0])
            for _ in range(20):  # Gauss-Newton polish: trf stops on a flat optimum before the gradient is 0
                j, r = jac_vp([z])[:, 0], at([z])[3]
                step = -float(j @ r) / float(j @ j) if float(j @ j) > 0 else 0.0
                trial = min(max(z + step, math.log(lo_vs)), math.log(hi_vs))
                if abs(trial - z) > 1e-3 or trial == z:  # only the last digits: a larger step is not a polish
                    break
                z = trial
                if abs(step) < 1e-14:
                    break
            vs = min(max(math.exp(z), lo_vs), hi_vs)
        X, free_lin, theta, resid, S = solve_at(vs, () if "vs" in fix else ("dS",))
        values = dict(fix, **dict(zip(free_lin, theta)), vs=vs)
        free = free_lin + (() if "vs" in fix else ("vs",))
        jac_cols = [X[n] for n in free_lin]
        if "vs" not in fix:
            cf = values["Cf"] if model != "asymmetric" else np.where(cols["v"] > 0, values["Cf_pos"], values["Cf_neg"])
            jac_cols.append((values["Fs"] - cf) * S["dS"])
        jac = np.column_stack(jac_cols)
    at_bound = {}
    for n in free:
        lo, hi = rng[n]
        tol = 1e-9 * max(abs(values[n]), abs(lo) if math.isfinite(lo) else 0.0, 1e-300)
        if values[n] - lo <= tol:
            at_bound[n] = "lower"
        elif math.isfinite(hi) and hi - values[n] <= 1e-9 * max(abs(hi), 1e-300):
            at_bound[n] = "upper"
    ordered = {n: float(values[n]) for n in names if n in values}
    if model == "asymmetric":
        ordered["offset"] = float(offset)
    return Fit(values=ordered, free=tuple(free), jacobian=jac, residual=resid, at_bound=at_bound,
               bounds={n: tuple(rng[n]) for n in free})


def profile_interval(cols: dict, y: np.ndarray, fit: Fit, name: str, n_eff: float, *, fix: dict | None = None,
                     bounds: dict | None = None, vs_range: tuple[float, float] = (1e-6, 1.0),
                     level: float = CHI2_95, step: float | None = None) -> tuple[float, float]:
    """The profile-likelihood interval of ``Fs`` or ``vs`` of a Stribeck ``fit`` (the symmetric model).

    Every other parameter is re-fitted at each value of ``name`` (for ``vs`` the linear ones; for ``Fs``
    also ``vs``), and the interval is where ``n_eff ln(RSS / RSS_min)`` stays below ``level`` (the
    95 % point of chi-square with one degree of freedom): ``n_eff`` rows carrying the evidence of
    independent ones (the correlated rows' effective number). Unlike the covariance it follows a
    profile that is not quadratic (``vs`` near a bound, a flat side); an end at a bound stays there.

    Parameters
    ----------
    cols, y :
        The rows of the fit.
    fit : Fit
        The Stribeck fit (:func:`fit_model` with ``stribeck=True``).
    name : {'Fs', 'vs'}
    n_eff : float
        Effective number of independent rows.
    fix, bounds, vs_range :
        As for the fit.
    level : float
        The profile's threshold.
    step : float, optional
        The first step from the estimate (default 1e-4 of it; a standard error saves evaluations); the
        steps double until the profile crosses the threshold, which is then found by Brent's method.

    Returns
    -------
    (low, high)

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> v = np.concatenate([np.linspace(-0.02, -2e-4, 500), np.linspace(2e-4, 0.02, 500)])
    >>> a = rng.normal(0.0, 0.5, v.size)
    >>> y = 1.8 * a + 12 * v + 2.4 * np.sign(v) + 0.6 * stribeck_shape(v, 2e-3) + 0.3 + rng.normal(0, 0.01, v.size)
    >>> cols = {"a": a, "v": v, "sign": np.sign(v)}
    >>> fit = fit_model(cols, y, stribeck=True, vs_range=(2e-4, 0.01))
    >>> lo, hi = profile_interval(cols, y, fit, "vs", v.size, vs_range=(2e-4, 0.01))
    >>> bool(lo < 2e-3 < hi and lo < fit.values["vs"] < hi and hi / lo < 1.1)
    True
    """
    from scipy.optimize import brentq

    fix = dict(fix or {})
    lo_b, hi_b = (tuple(vs_range) if name == "vs" else PHYSICAL["Fs"])
    if bounds and name in bounds:
        lo_b, hi_b = bounds[name]
    best = fit.values[name]
    rss0 = fit.rss

    def excess(value: float) -> float:
        alt = fit_model(cols, y, stribeck=True, fix=dict(fix, **{name: value}), bounds=bounds, vs_range=vs_range)
        return n_eff * math.log(max(alt.rss, rss0) / rss0) - level

    out = []
    first = step
    for side in (-1.0, 1.0):
        step = first
        edge = lo_b if side < 0 else hi_b
        step = 1e-4 * max(abs(best), 1e-300) if not step or not math.isfinite(step) else 0.5 * abs(step)
        inner, found = best, None
        for _ in range(60):
            trial = best + side * step
            if (side < 0 and trial <= edge) or (side > 0 and trial >= edge) or not math.isfinite(trial):
                break
            if name == "vs" and trial <= 0:
                break
            if excess(trial) > 0:
                found = trial
                break
            inner, step = trial, 2.0 * step
        if found is None:
            out.append(float(edge))
        else:
            out.append(float(brentq(excess, min(inner, found), max(inner, found), xtol=1e-4 * abs(best), rtol=1e-4)))
    return out[0], out[1]
