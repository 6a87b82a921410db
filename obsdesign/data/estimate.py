"""The estimation step of :func:`obsdesign.data.identify` on the rows of the fit.

Bounded fits (:mod:`obsdesign.data.friction_fit`) with and without the Stribeck term, the model
selection between them, the IDIM-LS standard errors, and the intervals of
:mod:`obsdesign.data.uncertainty`.

Model selection: the Stribeck term is kept when it lowers the Bayesian information criterion
``BIC = n_eff ln(RSS / n) + k ln n_eff`` (``n`` rows, ``k`` fitted parameters) by more than
:data:`BIC_MARGIN` ("strong evidence" on the scale of Kass and Raftery, 1995), its ``vs`` is
not at a bound and ``Fs > Cf`` (a drop of friction with speed); or when asked
(``stribeck='on'``, or a fixed or bounded ``Fs``/``vs``). The rows are correlated, and ``n``
correlated rows carry the evidence of fewer independent ones: ``n_eff = n / tau`` with ``tau``
the integrated autocorrelation time of the residuals of the fit with the term
(:func:`~obsdesign.data.uncertainty.correlation_time`, at least 1). With ``n`` in place of
``n_eff`` a closed-loop record of an axis without a Stribeck drop kept a spurious 3 % one
(BIC decrease 40 at ``tau`` 4.8; 1.4 against it with ``n_eff``). :func:`obsdesign.data.identify`
decides on the rows down to the slowest trusted speed (:func:`~obsdesign.data.friction_fit.trusted_speed`),
where a drop below the default min speed lives (:func:`select_stribeck`).
"""

from __future__ import annotations

import math

import numpy as np

from ._idim import ols
from .choices import STRIBECK_CHOICES
from .friction_fit import PHYSICAL, fit_model, profile_interval
from .uncertainty import block_length, bootstrap, correlation_time, eiv_shift, intervals, make_index_sets

__all__ = ["estimate", "cautions", "model_shift", "widened", "MODEL_SHIFT_FACTOR", "BIC_MARGIN", "STRIBECK_CHOICES", "STRIBECK_INTERVAL",
           "select_stribeck"]

#: How the Stribeck level and speed get their intervals: the profile likelihood over each (the other parameters
#: re-fitted), joined with the bootstrap's and widened by the shifts like the others. Their columns are nonlinear
#: functions of the filtered velocity, so the one-step bootstrap alone (55-90 % coverage on synthetic records
#: before the record's own cut-off) understated them.
STRIBECK_INTERVAL = ("Fs and vs: the profile likelihood (n_eff ln(RSS/RSS_min) < 3.84, the others re-fitted) "
                     "joined with the bootstrap's")
#: The BIC decrease the Stribeck term must bring to be kept (``stribeck='auto'``).
BIC_MARGIN = 10.0


def _bic(fit, n_eff: float) -> float:
    """``n_eff ln(RSS / n) + k ln n_eff``: the BIC of ``n_eff`` independent rows with the fit's mean square."""
    n = fit.residual.size
    return n_eff * math.log(fit.rss / n) + len(fit.free) * math.log(n_eff)


def _idim_std(cols: dict, y: np.ndarray, model: str) -> tuple[dict, float, float]:
    """IDIM-LS standard errors ``sigma_e^2 (X^T X)^-1`` (unbounded OLS; asymmetric: propagated) and cond."""
    X = np.column_stack([cols[c] for c in ("a", "v", "sign", "one")])
    theta, cov, resid, cond = ols(X, y, ("acceleration", "velocity", "sign(v)", "offset"))
    sd = np.sqrt(np.diag(cov))
    out = dict(m=sd[0], sigma=sd[1], Cf=sd[2], offset=sd[3])
    if model == "asymmetric":
        Xa = np.column_stack([cols[c] for c in ("a", "v_pos", "v_neg", "pos", "neg")])
        _, cov_a, resid, cond = ols(Xa, y, ("acceleration", "v for v > 0", "v for v < 0", "v > 0", "v < 0"))
        sa = np.sqrt(np.diag(cov_a))
        r, pinv_a = np.linalg.pinv(X)[3], np.linalg.pinv(Xa)  # the offset is a linear map r of y
        s2 = float(resid @ resid) / (Xa.shape[0] - Xa.shape[1])
        out.update(m=sa[0], sigma_pos=sa[1], sigma_neg=sa[2],
                   sigma=math.sqrt(s2 * float(np.sum((0.5 * (pinv_a[1] + pinv_a[2])) ** 2))),
                   Cf=math.sqrt(s2 * float(np.sum((0.5 * (pinv_a[3] - pinv_a[4])) ** 2))),
                   Cf_pos=math.sqrt(s2 * float(np.sum((pinv_a[3] - r) ** 2))),
                   Cf_neg=math.sqrt(s2 * float(np.sum((r - pinv_a[4]) ** 2))))
    return {k: float(v) for k, v in out.items()}, cond, float(theta[0])


