"""Figures of the paper reproductions of :mod:`obsdesign.studies` (matplotlib, Agg backend)."""

from __future__ import annotations

import numpy as np

from ..studies import ConvergenceStudy, ExperimentsStudy, FrictionLoopsStudy
from .figures import plt

__all__ = ["convergence_figure", "experiments_figure", "friction_loops_figure"]


def convergence_figure(study: ConvergenceStudy):
    """Fig. simconv: input, displacement, friction estimates for rho 0.98/1.02, steady-sliding rates.

    Parameters
    ----------
    study : ConvergenceStudy
        From :func:`obsdesign.studies.convergence_study`.
    """
    fig, axes = plt.subplots(4, 1, figsize=(8, 10), constrained_layout=True)
    r98, r102 = study.runs[("excitation", 0.98)], study.runs[("excitation", 1.02)]
    axes[0].plot(r102.t, r102.u)
    axes[0].set_ylabel("u [N]")
    axes[0].set_title("(a) band-limited random input")
    axes[1].plot(r102.t, r102.x_meas * 1e3, lw=0.5)
    axes[1].set_ylabel("x_meas [mm]")
    axes[1].set_title("(b) noisy displacement")
    axes[2].plot(r102.t, r102.f, "k", lw=1, label="w3 (model plant)")
    axes[2].plot(r98.t, r98.f_hat_filtered, lw=0.8, label="estimate, rho = 0.98")
    axes[2].plot(r102.t, r102.f_hat_filtered, lw=0.8, label="estimate, rho = 1.02")
    axes[2].set_ylabel("friction state [N]")
    axes[2].legend(loc="best")
    axes[2].set_title("(c) friction state and its estimates")
    for rho in (0.98, 1.02):
        res = study.runs[("steady", rho)]
        meas, exp = study.rates[rho]
        axes[3].semilogy(res.t, np.abs(res.f_hat - res.f), label=f"rho = {rho}: {meas:+.3f} 1/s (eq:3:3:2: {exp:+.3f})")
    axes[3].set_xlabel("time [s]")
    axes[3].set_ylabel("|f_hat - f| [N]")
    axes[3].legend(loc="best")
    axes[3].set_title("(d) steady sliding: error growth/decay rate")
    return fig


def experiments_figure(study: ExperimentsStudy):
    """Fig. experror: positioning and tracking errors, PID vs PID + observer.

    Parameters
    ----------
    study : ExperimentsStudy
        From :func:`obsdesign.studies.experiments_study`.
    """
    fig, axes = plt.subplots(2, 1, figsize=(8, 7), constrained_layout=True)
    for ax, scenario in zip(axes, ("positioning", "tracking")):
        for ctrl in ("pid", "pid+observer"):
            r = study.runs[(scenario, ctrl)]
            ax.plot(r.t, r.e * 1e6, lw=0.8, label=ctrl)
        ax.set_ylabel("error [um]")
        ax.set_title(f"({'a' if scenario == 'positioning' else 'b'}) {scenario}")
        ax.legend(loc="best")
    axes[0].set_ylim(-50, 50)
    axes[1].set_xlabel("time [s]")
    return fig


def friction_loops_figure(study: FrictionLoopsStudy):
    """Fig. frictionloops: the friction estimate against the displacement, with the model's.

    Parameters
    ----------
    study : FrictionLoopsStudy
        From :func:`obsdesign.studies.friction_loops_study`.
    """
    fig, ax = plt.subplots(figsize=(7, 5), constrained_layout=True)
    ax.plot(study.x * 1e3, study.model_f, lw=0.8, label="model f = Fc + sigma v (from filtered v_hat)")
    ax.plot(study.x * 1e3, study.model_fc, lw=1.2, label="model Fc")
    ax.plot(study.x * 1e3, study.estimate, lw=1.2, label="estimate w3 (filtered)")
    ax.set_xlabel("measured displacement [mm]")
    ax.set_ylabel("friction [N]")
    ax.set_ylim(-1.0, 1.0)
    ax.legend(loc="best")
    return fig
