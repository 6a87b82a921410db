"""Rules that turn an :class:`~obsdesign.data.Identification` into a complete design config.

The data give the plant (``m``, ``sigma``, ``Cf``, ``offset``), the sample time and the
sensor; everything else follows from documented rules tied to the sample time ``dt``:

=================  ==========================================================================
field              rule
=================  ==========================================================================
plant.K            the trace's input gain (|gain|; 1.0 when the input was logged in N)
plant.G            the identified offset (a constant load force)
plant.u_max        1.2 x the largest logged |input| (= max |force| / K); 10 V if no force
friction.s         identified; else ``1 / presliding_window`` (1e4 1/m at the default 0.1 mm)
friction.kappa     fastest observer pole ``(rho + 1) sqrt(kappa/m) = 0.2 / dt``
observer           variant ``static``, ``rho`` = 4, ``dt`` of the trace,
                   ``omega_co = 2 pi f_s / 10`` (a fifth of the Nyquist frequency)
sensor             ``noise_rms`` and ``quantization`` estimated from the trace,
                   white noise up to the Nyquist frequency
pid                ``tau = m / sigma`` (so ``H = phi / (s (tau s + 1))`` with ``phi = K tau / m`` is
                   ``K / (m s^2 + sigma s)``), phase margin 60 deg, ``max_S`` placing the
                   crossover ``omega_c = k phi / sin(Phi)`` at a tenth of the Nyquist frequency
=================  ==========================================================================
"""

from __future__ import annotations

import math

from ..params import Config, FrictionParams, ObserverSpec, PIDSpec, PlantParams, SensorSpec

__all__ = ["config_from", "PHASE_MARGIN_DEG", "FASTEST_POLE_DT", "U_MAX_MARGIN"]

#: Phase margin [deg] of the PID rule.
PHASE_MARGIN_DEG = 60.0
#: Fastest observer pole times dt.
FASTEST_POLE_DT = 0.2
#: Margin on the largest logged input for the actuator limit.
U_MAX_MARGIN = 1.2


def _positive(name: str, value: float, why: str) -> float:
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name}: expected an identified value > 0 for a design, found {value!r} ({why})")
    return value


def config_from(ident, *, name: str = "identified", K: float | None = None, u_max: float | None = None,
                rho: float = 4.0, presliding_window: float = 1e-4) -> Config:
    """A complete :class:`~obsdesign.Config` from an identification (rules in the module docstring).

    Parameters
    ----------
    ident : Identification
    name : str
        Name of the design.
    K : float, optional
        Actuator gain [N/V]; default the trace's ``|input_gain|``.
    u_max : float, optional
        Actuator limit [V]; default 1.2 max|force| / K, or 10 V for an all-zero force.
    rho : float
        Observer gain parameter (> 1). With 4, the gross-sliding poles are
        ``-(rho -+ 1) sqrt(kappa/m)``: the dominant one is 3/5 of the fastest (0.12/dt).
    presliding_window : float
        Pre-sliding distance ``1/s`` [m] assumed when ``s`` was not identified.

    Returns
    -------
    Config

    Raises
    ------
    ValueError
        If ``m``, ``sigma`` or ``Cf`` was identified non-positive (no physical design).

    Examples
    --------
    >>> from obsdesign.data import Identification
    >>> ident = Identification(model="coulomb-viscous", m=2.0, sigma=20.0, Cf=1.0, offset=3.0, m_std=0.0,
    ...                        sigma_std=0.0, Cf_std=0.0, offset_std=0.0, nrmse_percent=1.0,
    ...                        condition_number=2.0, samples=1000, sample_time=1e-3, force_peak=5.0)
    >>> cfg = config_from(ident)
    >>> cfg.plant.u_max, cfg.friction.kappa, cfg.friction.s, cfg.pid.tau
    (6.0, 3200.0, 10000.0, 0.1)
    """
    dt = ident.sample_time
    m = _positive("m", ident.m, "the mass must be positive")
    sigma = _positive("sigma", ident.sigma, "the viscous coefficient must be positive")
    Cf = _positive("Cf", ident.Cf, "the Coulomb level must be positive")
    gain = abs(ident.input_gain) if K is None else K
    if u_max is None:
        u_max = U_MAX_MARGIN * ident.force_peak / gain if ident.force_peak > 0 else 10.0
    if isinstance(rho, bool) or not isinstance(rho, (int, float)) or not rho > 1:
        raise ValueError(f"rho: expected a finite number > 1 (stable observer), found {rho!r}")
    s = ident.s if ident.s is not None else 1.0 / presliding_window
    kappa = m * (FASTEST_POLE_DT / (dt * (rho + 1.0))) ** 2
    nyquist = 0.5 / dt
    omega_c = 2.0 * math.pi * nyquist / 10.0
    tau = m / sigma
    phi = gain * tau / m
    max_S = phi / (omega_c * math.sin(math.radians(PHASE_MARGIN_DEG)))
    return Config(
        name=name,
        plant=PlantParams(m=m, K=gain, G=ident.offset, u_max=u_max),
        friction=FrictionParams(Cf=Cf, sigma=sigma, s=s, kappa=kappa),
        sensor=SensorSpec(noise_rms=ident.noise_rms, noise_bandwidth=nyquist, quantization=ident.quantization),
        observer=ObserverSpec(rho=float(rho), omega_co=2.0 * math.pi * nyquist / 5.0, variant="static", dt=dt),
        pid=PIDSpec(max_S=max_S, phase_margin_deg=PHASE_MARGIN_DEG, tau=tau),
    )