def _jac_std(fit) -> dict:
    n, p = fit.jacobian.shape
    s2 = fit.rss / max(n - p, 1)
    scale = np.linalg.norm(fit.jacobian, axis=0)
    scale[scale == 0] = 1.0
    js = fit.jacobian / scale
    cov = s2 * np.linalg.pinv(js.T @ js) / scale[:, None] / scale[None, :]
    return {name: float(math.sqrt(max(cov[i, i], 0.0))) for i, name in enumerate(fit.free)}


def _select(cols, y, *, stribeck, fix, bounds, vs_range):
    base = fit_model(cols, y, fix=fix, bounds=bounds)
    asked = stribeck == "on" or any(k in fix or k in bounds for k in ("Fs", "vs"))
    if stribeck == "off" and not asked:
        return base, base, "Stribeck term not fitted (stribeck='off')"
    rich = fit_model(cols, y, stribeck=True, fix=fix, bounds=bounds, vs_range=vs_range)
    n = rich.residual.size
    n_eff = n / correlation_time(rich.residual)
    b0, b1 = _bic(base, n_eff), _bic(rich, n_eff)
    rows = f"{n} rows" if n_eff == n else f"{n_eff:.0f} effective of {n} rows (residual correlation time {n / n_eff:.2g})"
    text = f"BIC {b0:.1f} without the Stribeck term, {b1:.1f} with it (vs {rich.values['vs']:.3g}; {rows})"
    if asked:
        return base, rich, f"Stribeck term fitted as asked; {text}"
    if "vs" in rich.at_bound:
        return base, base, f"Stribeck term dropped: vs at its {rich.at_bound['vs']} bound; {text}"
    if not rich.values["Fs"] > rich.values["Cf"]:
        return base, base, (f"Stribeck term dropped: the fit gives Fs = {rich.values['Fs']:.4g} below Cf = "
                            f"{rich.values['Cf']:.4g} (friction falling towards standstill is not a Stribeck drop); "
                            f"{text}")
    if b0 - b1 > BIC_MARGIN:
        return base, rich, f"Stribeck term kept: {text}, a decrease of {b0 - b1:.1f} > {BIC_MARGIN:g}"
    return base, base, f"Stribeck term dropped: {text}, a decrease of {b0 - b1:.1f} <= {BIC_MARGIN:g}"


def select_stribeck(cols: dict, y: np.ndarray, *, stribeck: str, fix: dict, bounds: dict,
                    vs_range: tuple[float, float]) -> tuple[bool, str]:
    """Whether the Stribeck term is in the model on the rows ``cols``, ``y``, and why (one line; module docstring).

    Parameters
    ----------
    cols, y :
        The rows the decision looks at (:func:`obsdesign.data.identify`: down to the trusted speed).
    stribeck : str
        One of :data:`STRIBECK_CHOICES`.
    fix, bounds : dict
        Checked fixed values and bounds (a fixed or bounded ``Fs``/``vs`` asks for the term).
    vs_range : (float, float)
        Default bounds of ``vs``.
    """
    _, chosen, text = _select(cols, y, stribeck=stribeck, fix=fix, bounds=bounds, vs_range=vs_range)
    return "Fs" in chosen.values, text


