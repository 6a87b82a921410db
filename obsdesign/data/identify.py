"""Identification of mass, viscous and Coulomb friction and load offset from a measured trace.

The inverse dynamic model of the rigid axis (eq:2:1 with ``Fc = Cf sign(v)`` in gross
sliding, eq:2:1:2, and static viscous friction) is linear in its parameters::

    u = m a + sigma v + Cf sign(v) + offset

and is fitted by ordinary least squares on filtered, differentiated and decimated
data (the IDIM-LS procedure of the EMPS benchmark). See ``docs/measured-data.md``.

Examples
--------
>>> import numpy as np
>>> from obsdesign.data import Trace
>>> dt = 1e-3
>>> t = np.arange(20_000) * dt
>>> x = 0.05 * np.sin(2 * np.pi * 0.5 * t) + 0.01 * np.sin(2 * np.pi * 2.3 * t)
>>> v, a = np.gradient(x, dt), np.gradient(np.gradient(x, dt), dt)
>>> u = 2.0 * a + 30.0 * v + 1.5 * np.sign(v) - 0.4     # m, sigma, Cf, offset
>>> ident = identify(Trace(t=t, position=x, force=u, sample_time=dt))
>>> [round(p, 2) for p in (ident.m, ident.sigma, ident.Cf, ident.offset)]
[2.0, 30.0, 1.5, -0.4]
"""

from __future__ import annotations

import html
import math
import warnings
from dataclasses import asdict, dataclass, field

import numpy as np

from .presliding import MIN_REVERSALS, MIN_ROWS as MIN_PRESLIDING_ROWS, _reversals, fit_presliding
from .trace import REVERSAL_THRESHOLD, Trace

__all__ = ["Identification", "identify", "MODELS", "FILTER_ORDER", "DEFAULT_DECIMATION",
           "MIN_REVERSALS", "MIN_PRESLIDING_ROWS"]

MODELS = ("coulomb-viscous", "asymmetric")
#: Order of the zero-phase Butterworth low-pass (the benchmark's choice).
FILTER_ORDER = 4
#: Default cut-off of that filter relative to the sampling rate (100 Hz at 1 kHz).
FILTER_FRACTION = 0.1
#: Default decimation factor (the benchmark's round(0.8 fnyq / (2 * 20 Hz)) = 10 at 1 kHz).
DEFAULT_DECIMATION = 10
#: Default pre-sliding window [m]: the largest travel after a reversal still called pre-sliding.
PRESLIDING_WINDOW = 1e-4


