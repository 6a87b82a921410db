"""Measured data in figures and in the report's section "Validation on measured data".

:func:`observation_figure` draws an :class:`~obsdesign.data.Observation` (``obsdesign observe
--plot``); :func:`fit_figure` draws an identification's fit; :func:`data_section` computes
everything the report's section shows from a trace: the identification with its
uncertainty, the fit over time, and the observer of the identified config run over the
log against the identified model's friction. Render only: the numbers come from
:mod:`obsdesign.data`.
"""

from __future__ import annotations

import numpy as np

from .figures import inline_svg, plt

__all__ = ["observation_figure", "fit_figure", "data_section", "MOVING_FRACTION", "moving_mask"]

#: Default speed threshold of the data check, as a fraction of the record's peak speed: where the
#: zero-phase filtered speed is above it the axis moves and the model's ``Cf sign(v)`` is defined; below it
#: (standstill, reversals) the sign of a noisy velocity flips and the model chatters by +-Cf.
MOVING_FRACTION = 0.05


def observation_figure(obs, model_w3=None):
    """Position, velocity estimate, friction estimates and force of an observation.

    Parameters
    ----------
    obs : Observation
        The observer's run over a trace.
    model_w3 : ndarray, optional
        A model's value of the friction state [N] per sample (e.g.
        :func:`obsdesign.data.model_friction_state`), drawn for comparison.

    Returns
    -------
    matplotlib.figure.Figure

    Examples
    --------
    >>> import numpy as np, obsdesign as od
    >>> from obsdesign.data import Trace, observe
    >>> t = np.arange(1000) * 1e-4
    >>> tr = Trace(t=t, position=1e-4 * np.sin(20 * t), force=np.zeros(1000), sample_time=1e-4)
    >>> fig = observation_figure(observe(od.load_preset("table1"), tr))
    >>> [ax.get_ylabel() for ax in fig.axes]
    ['position [mm]', 'velocity [mm/s]', 'friction [N]', 'force [N]']
    >>> plt.close(fig)
    """
    t = obs.t
    fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True, constrained_layout=True)
    axes[0].plot(t, obs.x_meas * 1e3, label="measured position")
    axes[0].set_ylabel("position [mm]")
    axes[1].plot(t, obs.v_hat * 1e3, label="observer's velocity estimate")
    axes[1].set_ylabel("velocity [mm/s]")
    ax = axes[2]
    ax.plot(t, obs.f_hat, lw=0.5, alpha=0.6, label="friction estimate (raw)")
    ax.plot(t, obs.f_hat_filtered, label="friction estimate (low-pass filtered)")
    if model_w3 is not None:
        ax.plot(t, model_w3, "k", lw=1, label="identified model's friction")
    ax.set_ylabel("friction [N]")
    axes[3].plot(t, obs.u, label="actuator force (logged)")
    axes[3].set_ylabel("force [N]")
    axes[3].set_xlabel("time [s]")
    for ax in axes:
        ax.legend(loc="best")
    fig.suptitle(f"observer over measured data: {obs.config.observer.variant} variant, "
                 f"rho {obs.config.observer.rho:g}, stiffness {obs.stiffness_schedule}")
    return fig


def _model_force(ident, trace) -> tuple[np.ndarray, np.ndarray]:
    """Zero-phase filtered measured force and the identified model's force [N] per sample."""
    from scipy import signal

    from ..data.trace import zero_phase_velocity

    dt = trace.sample_time
    v = zero_phase_velocity(trace.position, dt, ident.filter_hz)
    a = np.gradient(v, dt)
    sos = signal.butter(4, ident.filter_hz, fs=1.0 / dt, output="sos")
    return signal.sosfiltfilt(sos, trace.force), ident.m * a + ident.friction(v) + ident.offset


def fit_figure(ident, trace):
    """Measured force against the identified model's force over time, and their difference.

    Parameters
    ----------
    ident : Identification
        The identification of ``trace``.
    trace : Trace
        The measured trace.

    Returns
    -------
    matplotlib.figure.Figure
    """
    measured, model = _model_force(ident, trace)
    fig, axes = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True, constrained_layout=True)
    axes[0].plot(trace.t, measured, lw=0.8, label="measured force (zero-phase filtered)")
    axes[0].plot(trace.t, model, "--", lw=0.8, label="identified model m a + sigma v + Cf sign(v) + offset")
    axes[0].set_ylabel("force [N]")
    axes[1].plot(trace.t, measured - model, lw=0.6, label="measured minus model")
    axes[1].set_ylabel("residual [N]")
    axes[1].set_xlabel("time [s]")
    for ax in axes:
        ax.legend(loc="best")
    return fig


def moving_mask(v: np.ndarray, moving_speed: float | None = None) -> tuple[np.ndarray, float]:
    """Where the axis moves, ``|v| > threshold``, and the threshold [m/s].

    Parameters
    ----------
    v : ndarray
        Velocity [m/s] per sample (the zero-phase filtered one of the record).
    moving_speed : float, optional
        The threshold [m/s] (> 0); default :data:`MOVING_FRACTION` of ``max |v|``.

    Examples
    --------
    >>> mask, threshold = moving_mask(np.array([0.0, 0.01, -0.5, 1.0]))
    >>> mask.tolist(), threshold
    ([False, False, True, True], 0.05)
    >>> moving_mask(np.zeros(3), moving_speed=-1.0)
    Traceback (most recent call last):
    ...
    ValueError: moving_speed: expected a finite number > 0 [m/s], found -1.0
    """
    from ..estimators.base import check_positive

    if moving_speed is None:
        threshold = MOVING_FRACTION * float(np.max(np.abs(v)))
    else:
        threshold = check_positive("moving_speed", moving_speed, "m/s")
    return np.abs(v) > threshold, threshold