def estimate(cols: dict, y: np.ndarray, *, model: str, stribeck: str, fix: dict, bounds: dict,
             vs_range: tuple[float, float], noise_var: dict, n_boot: int, seed: int) -> dict:
    """Fields of :class:`~obsdesign.data.Identification` from the rows ``cols``, ``y`` of the fit.

    ``noise_var`` gives the white-noise variance of the ``a`` and ``v`` columns (per row) for the
    errors-in-variables shift; ``n_boot = 0`` skips the bootstrap (intervals from the standard errors).

    Parameters
    ----------
    cols : dict
        The regressor columns on the rows of the fit (see :func:`obsdesign.data.friction_fit.fit_model`).
    y : ndarray
        The force on those rows.
    model : str
        ``'coulomb-viscous'`` or ``'asymmetric'``.
    stribeck : str
        One of :data:`STRIBECK_CHOICES`.
    fix, bounds : dict
        Checked fixed values and bounds.
    vs_range : (float, float)
        Default bounds of ``vs``.
    noise_var : dict
        ``{"a": var, "v": var}`` per row.
    n_boot, seed : int
        Bootstrap replicates and seed.
    """
    idim, cond, m_ols = _idim_std(cols, y, model)
    if not m_ols > 0 and not fix and not bounds:  # a sign or column error: bounds would only hide it
        free = {n: (-math.inf, math.inf) for n in PHYSICAL}
        base = sym = fit_model(cols, y, bounds=free)
        selection = ("no bounds and no Stribeck term: the IDIM-LS mass is <= 0, a sign or column error (see the "
                     "warnings), so the values are shown as found")
        bounds = free
    else:
        base, sym, selection = _select(cols, y, stribeck=stribeck, fix=fix, bounds=bounds, vs_range=vs_range)
    kept = "Fs" in sym.values
    fits = [sym]
    if model == "asymmetric":
        afix = dict(fix, **({"Fs": sym.values["Fs"], "vs": sym.values["vs"]} if kept else {}))
        fits.append(fit_model(cols, y, model="asymmetric", stribeck=kept, fix=afix, bounds=bounds,
                              vs_range=vs_range, offset=sym.values["offset"]))
    final = fits[-1]
    values = dict(final.values)
    if model == "asymmetric":
        values["sigma"] = 0.5 * (values["sigma_pos"] + values["sigma_neg"])
        values["Cf"] = 0.5 * (values["Cf_pos"] + values["Cf_neg"])
        for k in ("Fs", "vs"):
            if kept:
                values[k] = sym.values[k]
    plain = not kept and not fix and not final.at_bound
    std = dict(idim) if plain else {**{k: 0.0 for k in values}, **_jac_std(sym), **_jac_std(final)}
    if model == "asymmetric" and not plain:
        std["sigma"] = 0.5 * math.hypot(std.get("sigma_pos", 0.0), std.get("sigma_neg", 0.0))
        std["Cf"] = 0.5 * math.hypot(std.get("Cf_pos", 0.0), std.get("Cf_neg", 0.0))

    # intervals: moving-block bootstrap of every stage on the same resampled rows, plus the EIV shift
    reps: dict[str, np.ndarray] = {}
    shifts: dict[str, float] = {}
    block = 0
    offset_reps = None
    for stage in fits:
        theta = np.array([stage.values[n] for n in stage.free])
        noisy = {i: noise_var[{"m": "a"}.get(n, "v")] * _rows_of(cols, n) for i, n in enumerate(stage.free)
                 if n in ("m", "sigma", "sigma_pos", "sigma_neg")}
        shift = eiv_shift(stage.jacobian, theta, noisy)
        shifts.update({n: float(s) for n, s in zip(stage.free, shift) if n not in shifts or stage is final})
        if n_boot <= 0:
            continue
        if stage is sym:
            block = block_length(stage.residual)
            idx = make_index_sets(stage.residual, n_boot=n_boot, seed=seed, block=block)
        lo = np.array([stage.bounds[n][0] for n in stage.free])
        hi = np.array([stage.bounds[n][1] for n in stage.free])
        resid = stage.residual
        if stage is not sym and offset_reps is not None:  # the held offset varies with the replicate
            out = np.empty((n_boot, theta.size))
            for i in range(n_boot):
                out[i] = bootstrap(stage.jacobian, resid + (offset_reps[i] - sym.values["offset"]) * cols["one"], theta, lo, hi,
                                   index_sets=idx[i:i + 1])[0]
        else:
            out = bootstrap(stage.jacobian, resid, theta, lo, hi, index_sets=idx)
        reps.update({n: out[:, i] for i, n in enumerate(stage.free) if n not in reps or stage is final})
        if "offset" in stage.free:
            offset_reps = out[:, stage.free.index("offset")]
    if model == "asymmetric" and reps:
        for mean, (p, q) in (("sigma", ("sigma_pos", "sigma_neg")), ("Cf", ("Cf_pos", "Cf_neg"))):
            if p in reps and q in reps:
                reps[mean] = 0.5 * (reps[p] + reps[q])
                shifts[mean] = 0.5 * (shifts.get(p, 0.0) + shifts.get(q, 0.0))
    profiles = {}
    if kept and n_boot > 0:  # the Stribeck level and speed: the profile likelihood, the others re-fitted
        n_eff = sym.residual.size / correlation_time(sym.residual)
        for name in ("Fs", "vs"):
            if name not in fix:
                profiles[name] = profile_interval(cols, y, sym, name, n_eff, fix=fix, bounds=bounds, vs_range=vs_range,
                                                  step=std.get(name))
    ivals = {}
    for name, value in values.items():
        if name in profiles:
            lo, hi = intervals(reps[name][:, None], np.array([0.0])) if name in reps else (value, value)
            s = shifts.get(name, 0.0) if math.isfinite(shifts.get(name, 0.0)) else 0.0
            ivals[name] = (min(float(np.min(lo)), profiles[name][0]) + min(s, 0.0),
                           max(float(np.max(hi)), profiles[name][1]) + max(s, 0.0))
        elif name in reps:
            lo, hi = intervals(reps[name][:, None], np.array([shifts.get(name, 0.0)]))
            ivals[name] = (float(lo[0]), float(hi[0]))
        elif name in fix:
            ivals[name] = (value, value)
        else:  # no bootstrap: +- 1.96 standard errors, widened by the shift
            half = 1.96 * std.get(name, 0.0)
            s = shifts.get(name, 0.0) if math.isfinite(shifts.get(name, 0.0)) else 0.0
            ivals[name] = (value - half + min(s, 0.0), value + half + max(s, 0.0))
    resid = final.residual
    power = float(np.mean(y**2))
    return dict(values=values, std=std, condition_number=cond, selection=selection, stribeck=kept,
                at_bound=dict(final.at_bound, **{k: v for k, v in sym.at_bound.items() if k not in final.free}),
                intervals=ivals, eiv_shift={k: v for k, v in shifts.items() if k in values}, block_length=block,
                nrmse=100.0 * math.sqrt(float(np.mean(resid**2)) / power) if power > 0 else math.inf,
                base_rss=base.rss, residual=resid)


