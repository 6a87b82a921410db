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

from .figures import figure_svg, plt

__all__ = ["observation_figure", "fit_figure", "data_section"]


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


def _svg(fig) -> str:
    import re

    text = figure_svg(fig)
    return re.sub(r"<metadata>.*?</metadata>", "", text[text.index("<svg"):], flags=re.S)


def data_section(trace) -> dict:
    """Everything the report's section "Validation on measured data" shows.

    Parameters
    ----------
    trace : Trace
        The measured trace (``obsdesign report --data FILE``).

    Returns
    -------
    dict
        ``source``, ``names`` (the column names), ``samples``, ``sample_time``,
        ``parameters`` (rows ``(name, value, std, unit)``), ``nrmse_percent``,
        ``condition_number``, ``s_note``, ``rms_error`` and ``rms_residual`` [N],
        ``observer`` (the :class:`~obsdesign.data.Observation`), ``fit_svg`` and ``observe_svg``.
        Strings are user text: the template escapes them.
    """
    from ..data import identify, model_friction_state, observe

    ident = identify(trace)
    cfg = ident.to_config(name="identified")
    obs = observe(cfg, trace)
    w3 = model_friction_state(ident, trace, cfg)
    measured, model = _model_force(ident, trace)
    params = [("m", ident.m, ident.m_std, "kg"), ("sigma", ident.sigma, ident.sigma_std, "N s/m"),
              ("Cf", ident.Cf, ident.Cf_std, "N"), ("offset", ident.offset, ident.offset_std, "N")]
    return {"source": trace.source, "names": dict(trace.names), "samples": trace.samples,
            "sample_time": trace.sample_time, "parameters": params, "nrmse_percent": ident.nrmse_percent,
            "condition_number": ident.condition_number, "s_note": ident.s_note,
            "rms_error": float(np.sqrt(np.mean((obs.f_hat - w3) ** 2))),
            "rms_residual": float(np.sqrt(np.mean((measured - model) ** 2))),
            "observer": obs, "fit_svg": _svg(fit_figure(ident, trace)),
            "observe_svg": _svg(observation_figure(obs, w3))}
