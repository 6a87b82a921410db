"""Figures of the paper reproductions of :mod:`obsdesign.studies` (matplotlib, Agg backend)."""

from __future__ import annotations

import numpy as np

from ..studies import ConvergenceStudy, ExperimentsStudy, FrictionLoopsStudy
from .figures import envelope, plt

__all__ = ["convergence_figure", "experiments_figure", "friction_loops_figure"]


def convergence_figure(study: ConvergenceStudy):
    """Fig. simconv: input, displacement, friction estimates for rho 0.98/1.02, steady-sliding rates.

    Parameters
    ----------
    study : ConvergenceStudy
        From :func:`obsdesign.studies.convergence_study`.
    """
    fig, axes = plt.subplots(4, 1, figsize=(8, 10.5), constrained_layout=True)
    r98, r102 = study.runs[("excitation", 0.98)], study.runs[("excitation", 1.02)]
    axes[0].plot(*envelope(r102.t, r102.u), lw=0.6)
    axes[0].set_ylabel("input force u [N]")
    axes[0].set_title("(a) band-limited random input force")
    axes[1].plot(*envelope(r102.t, r102.x_meas * 1e3), lw=0.5)
    axes[1].set_ylabel("measured x [mm]")
    axes[1].set_title("(b) measured displacement (with sensor noise)")
    axes[2].plot(*envelope(r102.t, r102.f), "k", lw=1, label="true friction state of the plant")
    axes[2].plot(*envelope(r98.t, r98.f_hat_filtered), lw=0.8, label="estimate with rho = 0.98 (violates Proposition 2)")
    axes[2].plot(*envelope(r102.t, r102.f_hat_filtered), lw=0.8, label="estimate with rho = 1.02")
    axes[2].set_ylabel("friction [N]")
    axes[2].legend(loc="best", fontsize="small")
    axes[2].set_title("(c) friction and its filtered estimates")
    for ax in axes[:3]:
        ax.set_xlabel("time [s]")
        ax.set_xlim(r102.t[0], r102.t[-1])
    for rho in (0.98, 1.02):
        res = study.runs[("steady", rho)]
        meas, exp = study.rates[rho]
        axes[3].semilogy(res.t, np.abs(res.f_hat - res.f),
                         label=f"rho = {rho}: rate {meas:+.3f} 1/s (predicted {exp:+.3f} 1/s)")
    axes[3].set_xlabel("time [s] (a separate 5 s run at constant force)")
    axes[3].set_ylabel("estimation error [N]")
    axes[3].legend(loc="best", fontsize="small")
    axes[3].set_title("(d) steady sliding: the error grows or decays at the dominant pole")
    return fig


def experiments_figure(study: ExperimentsStudy):
    """Fig. experror: positioning error (full scale and a marked zoom) and the tracking error per chirp band.

    Parameters
    ----------
    study : ExperimentsStudy
        From :func:`obsdesign.studies.experiments_study`.
    """
    from ..loop.scenarios import CHIRP_BAND_LABELS

    fig = plt.figure(figsize=(9, 10), constrained_layout=True)
    grid = fig.add_gridspec(3, len(CHIRP_BAND_LABELS))
    full = fig.add_subplot(grid[0, :])
    zoom = fig.add_subplot(grid[1, :], sharex=full)
    # choice subset: labels of the study's two controllers
    names = {"pid": "PID alone", "pid+observer": "PID + friction observer"}
    for ctrl in study.positioning:
        r = study.runs[("positioning", ctrl)]
        te, ee = envelope(r.t, r.e * 1e6)  # both panels span the whole run (the zoom is in y only)
        full.plot(te, ee, lw=0.8, label=names[ctrl])
        zoom.plot(te, ee, lw=0.8, label=names[ctrl])
    full.set_title("(a) positioning error, 1 mm steps up and down (full scale: the overshoot shows)")
    zoom.set_ylim(-50, 50)
    zoom.set_title("(b) the same, zoomed to \u00b150 um (traces leave this range)")
    for ax in (full, zoom):
        ax.set_xlabel("time [s]")
        ax.set_ylabel("error x_ref - x [um]")
        ax.legend(loc="best", fontsize="small")
    for i, (label, lo, hi) in enumerate(CHIRP_BAND_LABELS):
        ax = fig.add_subplot(grid[2, i])
        for ctrl in study.tracking:
            r = study.runs[("tracking", ctrl)]
            i0, i1 = _band_slice(r, lo, hi)
            t_band, e_band = r.t[i0:i1], r.e[i0:i1] * 1e6
            if hi > 1.0:  # dozens of periods: draw the envelope (peak |error| per 0.5 s) so it stays readable
                n = max(1, int(round(0.5 / (r.t[1] - r.t[0]))))
                m = len(e_band) // n
                t_band = t_band[: m * n].reshape(m, n).mean(axis=1)
                e_band = np.abs(e_band[: m * n]).reshape(m, n).max(axis=1)
            ax.plot(t_band, e_band, lw=0.8, label=names[ctrl])
        title = f"({chr(ord('c') + i)}) chirp {label}" + ("\npeak |error| per 0.5 s" if hi > 1.0 else "")
        ax.set_title(title, fontsize="small")
        ax.set_xlabel("time [s]")
        if i == 0:
            ax.set_ylabel("tracking error [um]")
            ax.legend(loc="best", fontsize="x-small")
    return fig


def _band_slice(res, lo: float, hi: float) -> tuple[int, int]:
    """Samples of a tracking run whose chirp frequency lies in [lo, hi) Hz (default chirp of the scenario)."""
    from ..loop.scenarios import chirp_frequency

    dt = res.t[1] - res.t[0]
    freq = chirp_frequency(res.t, len(res.t) * dt)
    i0, i1 = np.searchsorted(freq, (lo, hi))
    return int(i0), int(i1)


def friction_loops_figure(study: FrictionLoopsStudy):
    """Fig. frictionloops: the friction estimate against the displacement, with the model's.

    Parameters
    ----------
    study : FrictionLoopsStudy
        From :func:`obsdesign.studies.friction_loops_study`.
    """
    fig, ax = plt.subplots(figsize=(7, 5), constrained_layout=True)
    ax.plot(study.x * 1e3, study.model_f, lw=0.8, label="friction model: Coulomb + viscous (estimated velocity)")
    ax.plot(study.x * 1e3, study.model_fc, lw=1.2, label="friction model: Coulomb part only")
    ax.plot(study.x * 1e3, study.estimate, lw=1.2, label="observer's friction estimate (low-pass filtered)")
    ax.set_xlabel("measured displacement [mm]")
    ax.set_ylabel("friction [N]")
    ax.set_ylim(-1.0, 1.0)
    ax.legend(loc="best")
    return fig