def _rows_of(cols: dict, name: str) -> float:
    v = cols["v"]
    if name == "sigma_pos":
        return float(np.count_nonzero(v > 0))
    if name == "sigma_neg":
        return float(np.count_nonzero(v < 0))
    return float(v.size)


def cautions(est: dict, cols: dict, noise_var: dict, units, filter_hz: float) -> tuple[str, ...]:
    """Cautions: a parameter at a bound; an errors-in-variables shift larger than the half-interval.

    Parameters
    ----------
    est : dict
        The result of :func:`estimate`.
    cols : dict
        The rows' columns.
    noise_var : dict
        Noise variance of the ``a`` and ``v`` columns.
    units : Units
        For the units in the sentences.
    filter_hz : float
        The fit's cut-off (named in the advice).
    """
    out = [f"{name} is at its {side} bound: the data push it beyond (a friction the model does not hold, e.g. a "
           f"Stribeck drop with the term off, or too slow an excitation); fix it (--fix {name}=VALUE) or give other "
           f"bounds (--bounds {name}=LO:HI) if you know better" for name, side in est["at_bound"].items()]
    for name, shift in est["eiv_shift"].items():
        if name not in est["intervals"]:
            continue
        lo, hi = est["intervals"][name]
        value = est["values"][name]
        if not math.isfinite(shift):
            out.append(f"{name}: the position noise on the regressors is as large as their signal (no bias "
                       "correction possible): use an excitation with larger and faster moves")
            continue
        half = 0.5 * (hi - lo - abs(shift))
        if name in ("m", "sigma") and abs(shift) > half and value != 0:
            col = "a" if name == "m" else "v"
            ratio = math.sqrt(noise_var[col]) / float(np.sqrt(np.mean(cols[col] ** 2)))
            kind = "acceleration" if col == "a" else "velocity"
            out.append(f"errors in variables: the position noise on the {kind} regressor is {100 * ratio:.2g} % of "
                       f"its RMS; it biases {name} by about {-100 * shift / value:+.2g} % (more than its bootstrap "
                       f"half-interval {half:.3g} {units.si(name)}; the interval includes the correction): use an "
                       f"excitation with more {kind} (larger, faster moves, frequencies up to {filter_hz:g} Hz), or a "
                       f"closed-loop tracking record, or a lower filter_hz")
    return tuple(out)


