"""The paper's reduced-order observer at a fixed stiffness, and its low-pass filter.

At a constant stiffness ``k`` the observer eq:3:1:2-3 is LTI::

    ytilde' = A(k) ytilde + b u + g(k) x,    (v_hat, f_hat) = ytilde + L x

with ``A, b, g`` from :meth:`obsdesign.design.observer.ObserverDesign.matrices`. Its
common discrete form is the kernel's own recursion
(:func:`obsdesign.design.discretize.step_matrices`): ``z = ytilde``, ``Cz = I``,
``d = L = (L1, L2)``.

``paper`` and ``paper-k0`` give the same discrete estimator at ``k = 0``; they differ only
in the closed loop, where ``paper`` runs the stiffness schedule of the kernel and
``paper-k0`` holds ``k = 0`` (a linear reduced-order observer: the ablation).

Examples
--------
>>> import obsdesign as od
>>> est = build_paper(od.load_preset("vcm"))
>>> est.nz, est.d.round(3).tolist()          # (L1, L2) feed the measurement through
(2, [936.318, -120000.0])
>>> with_lowpass(est, 2 * 3.141592653589793 * 40).nz
4
"""

from __future__ import annotations

import math

import numpy as np

from ..design.observer import design_observer
from ..params import Config
from .base import DiscreteEstimator, check_config


def step_matrices(A, b, g, h):
    """The kernel's exact 2x2 recursion, :func:`obsdesign.design.discretize.step_matrices`.

    Imported on call: ``sim`` sits downstream of ``estimators`` (its package ``__init__``
    loads the simulator, which will load the estimators), so a module-level import would
    close an import circle.
    """
    from ..design.discretize import step_matrices as exact

    return exact(A, b, g, h)

__all__ = ["build_paper", "build_paper_k0", "with_lowpass", "lowpass_recursion", "model_sigma", "paper_dominant_pole"]


def model_sigma(cfg: Config, sigma_model: float | None) -> float:
    """Viscous coefficient [N s/m] of the linear model: ``sigma`` for ``static``, 0 for ``lag``.

    Parameters
    ----------
    cfg : Config
        The design.
    sigma_model : float, optional
        An explicit value (returned when given).

    ``sigma_model`` overrides it (a finite number >= 0).
    """
    if sigma_model is None:
        return float(cfg.friction.sigma) if cfg.observer.variant == "static" else 0.0
    if isinstance(sigma_model, bool) or not isinstance(sigma_model, (int, float)) or not (
        math.isfinite(sigma_model) and sigma_model >= 0.0
    ):
        raise ValueError(f"sigma_model: expected a finite number >= 0 [N s/m] (or None), found {sigma_model!r}")
    return float(sigma_model)


def paper_dominant_pole(cfg: Config) -> float:
    """Largest real part [1/s] of the paper observer's poles at ``k = 0`` (gross sliding).

    Parameters
    ----------
    cfg : Config
        The design.

    For both variants this is ``-sqrt(kappa/m) (rho - 1)``.

    >>> import obsdesign as od
    >>> round(paper_dominant_pole(od.load_preset("table1")), 4)
    -2.4388
    """
    d = design_observer(check_config(cfg))
    return float(np.max(d.eigenvalues(0.0).real))