@dataclass(frozen=True, kw_only=True)
class Identification:
    """Result of :func:`identify`: parameters, standard errors and fit statistics.

    Attributes
    ----------
    model : str
        ``'coulomb-viscous'`` or ``'asymmetric'``.
    m, sigma, Cf, offset : float
        Mass [kg], viscous coefficient [N s/m], Coulomb level [N], offset [N]. For
        ``asymmetric``, ``sigma`` and ``Cf`` are the means of the two directions.
    m_std, sigma_std, Cf_std, offset_std : float
        Standard errors from the OLS covariance ``sigma_e^2 (X^T X)^-1``.
    sigma_pos, sigma_neg, Cf_pos, Cf_neg : float or None
        Per-direction values (``asymmetric`` only).
    sigma_pos_std, sigma_neg_std, Cf_pos_std, Cf_neg_std : float or None
        Their standard errors.
    nrmse_percent : float
        ``100 rms(residual) / rms(u)`` over the rows of the fit.
    condition_number : float
        2-norm condition number of the regressor after scaling each column to unit norm.
    samples : int
        Rows in the fit (after decimation and dropping low velocities).
    s : float or None
        Pre-sliding scaling factor of eq:2:3:1 [1/m], ``None`` if the data do not resolve it.
    s_note : str
        How ``s`` was obtained, or why it was not.
    sample_time, filter_hz, decimation :
        The trace's sample time [s], the Butterworth cut-off [Hz], the decimation factor.
    input_gain, force_peak, noise_rms, quantization, reversals :
        Trace facts used by :meth:`to_config`: the input gain [N/unit], the largest |force|
        [N], the position noise RMS [m], the encoder step [m] (0: not quantized), and the
        number of motion reversals.
    source : str
        Where the trace came from (its file name), for tables.
    warnings : tuple of str
        Why the values are not physical, if they are not: a mass, viscous coefficient or Coulomb
        level <= 0, each with its likely cause (the sign of the input gain, swapped columns, units).
        Empty for a plausible identification.
    """

    model: str
    m: float
    sigma: float
    Cf: float
    offset: float
    m_std: float
    sigma_std: float
    Cf_std: float
    offset_std: float
    nrmse_percent: float
    condition_number: float
    samples: int
    sigma_pos: float | None = None
    sigma_neg: float | None = None
    Cf_pos: float | None = None
    Cf_neg: float | None = None
    sigma_pos_std: float | None = None
    sigma_neg_std: float | None = None
    Cf_pos_std: float | None = None
    Cf_neg_std: float | None = None
    s: float | None = None
    s_note: str = ""
    sample_time: float = field(default=1e-3)
    filter_hz: float = 100.0
    decimation: int = DEFAULT_DECIMATION
    input_gain: float = 1.0
    force_peak: float = 0.0
    noise_rms: float = 0.0
    quantization: float = 0.0
    reversals: int = 0
    source: str = ""
    warnings: tuple[str, ...] = ()

    _KEYS = ("m", "sigma", "Cf", "offset", "m_std", "sigma_std", "Cf_std", "offset_std", "nrmse_percent",
             "condition_number", "samples")
    _ASYM = ("sigma_pos", "sigma_neg", "Cf_pos", "Cf_neg")
    _EXTRA = ("s", "s_note", "model", "sample_time", "filter_hz", "decimation")

    def to_dict(self) -> dict:
        """JSON-ready mapping: the parameters, their standard errors and the fit statistics.

        Keys: ``m, sigma, Cf, offset, m_std, sigma_std, Cf_std, offset_std, nrmse_percent,
        condition_number, samples``; with ``asymmetric`` also ``sigma_pos, sigma_neg, Cf_pos,
        Cf_neg``; always ``s, s_note, model, sample_time, filter_hz, decimation``; and ``warnings``
        (a list of sentences) when the identification is not physical.
        """
        data = asdict(self)
        keys = self._KEYS + (self._ASYM if self.model == "asymmetric" else ()) + self._EXTRA
        out = {k: data[k] for k in keys}
        if self.warnings:
            out["warnings"] = list(self.warnings)
        return out

    def friction(self, v: np.ndarray | float) -> np.ndarray:
        """Model friction force [N] along a velocity trace ``v`` [m/s], without the offset.

        ``Cf sign(v) + sigma v`` (per direction for ``asymmetric``; 0 at ``v = 0``). The
        offset is a load, not friction: it is the config's ``G`` (see :meth:`to_config`).
        The actuator force the model predicts is ``m a + friction(v) + offset``.

        Examples
        --------
        >>> ident = Identification(model="coulomb-viscous", m=1.0, sigma=10.0, Cf=2.0, offset=0.5, m_std=0.0,
        ...                        sigma_std=0.0, Cf_std=0.0, offset_std=0.0, nrmse_percent=0.0,
        ...                        condition_number=1.0, samples=100)
        >>> ident.friction(np.array([-0.1, 0.0, 0.2])).tolist()
        [-3.0, 0.0, 4.0]
        """
        v = np.asarray(v, dtype=float)
        if self.model == "asymmetric":
            return np.where(v > 0, self.Cf_pos + self.sigma_pos * v, np.where(v < 0, -self.Cf_neg + self.sigma_neg * v, 0.0))
        return self.Cf * np.sign(v) + self.sigma * v

    def to_config(self, *, name: str = "identified", K: float | None = None, u_max: float | None = None,
                  rho: float = 4.0, presliding_window: float = PRESLIDING_WINDOW):
        """A complete :class:`obsdesign.Config` for this axis; see :func:`obsdesign.data.rules.config_from`."""
        from .rules import config_from

        return config_from(self, name=name, K=K, u_max=u_max, rho=rho, presliding_window=presliding_window)

    # -- display ---------------------------------------------------------------------------------
    def _rows(self) -> list[tuple[str, str]]:
        def pm(value, std, unit, digits=5):
            return f"{value:.{digits}g} ± {std:.2g} {unit}"

        rows = [("model", self.model), ("source", self.source or "-"),
                ("m", pm(self.m, self.m_std, "kg")), ("sigma", pm(self.sigma, self.sigma_std, "N s/m")),
                ("Cf", pm(self.Cf, self.Cf_std, "N")), ("offset", pm(self.offset, self.offset_std, "N"))]
        if self.model == "asymmetric":
            rows += [("sigma_pos", pm(self.sigma_pos, self.sigma_pos_std, "N s/m")),
                     ("sigma_neg", pm(self.sigma_neg, self.sigma_neg_std, "N s/m")),
                     ("Cf_pos", pm(self.Cf_pos, self.Cf_pos_std, "N")),
                     ("Cf_neg", pm(self.Cf_neg, self.Cf_neg_std, "N"))]
        rows += [("s", "-" if self.s is None else f"{self.s:.5g} 1/m"), ("s note", self.s_note),
                 ("NRMSE", f"{self.nrmse_percent:.3g} %"), ("condition number", f"{self.condition_number:.4g}"),
                 ("rows in the fit", str(self.samples)),
                 ("filter", f"Butterworth {FILTER_ORDER}th order {self.filter_hz:g} Hz, zero phase"),
                 ("decimation", f"{self.decimation} (sample time {self.sample_time:g} s)")]
        rows += [("WARNING", w) for w in self.warnings]
        return rows

    def __str__(self) -> str:
        rows = self._rows()
        width = max(len(k) for k, _ in rows)
        return "\n".join([f"Identification ({self.model})"] + [f"  {k:<{width}}  {v}" for k, v in rows])

    def _repr_html_(self) -> str:
        esc = html.escape
        body = "".join(f"<tr><th>{esc(k)}</th><td>{esc(v)}</td></tr>" for k, v in self._rows())
        return f"<table class='obsdesign-result'><caption>{esc('Identification (' + self.model + ')')}</caption>{body}</table>"