#: The rows of the model-error check: speeds above this many times the fit's min speed.
MODEL_SHIFT_FACTOR = 4.0


def model_shift(est: dict, cols: dict, y: np.ndarray, threshold: float, *, model, fix, bounds, vs_range,
                noise_var) -> dict:
    """``name -> change of the estimate`` when the rows below :data:`MODEL_SHIFT_FACTOR` x the min speed are left out.

    Near a reversal the friction follows the position (pre-sliding, a bristle's lag), not ``Cf sign(v)``:
    a misfit of the static model that no bootstrap of its residuals sees. Where leaving those rows out
    moves an estimate, the model does not hold there by at least that much, and the interval is widened
    by the move (on its side). Simulated LuGre axes were biased by 0.3 to 0.9 % in m, sigma and Cf with
    bootstrap half-widths of 0.15 to 0.7 % (covered in 0 of 4 draws); the move is of the bias's size.
    With the Stribeck term kept, the check fits it too (on the rows left). Not done where too few rows remain.

    Parameters
    ----------
    est : dict
        The result of :func:`estimate`.
    cols, y :
        The rows of the fit.
    threshold : float
        The fit's min speed.
    model, fix, bounds, vs_range, noise_var :
        As for :func:`estimate`.
    """
    sub = np.abs(cols["v"]) > MODEL_SHIFT_FACTOR * threshold
    if np.count_nonzero(sub) < max(20, sub.size // 4):
        return {}
    part = {k: (c if k == "shape" else c[sub]) for k, c in cols.items()}
    shape = cols["shape"]
    part["shape"] = lambda vs, parts: {k: c[sub] for k, c in shape(vs, parts).items()}
    try:
        alt = estimate(part, y[sub], model=model, stribeck="on" if est["stribeck"] else "off", fix=fix,
                       bounds=bounds, vs_range=vs_range, noise_var=noise_var, n_boot=0, seed=0)
    except ValueError:
        return {}
    return {k: float(alt["values"][k] - est["values"][k]) for k in est["intervals"]
            if k in alt["values"] and k not in fix}


def widened(intervals: dict, values: dict, shift: dict) -> dict:
    """Each interval widened on its side by ``shift`` and stretched to hold its own estimate.

    Parameters
    ----------
    intervals : dict
        ``name -> (low, high)``.
    values : dict
        ``name -> estimate``.
    shift : dict
        ``name -> model-error shift`` (:func:`model_shift`).

    Examples
    --------
    >>> widened({"m": (1.0, 2.0)}, {"m": 2.5}, {"m": -0.5})
    {'m': (0.5, 2.5)}
    """
    out = {}
    for name, (lo, hi) in intervals.items():
        s = shift.get(name, 0.0)
        lo, hi = lo + min(s, 0.0), hi + max(s, 0.0)
        out[name] = (min(lo, float(values[name])), max(hi, float(values[name])))
    return out