def build_paper(cfg: Config, *, stiffness: float = 0.0, sigma_model: float | None = None,
                name: str = "paper", schedule: str = "estimated") -> DiscreteEstimator:
    """The paper's observer frozen at ``stiffness`` k [N/m], in the common discrete form.

    Parameters
    ----------
    cfg : Config
        Gains from ``design_observer(cfg)`` (rho, kappa, variant) and ``cfg.observer.dt``.
    stiffness : float
        The constant pre-sliding stiffness [N/m], ``>= 0`` (default 0: gross sliding).
    sigma_model : float, optional
        Must match the variant (``sigma`` for ``static``, 0 for ``lag``): the paper's
        observer has its model built in.
    name : str
        Registry name recorded in the result.
    schedule : str
        The kernel's stiffness schedule this entry runs with.

    Raises
    ------
    ValueError
        Negative stiffness, or a ``sigma_model`` the variant does not use.
    """
    cfg = check_config(cfg)
    if isinstance(stiffness, bool) or not isinstance(stiffness, (int, float)) or not (
        math.isfinite(stiffness) and stiffness >= 0.0
    ):
        raise ValueError(f"stiffness: expected a finite number >= 0 [N/m], found {stiffness!r}")
    own = model_sigma(cfg, None)
    if sigma_model is not None and model_sigma(cfg, sigma_model) != own:
        raise ValueError(f"sigma_model: the paper's {cfg.observer.variant!r} observer has sigma_model = {own!r} "
                         f"built in; expected None or {own!r}, found {sigma_model!r}")
    design = design_observer(cfg)
    A, b, g = design.matrices(float(stiffness))
    Phi, gu, g0, g1 = step_matrices(A, b, g, cfg.observer.dt)
    L = np.array([design.L1, design.L2])
    eig = design.eigenvalues(float(stiffness))
    return DiscreteEstimator(
        name=name, dt=cfg.observer.dt, Phi=Phi, gu=gu, g0=g0, g1=g1, Cz=np.eye(2), d=L,
        params={"variant": design.variant, "rho": design.rho, "kappa": design.kappa, "L1": design.L1,
                "L2": design.L2, "stiffness": float(stiffness), "schedule": schedule, "sigma_model": own,
                "m": design.m, "slowest_pole": float(np.max(eig.real)), "fastest_pole": float(np.min(eig.real))},
        tuning="reference",
        init=np.column_stack([-L, np.eye(2)]),
    )


def build_paper_k0(cfg: Config, *, sigma_model: float | None = None) -> DiscreteEstimator:
    """The paper's gains with the stiffness schedule off (``k = 0`` always): the ablation.

    Parameters
    ----------
    cfg : Config
        The design.
    sigma_model : float, optional
        Viscous coefficient of the model (default from the variant).
    """
    return build_paper(cfg, stiffness=0.0, sigma_model=sigma_model, name="paper-k0", schedule="off")


def lowpass_recursion(omega_co: float, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """FOH recursion ``(Phi, g0, g1)`` of eq:3:4:5 with state ``(f_filtered, its derivative)``.

    Parameters
    ----------
    omega_co : float
        Cutoff of eq:3:4:5 [rad/s].
    dt : float
        Sample time [s].

    The same recursion as the simulator's filter: exact for an input linear between samples.
    """
    w = float(omega_co)
    A = np.array([[0.0, 1.0], [-w * w, -2.0 * w]])
    Phi, _, g0, g1 = step_matrices(A, np.zeros(2), np.array([0.0, w * w]), dt)
    return Phi, g0, g1


def with_lowpass(est: DiscreteEstimator, omega_co: float) -> DiscreteEstimator:
    """``est`` with its friction estimate passed through ``F(s) = omega_co^2/(s + omega_co)^2``.

    Parameters
    ----------
    est : DiscreteEstimator
        The estimator.
    omega_co : float
        Cutoff of eq:3:4:5 [rad/s].

    The filter's FOH recursion is fed by ``f_hat[n-1]`` and ``f_hat[n]``; substituting
    ``f_hat[n] = Cz_f z[n] + d_f y[n]`` and the estimator's own recursion gives one
    recursion of the common form with ``nz + 2`` states (``v_hat`` stays unfiltered).
    """
    if est.nz + 2 > 4:
        raise ValueError(f"est: with_lowpass needs nz <= 2, found nz = {est.nz}")
    P, a0, a1 = lowpass_recursion(omega_co, est.dt)
    n = est.nz
    cf, df = est.Cz[1], est.d[1]
    Phi = np.zeros((n + 2, n + 2))
    Phi[:n, :n] = est.Phi
    Phi[n:, :n] = np.outer(a1, cf @ est.Phi) + np.outer(a0, cf)
    Phi[n:, n:] = P
    gu = np.concatenate([est.gu, a1 * (cf @ est.gu)])
    g0 = np.concatenate([est.g0, a0 * df + a1 * (cf @ est.g0)])
    g1 = np.concatenate([est.g1, a1 * (cf @ est.g1 + df)])
    Cz = np.zeros((2, n + 2))
    Cz[0, :n] = est.Cz[0]
    Cz[1, n] = 1.0
    init = np.vstack([est.init, [[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]])
    return DiscreteEstimator(
        name=f"{est.name}+lowpass", dt=est.dt, Phi=Phi, gu=gu, g0=g0, g1=g1, Cz=Cz,
        d=np.array([est.d[0], 0.0]), params={**est.params, "omega_co": float(omega_co)},
        tuning=est.tuning, init=init,
    )
