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
from dataclasses import dataclass, field
from functools import partial

import numpy as np

from ._idim import MAX_BOOTSTRAP, check_int, implausible, positive_number, time_window
from ._ident_fit import fit_aligned, interval_method, past_presliding, presliding_notice, timing_spread
from .choices import INPUT_TIMINGS, MAX_DELAY, STRIBECK_CHOICES
from .cutoff import choose_filter
from .estimate import cautions, widened
from .friction_fit import check_bounds, check_fix
from .stribeck_rows import FITTED
from ._ident_rows import ASYM, FILTER_ORDER, rows
from .timing import aligned, check_delay, find_timing
from .presliding import MIN_REVERSALS, MIN_ROWS as MIN_PRESLIDING_ROWS, _reversals
from .trace import REVERSAL_THRESHOLD, Trace
from .uncertainty import N_BOOT
from .units import Units, check_plausible

__all__ = ["Identification", "identify", "MODELS", "FILTER_ORDER", "DEFAULT_DECIMATION",
           "MIN_REVERSALS", "MIN_PRESLIDING_ROWS"]

MODELS = ("coulomb-viscous", "asymmetric")
#: Decimation factor at the largest default cut-off (a tenth of the sampling rate): the benchmark's
#: round(0.8 fnyq / (2 * 20 Hz)) = 10 at 1 kHz. The default is ``round(fs / filter_hz)``.
DEFAULT_DECIMATION = 10
#: Default pre-sliding window [m]: the largest travel after a reversal still called pre-sliding.
PRESLIDING_WINDOW = 1e-4
#: Rows within ``PRESLIDING_TRAVEL / s`` of travel past a reversal are left out of the gross-sliding fit
#: (``s`` fitted from the log; the paper's map reaches the Coulomb level at ``1/s``).
PRESLIDING_TRAVEL = 1.0
#: ``s`` is reported from ``presliding_window``; where no reversal dwells there, the rows' travel floor alone comes
#: from ``10^k`` times it, ``0 < k < WINDOW_STEPS`` (``_ident_fit.past_presliding``; a fast reversal leaves 0.1 mm
#: before 5 rows). A third step (100 times) moved EMPS's estimates by up to 1.9 %; two leave EMPS unchanged.
WINDOW_STEPS = 2


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
    filter_rule : str
        How ``filter_hz`` was chosen: ``given``, or the rule of :mod:`obsdesign.data.cutoff` as applied.
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
    Fs, vs, Fs_std, vs_std : float or None
        Stribeck level at standstill [N] and Stribeck speed [m/s] when the term is kept.
    stribeck : bool
        Whether the Stribeck term is in the model.
    selection : str
        The model selection: the BIC with and without the Stribeck term and the decision.
    intervals : dict
        ``name -> (low, high)``: 95 % intervals of every parameter (moving-block bootstrap,
        widened by the errors-in-variables shift; ``interval_method`` says which); a fitted ``Fs``, ``vs``:
        the profile likelihood joined with the bootstrap's, widened likewise; and by the ``timing_shift``.
    interval_method : str
        How :attr:`intervals` were obtained.
    eiv_shift : dict
        ``name -> shift``: predicted change of the bias-compensated estimate (errors in variables).
    model_shift : dict
        ``name -> shift``: the change of the estimate without the rows near reversals (below
        :data:`~obsdesign.data.estimate.MODEL_SHIFT_FACTOR` x the min speed), which widens the interval: model error.
    at_bound : dict
        ``name -> 'lower'|'upper'`` for a fitted parameter at one of its bounds.
    fixed : tuple of str
        Parameters held at a given value.
    min_speed : float
        The speed threshold of the rows of the fit [m/s] (with the Stribeck term kept: ``stribeck_min_speed``).
    stribeck_min_speed : float
        The min speed of the Stribeck decision's rows [m/s] (:mod:`obsdesign.data.stribeck_rows`).
    travel_floor : float
        Rows within this travel past a velocity reversal were left out [m, rad]: ``1/s`` with ``s`` fitted
        (the pre-sliding regime, where the gross-sliding model does not hold); 0 when ``s`` is not.
    window : str
        The time window of the fit (empty: the whole record).
    units : Units
        The units of the log (axis kind, input unit); values here are SI.
    notices : tuple of str
        Cautions: implausible values for the units, a parameter at a bound, an errors-in-variables
        bias larger than the interval (naming a better excitation).
    input_timing : str
        The input timing the fit used: ``'sample'`` (as logged) or ``'hold'``.
    delay_samples : int
        Samples the position is logged after the input it answers to (the drive's delay).
    timing_note : str
        How the timing and the delay were found (:mod:`obsdesign.data.timing`), and how sure.
    timing_evidence : dict
        ``'timing/delay' -> BIC difference`` to the best candidate (empty when both were given).
    timing_shift : dict
        ``name -> (low, high)``: the most negative and most positive change of the estimate under the other
        timings the data do not reject, which widens the interval (empty when the timing is resolved or
        given; :mod:`obsdesign.data._ident_fit`). A notice says so in one line.
    presliding_shift : dict
        ``name -> shift``: where ``s`` is not resolved, the change without the rows within ``presliding_window``
        past each reversal, which widens the interval (else empty); a notice names those beyond 2 standard errors.
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
    filter_rule: str = "given"
    input_gain: float = 1.0
    force_peak: float = 0.0
    noise_rms: float = 0.0
    quantization: float = 0.0
    reversals: int = 0
    source: str = ""
    warnings: tuple[str, ...] = ()
    Fs: float | None = None
    vs: float | None = None
    Fs_std: float | None = None
    vs_std: float | None = None
    stribeck: bool = False
    selection: str = ""
    intervals: dict = field(default_factory=dict)
    interval_method: str = ""
    eiv_shift: dict = field(default_factory=dict)
    model_shift: dict = field(default_factory=dict)
    at_bound: dict = field(default_factory=dict)
    fixed: tuple[str, ...] = ()
    min_speed: float = 0.0
    stribeck_min_speed: float = 0.0
    travel_floor: float = 0.0
    window: str = ""
    units: Units = field(default_factory=Units)
    notices: tuple[str, ...] = ()
    input_timing: str = "sample"
    delay_samples: int = 0
    timing_note: str = ""
    timing_evidence: dict = field(default_factory=dict)
    timing_shift: dict = field(default_factory=dict)
    presliding_shift: dict = field(default_factory=dict)

    _KEYS = ("m", "sigma", "Cf", "offset", "m_std", "sigma_std", "Cf_std", "offset_std", "nrmse_percent",
             "condition_number", "samples")
    _ASYM = ("sigma_pos", "sigma_neg", "Cf_pos", "Cf_neg")
    _EXTRA = ("s", "s_note", "model", "sample_time", "filter_hz", "filter_rule", "decimation", "stribeck", "selection",
              "interval_method", "at_bound", "fixed", "min_speed", "stribeck_min_speed", "travel_floor", "window", "input_timing",
              "delay_samples", "timing_note")

    def to_dict(self) -> dict:
        """JSON-ready mapping: the parameters, their standard errors and the fit statistics.

        Keys: ``m, sigma, Cf, offset, m_std, sigma_std, Cf_std, offset_std, nrmse_percent,
        condition_number, samples``; with ``asymmetric`` also ``sigma_pos, sigma_neg, Cf_pos,
        Cf_neg``; with the Stribeck term ``Fs, vs, Fs_std, vs_std``; always ``s, s_note, model,
        sample_time, filter_hz, filter_rule, decimation, stribeck, selection, interval_method, at_bound, fixed,
        min_speed, stribeck_min_speed, travel_floor, window, input_timing, delay_samples, timing_note``, ``timing_evidence``, ``model_shift``, ``presliding_shift``, ``timing_shift`` (name -> [low, high]), ``intervals`` (name -> [low, high]), ``eiv_shift`` and ``units``
        (``axis``, ``input_unit``, ``mass_unit``, ``force_unit``, ``length_unit``, the logged
        ``time``/``position`` units); ``warnings`` (a list of sentences) when the identification is
        not physical, ``notices`` when there are cautions.
        """
        data = {f: getattr(self, f) for f in self.__dataclass_fields__}
        keys = (self._KEYS + (self._ASYM if self.model == "asymmetric" else ())
                + (("Fs", "vs", "Fs_std", "vs_std") if self.stribeck else ()) + self._EXTRA)
        out = {k: data[k] for k in keys}
        out["intervals"] = {k: list(v) for k, v in self.intervals.items()}
        out["eiv_shift"] = dict(self.eiv_shift)
        out["timing_evidence"] = dict(self.timing_evidence)
        out["model_shift"] = dict(self.model_shift)
        out["timing_shift"] = {k: list(v) for k, v in self.timing_shift.items()}
        out["presliding_shift"] = dict(self.presliding_shift)
        u = self.units
        out["units"] = {"axis": u.axis, "input_unit": u.input_unit(self.input_gain), "mass_unit": u.mass_unit,
                        "force_unit": u.force_unit, "length_unit": u.length_unit, "time": u.time,
                        "position": u.position}
        if self.warnings:
            out["warnings"] = list(self.warnings)
        if self.notices:
            out["notices"] = list(self.notices)
        return out

    def friction(self, v: np.ndarray | float) -> np.ndarray:
        """Model friction force [N] along a velocity trace ``v`` [m/s], without the offset.

        ``Cf sign(v) + sigma v`` (per direction for ``asymmetric``; 0 at ``v = 0``), plus
        ``(Fs - Cf) sign(v) exp(-(v/vs)^2)`` with the Stribeck term. The
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
            out = np.where(v > 0, self.Cf_pos + self.sigma_pos * v, np.where(v < 0, -self.Cf_neg + self.sigma_neg * v, 0.0))
            level = np.where(v > 0, self.Cf_pos, self.Cf_neg)
        else:
            out, level = self.Cf * np.sign(v) + self.sigma * v, self.Cf
        if self.stribeck:
            out = out + (self.Fs - level) * np.sign(v) * np.exp(-((v / self.vs) ** 2))
        return out

    def to_config(self, *, name: str = "identified", K: float | None = None, u_max: float | None = None,
                  rho: float = 4.0, presliding_window: float = PRESLIDING_WINDOW):
        """A complete :class:`obsdesign.Config` for this axis; see :func:`obsdesign.data.rules.config_from`."""
        from .rules import config_from

        return config_from(self, name=name, K=K, u_max=u_max, rho=rho, presliding_window=presliding_window)

    # -- display ---------------------------------------------------------------------------------
    def _rows(self) -> list[tuple[str, str]]:
        return rows(self)

    def __str__(self) -> str:
        rows = self._rows()
        width = max(len(k) for k, _ in rows)
        return "\n".join([f"Identification ({self.model})"] + [f"  {k:<{width}}  {v}" for k, v in rows])

    def _repr_html_(self) -> str:
        esc = html.escape
        body = "".join(f"<tr><th>{esc(k)}</th><td>{esc(v)}</td></tr>" for k, v in self._rows())
        return f"<table class='obsdesign-result'><caption>{esc('Identification (' + self.model + ')')}</caption>{body}</table>"


# -- the procedure -----------------------------------------------------------------------------

def identify(trace: Trace, *, model: str = "coulomb-viscous", filter_hz: float | None = None,
             decimation: int | None = None, presliding_window: float = PRESLIDING_WINDOW, stribeck: str = "auto",
             fix: dict | None = None, bounds: dict | None = None, min_speed: float | None = None,
             window: tuple[float, float] | None = None, n_boot: int = N_BOOT, seed: int = 0,
             input_timing: str = "auto", delay_samples: int | None = None,
             stribeck_min_speed: float | None = None) -> Identification:
    """Fit ``u = m a + sigma v + Cf sign(v) + offset`` (+ a Stribeck term) to a trace, within bounds.

    Parameters
    ----------
    trace : Trace
    model : {'coulomb-viscous', 'asymmetric'}
        ``asymmetric`` fits separate viscous and Coulomb terms for ``v > 0`` and ``v < 0``
        with one common offset (see Notes for what the data can separate).
    filter_hz : float, optional
        Cut-off [Hz] of the 4th-order zero-phase Butterworth low-pass. Default: from the record,
        one octave above where the position's spectrum meets its noise floor, at most a tenth of
        the sampling rate (the benchmark's 100 Hz at 1 kHz): :func:`obsdesign.data.cutoff.noise_cutoff`;
        and at least an octave above the force's bandwidth (:func:`obsdesign.data.cutoff.force_bandwidth`).
    decimation : int, optional
        Decimation factor, default ``round(fs / filter_hz)`` (the benchmark's 10 at 100 Hz and
        1 kHz): the decimation filter (0.4 ``filter_hz``) then band-limits the rows below the
        low-pass, so the force and the nonlinear Coulomb and Stribeck columns share one filter.
    presliding_window : float
        Largest travel [m] after a reversal still taken as pre-sliding (default 1e-4 m).
    stribeck : {'auto', 'on', 'off'}
        The Stribeck term ``(Fs - Cf) sign(v) exp(-(v/vs)^2)``: kept by the model selection of
        :mod:`obsdesign.data.estimate` (``auto``) on the rows of :mod:`obsdesign.data.stribeck_rows`, always
        fitted, or never.
    fix : dict, optional
        Parameters held at a value, e.g. ``{"sigma": 12.0}`` (names of
        :data:`obsdesign.data.friction_fit.PARAMETERS` and ``ASYMMETRIC``).
    bounds : dict, optional
        ``{name: (low, high)}``; defaults: ``m, sigma, Cf, Fs >= 0`` (a fit never returns a
        negative viscous coefficient), ``vs`` between ``stribeck_min_speed`` and half the peak speed.
    min_speed : float, optional
        Rows with ``|v|`` at or below it [m/s, rad/s] are left out; default 1 % of the peak.
    stribeck_min_speed : float, optional
        The min speed of the rows of the Stribeck decision and fit [m/s, rad/s], at most ``min_speed``; default
        ``min_speed`` if given, else the slowest trusted speed (:mod:`obsdesign.data.stribeck_rows`).
    window : (float, float), optional
        Only the samples with ``t0 <= t <= t1`` [s].
    n_boot : int
        Bootstrap replicates of the intervals, at most 100,000 (0: intervals of 1.96 standard errors).
    seed : int
        Seed of the bootstrap.
    input_timing : {'auto', 'sample', 'hold'}
        ``hold``: the input logged at sample ``n`` is held until ``n + 1`` (a sampled controller's
        output, zero-order hold, as in :func:`obsdesign.simulate`); the second-difference
        acceleration at ``n`` then corresponds exactly to ``(u[n-1] + u[n]) / 2``, which is used. ``sample``
        (the EMPS benchmark's IDIM-LS): the input as logged. On a held input, ``sample``
        biases the viscous coefficient (-1 % open loop, -3 % closed loop in the coverage check).
        ``auto`` (default): found from the data with the delay (:mod:`obsdesign.data.timing`).
    delay_samples : int, optional
        Samples (0 to 50) the position is logged after the input it answers to; default: found
        from the data among 0 to 3 (``MAX_DELAY``). The fit pairs
        ``position[n + d]`` with ``force[n]``.

    Returns
    -------
    Identification

    Raises
    ------
    ValueError
        A bad model, cut-off, decimation, window, bound, fixed value or minimum speed; a trace
        too short for them; an input that is constant; a position that barely moves.

    Warns
    -----
    UserWarning
        If the identified m, sigma or Cf is <= 0 (also in :attr:`Identification.warnings`), naming the
        likely cause: the sign of the input gain, swapped columns, units. Plausibility and
        uncertainty cautions are in :attr:`Identification.notices` (not warned).

    Notes
    -----
    1. Position and force are low-passed by the same Butterworth filter run forwards and
       backwards (``sosfiltfilt``): zero phase, so no lag between the columns.
    2. Velocity by ``numpy.gradient``, acceleration by the second difference (exact for a mass
       under a held input, :func:`~obsdesign.data._idim.second_difference`); 5 periods of the
       cut-off (50 samples at the default) are cut at both ends (filter transients).
    3. Every regressor column and the force are decimated in parallel by
       ``scipy.signal.decimate`` (8th-order Chebyshev I anti-alias filter at 0.8 of the new
       Nyquist frequency, zero phase). Oversampled rows are strongly correlated, which OLS
       statistics assume they are not; decimation keeps one row per correlation length.
    4. Rows with ``|v|`` at or below ``min_speed`` (1 % of the largest ``|v|``) are dropped: there
       the axis sticks or is in pre-sliding, where ``Cf sign(v)`` (eq:2:1:2) does not hold. Where ``s`` is
       fitted (8.; for the rows only, also in 10 times the window), so are the rows within ``1/s`` of travel past
       a reversal (``travel_floor``) at any speed, and the fit is run again: the friction is in pre-sliding there
       (the example log: m -1.7 %, Cf -3.3 % and intervals that missed the truth before, -0.18 %, +0.06 % after).
    5. Bounded least squares (:mod:`obsdesign.data.friction_fit`); without an active bound, a
       fixed value or the Stribeck term this is the IDIM-LS solution and ``*_std`` are its
       standard errors ``sigma_e^2 (X^T X)^-1``; otherwise from the Jacobian at the solution.
    6. ``asymmetric``: in gross sliding the data determine only the two levels
       ``Cf_pos + offset`` and ``offset - Cf_neg``, not all three terms. The common offset
       is therefore taken from the ``coulomb-viscous`` fit of the same rows, and ``Cf_pos``,
       ``Cf_neg`` are the levels minus/plus it (standard errors propagated linearly).
    7. ``intervals``: a moving-block bootstrap widened by the errors-in-variables shift
       (:mod:`obsdesign.data.uncertainty`); for a fitted ``Fs`` and ``vs`` joined with the profile likelihood
       (:func:`~obsdesign.data.friction_fit.profile_interval`; ``docs/measured-data.md``); when the log's
       timing is not resolved, widened to the fits under the other timings not rejected (``timing_shift``).
    8. ``s`` (eq:2:3:1-2:3:5) is fitted only if at least 5 reversals each stay within
       ``presliding_window`` of the reversal point for 5 rows of the fit grid (``5 decimation``
       samples; 50 samples, the benchmark's grid, when ``decimation`` is not given) over at least 5 distinct encoder readings; otherwise ``s = None`` and
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
    >>> lo, hi = ident.intervals["m"]          # 95 %: a bootstrap over the record
    >>> bool(lo < ident.m < hi and (hi - lo) / ident.m < 0.01)
    True
    """
    if not isinstance(trace, Trace):
        raise TypeError(f"trace: expected a Trace, found {type(trace).__name__}")
    if not isinstance(model, str) or model not in MODELS:
        raise ValueError(f"model: expected one of {', '.join(repr(m) for m in MODELS)}, found {model!r}")
    if not isinstance(stribeck, str) or stribeck not in STRIBECK_CHOICES:
        raise ValueError(f"stribeck: expected one of {', '.join(map(repr, STRIBECK_CHOICES))}, found {stribeck!r}")
    fix, bounds = check_fix(fix), check_bounds(bounds)
    both = sorted(set(fix) & set(bounds))
    if both:
        raise ValueError(f"fix, bounds: expected a parameter either fixed or bounded, found {both[0]!r} in both")
    n_boot, seed = check_int("n_boot", n_boot, 0, MAX_BOOTSTRAP), check_int("seed", seed, 0)
    dt = trace.sample_time
    fs = 1.0 / dt
    position, force, span = time_window(trace, window)
    filter_hz, filter_rule, q = choose_filter(position, dt, filter_hz, decimation, force=force)
    presliding_window = positive_number("presliding_window", presliding_window, 0.0, trace.units.length_unit)
    if min_speed is not None:
        min_speed = positive_number("min_speed", min_speed, 0.0, trace.units.si("speed"))
    if not isinstance(input_timing, str) or input_timing not in INPUT_TIMINGS:
        raise ValueError(f"input_timing: expected one of {', '.join(map(repr, INPUT_TIMINGS))}, found {input_timing!r}")
    delay_samples = None if delay_samples is None else check_delay(delay_samples, check_int("delay_samples",
                                                                                           delay_samples, 0))
    force_range = float(np.ptp(force))
    if not force_range > 0.0:
        raise ValueError(f"input: the record has constant input ({float(force[0]):g} {trace.units.force_unit} in "
                         f"every sample of {trace.source!r}); nothing to identify: the fit needs a force that varies")
    border = int(math.ceil(5.0 * fs / filter_hz))
    top = MAX_DELAY if delay_samples is None else delay_samples
    if position.size - top - 2 * border < 20 * q:
        raise ValueError(f"trace: expected at least {2 * border + 20 * q + top} samples for filter_hz = {filter_hz:g} "
                         f"Hz, decimation {q} and a delay of up to {top} samples, found {position.size}")
    found = find_timing(position, force, dt=dt, filter_hz=filter_hz, decimation=q,
                        timing=None if input_timing == "auto" else input_timing, delay=delay_samples,
                        min_speed=min_speed)
    kw = dict(dt=dt, filter_hz=filter_hz, q=q, model=model, fix=fix, bounds=bounds, speed=trace.units.si("speed"))
    pair = aligned(position, force, found.timing, found.delay)
    fit = partial(fit_aligned, *pair, stribeck=stribeck, min_speed=min_speed, n_boot=n_boot, seed=seed,
                  stribeck_min_speed=stribeck_min_speed, **kw)  # a refit overrides any keyword
    fitted = fit()
    fitted, s, s_note, floor, pre_shift = past_presliding(
        fitted, pair[0], dt=dt, rows=DEFAULT_DECIMATION if decimation is None else q, window=presliding_window,
        steps=WINDOW_STEPS, travel=PRESLIDING_TRAVEL, length_unit=trace.units.length_unit,
        refit=lambda f, **o: fit(travel_floor=f, **o))
    kw["travel_floor"] = floor
    est, intervals, model_shift, cols, y, threshold = (fitted[k] for k in FITTED)
    intervals = widened(intervals, est["values"], pre_shift)
    pre_note = presliding_notice(pre_shift, est, presliding_window, trace.units.length_unit, trace.units.si)
    intervals, timing_shift, spread = timing_spread(position, force, found, fitted, intervals, est["values"],
                                                    unit=trace.units.si, **kw)
    v = fitted["v"]
    values, std = est["values"], est["std"]
    shown = ("m", "sigma", "Cf", "offset") + (ASYM if model == "asymmetric" else ()) + (("Fs", "vs") if est["stribeck"] else ())
    result = {k: float(values[k]) for k in shown} | {f"{k}_std": float(std.get(k, 0.0)) for k in shown}
    notes = implausible({k: (None if k in est["at_bound"] else v) for k, v in result.items()}, trace)
    for note in notes:
        warnings.warn(note, stacklevel=2)
    notices = trace.warnings + check_plausible(trace.units, mass=result["m"], gain=trace.input_gain) + cautions(
        est, cols, fitted["noise_var"], trace.units, filter_hz) + tuple(n for n in (pre_note, spread) if n)
    return Identification(model=model, **result, nrmse_percent=est["nrmse"], condition_number=est["condition_number"],
                          samples=int(y.size), s=s, s_note=s_note, sample_time=dt, filter_hz=float(filter_hz),
                          filter_rule=filter_rule, decimation=q, input_gain=trace.input_gain, force_peak=float(np.max(np.abs(pair[1]))),
                          noise_rms=fitted["noise_rms"], quantization=fitted["quantum"],
                          reversals=int(_reversals(v, REVERSAL_THRESHOLD * float(np.max(np.abs(v)))).size),
                          source=trace.source, warnings=notes, notices=notices, stribeck=est["stribeck"], selection=est["selection"],
                          intervals=intervals, eiv_shift=est["eiv_shift"], model_shift=model_shift,
                          at_bound=est["at_bound"], fixed=tuple(sorted(fix)), min_speed=float(threshold),
                          stribeck_min_speed=float(fitted["floor"]), travel_floor=floor,
                          window=span, timing_shift=timing_shift, presliding_shift=pre_shift,
                          interval_method=interval_method(est, n_boot, model_shift, fix, timing_shift, pre_shift),
                          units=trace.units, input_timing=found.timing, delay_samples=found.delay,
                          timing_note=found.note, timing_evidence=found.evidence)