# -- the procedure -----------------------------------------------------------------------------

def _check_int(name: str, value: object, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise ValueError(f"{name}: expected an integer >= {low}, found {value!r}")
    return int(value)


def _ols(X: np.ndarray, y: np.ndarray, names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Estimates, covariance ``sigma_e^2 (X^T X)^-1``, residual, scaled condition number.

    The columns are scaled to a largest |value| of 1 before the solve, so LAPACK never sees an
    overflowing product (and never prints its own error text); a regressor that is non-finite,
    zero in every row or a combination of the others is refused naming it.
    """
    if not (np.all(np.isfinite(X)) and np.all(np.isfinite(y))):
        bad = [n for n, col in zip(names, X.T) if not np.all(np.isfinite(col))] or ["the force"]
        raise ValueError(f"trace: the regressor {', '.join(bad)} overflows to non-finite values (derivatives of the "
                         "position over the sample time); check the units of position and time")
    scale = np.max(np.abs(X), axis=0)
    zero = [n for n, sc in zip(names, scale) if not sc > 0]
    if zero:
        raise ValueError(f"trace: expected every regressor to vary, found {', '.join(zero)} zero in every row of "
                         "the fit: the record does not excite that term")
    Xs = X / scale
    y_scale = float(np.max(np.abs(y))) or 1.0
    theta_s, _, rank, _ = np.linalg.lstsq(Xs, y / y_scale, rcond=None)
    if rank < X.shape[1]:
        raise ValueError(f"trace: the regressors ({', '.join(names)}) are linearly dependent over the rows of the "
                         f"fit (rank {rank} of {X.shape[1]}): the record cannot separate these terms")
    theta = theta_s * y_scale / scale
    resid = y - X @ theta
    dof = X.shape[0] - X.shape[1]
    sigma2 = float(resid @ resid) / dof
    cov = sigma2 * np.linalg.inv(Xs.T @ Xs) / scale[:, None] / scale[None, :]  # no overflowing outer product
    cond = float(np.linalg.cond(Xs / np.linalg.norm(Xs, axis=0)))
    return theta, cov, resid, cond


def _implausible(result: dict, input_gain: float) -> tuple[str, ...]:
    """Sentences naming each identified m, sigma, Cf (and per-direction level) <= 0 with its likely cause."""
    names = {"m": ("mass", "kg"), "sigma": ("viscous coefficient", "N s/m"), "Cf": ("Coulomb level", "N"),
             "sigma_pos": ("viscous coefficient for v > 0", "N s/m"),
             "sigma_neg": ("viscous coefficient for v < 0", "N s/m"),
             "Cf_pos": ("Coulomb level for v > 0", "N"), "Cf_neg": ("Coulomb level for v < 0", "N")}
    bad = [k for k in names if result.get(k) is not None and not result[k] > 0]
    if not bad:
        return ()
    if input_gain < 0:
        cause = (f"the input gain is negative (input_gain = {input_gain:g}): check its sign; a force that opposes "
                 "the logged input gives a negative mass")
    elif result["m"] <= 0 and result["sigma"] <= 0 and result["Cf"] <= 0:
        cause = ("every term is negative: the input acts against the position, so check the sign of the input "
                 "gain (or of the position column)")
    else:
        cause = ("check that the position and input columns are not swapped, the sign of the input gain, and the "
                 "units (position in m, time in s, input times the gain in N)")
    found = ", ".join(f"{k} = {result[k]:.4g} {names[k][1]}" for k in bad)
    return (f"identify: not physical: expected a positive {names[bad[0]][0]}, found {found}; {cause}",)


def _quantization(position: np.ndarray) -> float:
    """Smallest nonzero position increment if every increment is a multiple of it, else 0."""
    steps = np.abs(np.diff(position))
    steps = steps[steps > 0]
    if steps.size == 0:
        return 0.0
    q = float(steps.min())
    ratio = steps / q
    return q if bool(np.all(np.abs(ratio - np.round(ratio)) < 1e-3)) else 0.0


def identify(trace: Trace, *, model: str = "coulomb-viscous", filter_hz: float | None = None,
             decimation: int | None = None, presliding_window: float = PRESLIDING_WINDOW) -> Identification:
    """Fit ``u = m a + sigma v + Cf sign(v) + offset`` to a trace by ordinary least squares.

    Parameters
    ----------
    trace : Trace
    model : {'coulomb-viscous', 'asymmetric'}
        ``asymmetric`` fits separate viscous and Coulomb terms for ``v > 0`` and ``v < 0``
        with one common offset (see Notes for what the data can separate).
    filter_hz : float, optional
        Cut-off [Hz] of the 4th-order zero-phase Butterworth low-pass. Default: a tenth
        of the sampling rate (the benchmark's 100 Hz at 1 kHz).
    decimation : int, optional
        Decimation factor, default 10 (the benchmark's factor at 1 kHz).
    presliding_window : float
        Largest travel [m] after a reversal still taken as pre-sliding (default 1e-4 m).

    Returns
    -------
    Identification

    Raises
    ------
    ValueError
        A bad model, cut-off, decimation or window; a trace too short for them; an input that
        is constant; a position that barely moves.

    Warns
    -----
    UserWarning
        If the identified m, sigma or Cf is <= 0 (also in :attr:`Identification.warnings`), naming the
        likely cause: the sign of the input gain, swapped columns, units.

    Notes
    -----
    1. Position and force are low-passed by the same Butterworth filter run forwards and
       backwards (``sosfiltfilt``): zero phase, so no lag between the columns.
    2. Velocity and acceleration by central differences (``numpy.gradient``); 5 periods of
       the cut-off (50 samples at the default) are cut at both ends (filter transients).
    3. Every regressor column and the force are decimated in parallel by
       ``scipy.signal.decimate`` (8th-order Chebyshev I anti-alias filter at 0.8 of the new
       Nyquist frequency, zero phase). Oversampled rows are strongly correlated, which OLS
       statistics assume they are not; decimation keeps one row per correlation length.
    4. Rows with ``|v|`` at or below 1 % of the largest ``|v|`` are dropped: there the axis
       sticks or is in pre-sliding, where ``Cf sign(v)`` (eq:2:1:2) does not hold.
    5. ``asymmetric``: in gross sliding the data determine only the two levels
       ``Cf_pos + offset`` and ``offset - Cf_neg``, not all three terms. The common offset
       is therefore taken from the ``coulomb-viscous`` fit of the same rows, and ``Cf_pos``,
       ``Cf_neg`` are the levels minus/plus it (standard errors propagated linearly).
    6. ``s`` (eq:2:3:1-2:3:5) is fitted only if at least 5 reversals each stay within
       ``presliding_window`` of the reversal point for 5 rows of the fit grid (``5 decimation``
       samples) over at least 5 distinct encoder readings; otherwise ``s = None`` and
       ``s_note`` says why.

    Examples
    --------
    >>> import obsdesign as od
    >>> from obsdesign.data import Trace
    >>> cfg = od.load_preset("vcm").override(m=2.0, sigma=20.0, Cf=1.0, s=1e5, G=3.0, dt=1e-4)
    >>> res = od.simulate(cfg, od.sim.Excitation(force_rms=20.0), duration=10.0, seed=1)
    >>> tr = Trace(t=res.t, position=res.x_meas, force=res.u + 3.0, sample_time=1e-4)  # actuator force
    >>> ident = identify(tr)
    >>> [round(p, 1) for p in (ident.m, ident.sigma, ident.Cf, ident.offset)]
    [2.0, 20.0, 1.0, 3.0]
    """
    from scipy import signal

    if not isinstance(trace, Trace):
        raise TypeError(f"trace: expected a Trace, found {type(trace).__name__}")
    if not isinstance(model, str) or model not in MODELS:
        raise ValueError(f"model: expected one of {', '.join(repr(m) for m in MODELS)}, found {model!r}")
    dt = trace.sample_time
    fs = 1.0 / dt
    if filter_hz is None:
        filter_hz = FILTER_FRACTION * fs
    elif isinstance(filter_hz, bool) or not isinstance(filter_hz, (int, float)) or not 0 < filter_hz < 0.5 * fs:
        raise ValueError(f"filter_hz: expected a cut-off in (0, {0.5 * fs:g}) Hz (below Nyquist), found {filter_hz!r}")
    q = DEFAULT_DECIMATION if decimation is None else _check_int("decimation", decimation, 1)
    if isinstance(presliding_window, bool) or not isinstance(presliding_window, (int, float)) or not presliding_window > 0:
        raise ValueError(f"presliding_window: expected a finite number > 0 [m], found {presliding_window!r}")
    force_range = float(np.ptp(trace.force))
    if not force_range > 0.0:
        raise ValueError(f"input: the record has constant input ({float(trace.force[0]):g} N in every sample of "
                         f"{trace.source!r}); nothing to identify: the fit needs a force that varies")
    border = int(math.ceil(5.0 * fs / filter_hz))
    n_used = trace.samples - 2 * border
    if n_used < 20 * q:
        raise ValueError(f"trace: expected at least {2 * border + 20 * q} samples for filter_hz = {filter_hz:g} Hz "
                         f"and decimation {q}, found {trace.samples}")

    sos = signal.butter(FILTER_ORDER, filter_hz, fs=fs, output="sos")
    x_f = signal.sosfiltfilt(sos, trace.position)
    u_f = signal.sosfiltfilt(sos, trace.force)
    v = np.gradient(x_f, dt)
    a = np.gradient(v, dt)
    keep = slice(border, trace.samples - border)

    def dec(col: np.ndarray) -> np.ndarray:
        col = col[keep]
        return signal.decimate(col, q, ftype="iir", zero_phase=True) if q > 1 else col

    pos, neg = (v > 0).astype(float), (v < 0).astype(float)
    cols = {"a": dec(a), "v": dec(v), "sign": dec(np.sign(v)), "one": dec(np.ones_like(v)),
            "v_pos": dec(v * pos), "v_neg": dec(v * neg), "pos": dec(pos), "neg": dec(neg)}
    y = dec(u_f)
    moving = np.abs(cols["v"]) > REVERSAL_THRESHOLD * np.max(np.abs(cols["v"]))
    if np.count_nonzero(moving) < 10:
        raise ValueError(f"trace: expected motion in at least 10 rows of the fit, found {np.count_nonzero(moving)} "
                         f"(the position barely changes)")
    y = y[moving]
    X = np.column_stack([cols[c][moving] for c in ("a", "v", "sign", "one")])
    theta, cov, resid, cond = _ols(X, y, ("acceleration", "velocity", "sign(v)", "offset"))
    std = np.sqrt(np.diag(cov))
    result = dict(m=theta[0], sigma=theta[1], Cf=theta[2], offset=theta[3], m_std=std[0], sigma_std=std[1],
                  Cf_std=std[2], offset_std=std[3])
    if model == "asymmetric":
        Xa = np.column_stack([cols[c][moving] for c in ("a", "v_pos", "v_neg", "pos", "neg")])
        th, cov_a, resid, cond = _ols(Xa, y, ("acceleration", "v for v > 0", "v for v < 0", "v > 0", "v < 0"))
        sd = np.sqrt(np.diag(cov_a))
        # offset from the symmetric fit: a linear map r of y; levels: rows p of the pseudo-inverse
        r = np.linalg.pinv(X)[3]
        pinv_a = np.linalg.pinv(Xa)
        s2 = float(resid @ resid) / (Xa.shape[0] - Xa.shape[1])
        off = theta[3]
        cf_pos, cf_neg = th[3] - off, off - th[4]
        cf_pos_std = math.sqrt(s2 * float(np.sum((pinv_a[3] - r) ** 2)))
        cf_neg_std = math.sqrt(s2 * float(np.sum((r - pinv_a[4]) ** 2)))
        mean_row = 0.5 * (pinv_a[1] + pinv_a[2]), 0.5 * (pinv_a[3] - pinv_a[4])
        result.update(m=th[0], m_std=sd[0], sigma=0.5 * (th[1] + th[2]), Cf=0.5 * (th[3] - th[4]),
                      sigma_std=math.sqrt(s2 * float(np.sum(mean_row[0] ** 2))),
                      Cf_std=math.sqrt(s2 * float(np.sum(mean_row[1] ** 2))),
                      sigma_pos=th[1], sigma_neg=th[2], Cf_pos=cf_pos, Cf_neg=cf_neg,
                      sigma_pos_std=sd[1], sigma_neg_std=sd[2], Cf_pos_std=cf_pos_std, Cf_neg_std=cf_neg_std)
    result = {k: float(v_) for k, v_ in result.items()}
    power = float(np.mean(y**2))
    nrmse = 100.0 * math.sqrt(float(np.mean(resid**2)) / power) if power > 0 else math.inf
    notes = _implausible(result, trace.input_gain)
    for note in notes:
        warnings.warn(note, stacklevel=2)

    quantum = _quantization(trace.position)
    noise = float(np.sqrt(np.mean((trace.position - x_f)[keep] ** 2)))
    noise = math.sqrt(max(0.0, noise**2 - quantum**2 / 12.0))
    s, note = fit_presliding(x=trace.position[keep], x_f=x_f[keep], v=v[keep], a=a[keep], u_f=u_f[keep], dt=dt,
                             m=result["m"], sigma=result["sigma"], Cf=result["Cf"], offset=result["offset"],
                             rows=q, window=float(presliding_window))
    return Identification(model=model, **result, nrmse_percent=nrmse, condition_number=cond,
                          samples=int(y.size), s=s, s_note=note, sample_time=dt, filter_hz=float(filter_hz),
                          decimation=q, input_gain=trace.input_gain, force_peak=float(np.max(np.abs(trace.force))),
                          noise_rms=noise, quantization=quantum, reversals=int(_reversals(v, REVERSAL_THRESHOLD * float(np.max(np.abs(v)))).size),
                          source=trace.source, warnings=notes)