def _rms(x: np.ndarray) -> float | None:
    return float(np.sqrt(np.mean(x ** 2))) if x.size else None


def data_section(trace, cfg=None, *, moving_speed: float | None = None, label: str | None = None) -> dict:
    """Everything the report's section "Validation on measured data" shows.

    The observer that runs over the record is ``cfg``'s, the design the report is about (its
    ``observer.dt`` set to the record's sample time where it differs: the observer runs at the rate
    the data were sampled); without ``cfg``, the identified config's. The reference friction is the
    identified model's, seen by that observer (:func:`~obsdesign.data.model_friction_state`: its
    load ``G`` and, for ``static``, its viscous term).

    The friction check is split by speed: the observer's estimate against the identified model where
    the axis moves (:func:`moving_mask`), and separately at standstill, where the model's
    ``Cf sign(v)`` of a velocity near zero flips between +-Cf and the difference measures that, not the
    observer.

    Parameters
    ----------
    trace : Trace
        The measured trace (``obsdesign report --data FILE``).
    cfg : Config, optional
        The report's config; default the identified one (``Identification.to_config()``).
    label : str, optional
        How the section names ``cfg`` (default ``the report's config`` or ``the identified config``).
    moving_speed : float, optional
        The speed [m/s] above which the axis counts as moving (default :data:`MOVING_FRACTION` of the
        record's peak zero-phase speed).

    Returns
    -------
    dict
        ``source``, ``names`` (the column names), ``samples``, ``sample_time``,
        ``parameters`` (rows ``(name, value, std, unit)``), ``nrmse_percent``,
        ``condition_number``, ``s_note``, ``rms_error`` (whole record), ``rms_error_moving`` and
        ``rms_error_standstill`` [N] (None where no sample is in that class), ``moving_speed`` [m/s],
        ``moving_fraction`` (of the samples), ``rms_residual`` [N],
        ``observer`` (the :class:`~obsdesign.data.Observation`), ``fit_svg`` and ``observe_svg``; ``units``
        (the record's :class:`~obsdesign.axis.AxisSpec`: the units above are SI of that axis);
        ``observer_label`` (whose observer ran) and ``observer_note`` (the sample time it was set to, or "").
        Strings are user text: the template escapes them.
    """
    from ..data import identify, model_friction_state, observe

    ident = identify(trace)
    identified = ident.to_config(name="identified")
    note = ""
    if cfg is None:
        cfg, label = identified, label or "the identified config"
    else:
        label = label or "the report's config"
        dt = cfg.observer.dt
        if abs(dt - trace.sample_time) > 1e-6 * trace.sample_time:
            cfg = cfg.override(dt=trace.sample_time)
            note = f"observer.dt {dt:.6g} s set to the record's sample time {trace.sample_time:.6g} s"
    obs = observe(cfg, trace)
    w3 = model_friction_state(ident, trace, cfg)
    from ..data.trace import zero_phase_velocity

    moving, threshold = moving_mask(zero_phase_velocity(trace.position, trace.sample_time, ident.filter_hz),
                                    moving_speed)
    error = obs.f_hat - w3
    measured, model = _model_force(ident, trace)
    units = identified.units  # the record's axis
    u = units.unit  # the record's axis (linear or rotary, from its units)
    params = [("m", ident.m, ident.m_std, u("kg")), ("sigma", ident.sigma, ident.sigma_std, u("N s/m")),
              ("Cf", ident.Cf, ident.Cf_std, u("N")), ("offset", ident.offset, ident.offset_std, u("N"))]
    if ident.stribeck:  # the Stribeck level and speed the config's feed-forward reads
        params += [("Fs", ident.Fs, ident.Fs_std, u("N")), ("vs", ident.vs, ident.vs_std, u("m/s"))]
    shown = {k: v for k, v in trace.metadata.items() if k not in ("time base", "encoding", "delimiter", "decimal")}
    return {"source": trace.source, "names": dict(trace.names), "samples": trace.samples, "format": trace.format,
            "units_read": trace.units.describe(trace.input_gain), "time_base": trace.metadata.get("time base"),
            "metadata": [(str(k)[:80], str(v)[:200]) for k, v in list(shown.items())[:20]],
            "sample_time": trace.sample_time, "parameters": params, "nrmse_percent": ident.nrmse_percent,
            "condition_number": ident.condition_number, "s_note": ident.s_note,
            "rms_error": _rms(error), "rms_error_moving": _rms(error[moving]),
            "rms_error_standstill": _rms(error[~moving]), "moving_speed": threshold, "moving_speed_given": moving_speed is not None,
            "moving_fraction": float(np.mean(moving)),
            "rms_residual": float(np.sqrt(np.mean((measured - model) ** 2))),
            "observer": obs, "fit_svg": inline_svg(fit_figure(ident, trace), units),
            "observe_svg": inline_svg(observation_figure(obs, w3), units), "units": units,
            "observer_label": label, "observer_note": note}
