"""Numerical rules of the simulator: how many Heun substeps the plant needs.

The observer and the low-pass filter are discretized exactly (their step is
stable for any ``dt``), but the plant is integrated with an explicit method:
``n_sub`` steps of Heun's method (explicit trapezoidal rule) per sample, step
``h = dt / n_sub``. An explicit step is only stable when ``h`` is small against
the plant's fastest time constant. The rates [1/s] of the plant are

===============================  ===========================================================
rate                             origin
===============================  ===========================================================
``sigma / m``                    viscous damping of the mass
``1 / beta``                     first-order lag of the viscous friction (``beta`` set)
``sqrt(sigma / (m beta))``       the mass against the lagged viscous force (``beta`` set)
``sqrt(kappa / m)``              the mass on the pre-sliding spring (stiffness up to ``kappa``)
``sqrt((kappa+sigma/beta)/m)``   the ``model`` plant of variant ``lag`` (A(3,2) = k + sigma/beta)
===============================  ===========================================================

and the rule is ``h * max(rates) <= MAX_STEP_RATE`` (0.2). Heun's method is
stable on the negative real axis up to ``h lambda = -2``; on an undamped
oscillation of frequency ``w`` it gains ``sqrt(1 + (h w)^4 / 4)`` per step,
at ``h w = 0.2`` about 0.6 % per period, which the plant's viscous damping
absorbs. :func:`substeps_for` takes the requested substeps (default 10) when
they satisfy the rule, otherwise the smallest number that does, up to
:data:`MAX_SUBSTEPS`; beyond that it refuses, naming the parameters.

Further plant friction models add their own rates to :func:`plant_rates`.

Examples
--------
>>> import obsdesign as od
>>> cfg = od.load_preset("vcm")
>>> substeps_for(cfg, cfg.observer.dt, 10)     # the presets keep 10
10
>>> substeps_for(cfg.override(dt=0.01), 0.01, 10)   # sqrt(kappa/m) = 121.9 1/s: 0.01 * 121.9 / 0.2 -> 7
10
>>> substeps_for(cfg.override(dt=0.5), 0.5, 10)     # 0.5 * 121.9 / 0.2 = 304.8 -> 305
305
>>> substeps_for(cfg.override(m=1e-6), 1e-4, 10)
Traceback (most recent call last):
...
ValueError: substeps: the plant's fastest rate sigma/m = 2.11e+07 1/s (plant.m = 1e-06, friction.sigma = 21.1) needs h = dt/substeps <= 9.479e-09 s, more than 1000 substeps per sample of dt = 0.0001 s; use a smaller observer.dt or a slower plant
"""

from __future__ import annotations

import math

from .._validate import check_integer
from ..params import Config

__all__ = ["MAX_SUBSTEPS", "MAX_STEP_RATE", "plant_rates", "fastest_rate", "substeps_for", "step_is_stable",
           "saturation_warning"]

#: Largest number of Heun substeps per sample chosen or accepted.
MAX_SUBSTEPS = 1000
#: Largest ``h * rate`` of the explicit plant step (see the module docstring).
MAX_STEP_RATE = 0.2


def plant_rates(*, m: float, sigma: float, kappa: float, beta: float | None = None,
                model_lag: bool = False) -> dict[str, float]:
    """The plant's rates [1/s] by name (the table of the module docstring).

    Parameters
    ----------
    m : float
        Mass [kg].
    sigma : float
        Viscous friction coefficient [N s/m].
    kappa : float
        Bound of the pre-sliding stiffness [N/m].
    beta : float, optional
        Lag of the viscous friction [s] (``None`` or 0: no lag).
    model_lag : bool
        The plant is the 3-state ``model`` of variant ``lag``.

    Returns
    -------
    dict
        ``{'sigma/m': ..., 'sqrt(kappa/m)': ..., ...}``.

    Examples
    --------
    >>> r = plant_rates(m=0.5, sigma=20.0, kappa=8000.0, beta=1e-3)
    >>> {k: round(v, 3) for k, v in r.items()}
    {'sigma/m': 40.0, 'sqrt(kappa/m)': 126.491, '1/beta': 1000.0, 'sqrt(sigma/(m beta))': 200.0}
    """
    rates = {"sigma/m": sigma / m, "sqrt(kappa/m)": math.sqrt(kappa / m)}
    if beta:
        rates["1/beta"] = 1.0 / beta
        rates["sqrt(sigma/(m beta))"] = math.sqrt(sigma / (m * beta))
        if model_lag:
            rates["sqrt((kappa + sigma/beta)/m)"] = math.sqrt((kappa + sigma / beta) / m)
    return rates


def fastest_rate(cfg: Config, *, plant: str = "physical") -> tuple[str, float]:
    """The name and value [1/s] of the plant's fastest rate.

    Parameters
    ----------
    cfg : Config
        The design (plant and friction parameters).
    plant : str
        The simulated plant structure, a name of :data:`obsdesign.sampled.choices.PLANTS`.

    Examples
    --------
    >>> import obsdesign as od
    >>> name, rate = fastest_rate(od.load_preset("table1"))
    >>> name, round(rate, 3)
    ('1/beta', 1000.0)
    """
    fr = cfg.friction
    rates = plant_rates(m=cfg.plant.m, sigma=fr.sigma, kappa=fr.kappa, beta=fr.beta,
                        model_lag=plant == "model" and cfg.observer.variant == "lag")
    name = max(rates, key=rates.get)
    return name, rates[name]


_SYMBOLS = {"m": "plant.m", "sigma": "friction.sigma", "kappa": "friction.kappa", "beta": "friction.beta"}


def _named_parameters(cfg: Config, rate_name: str) -> str:
    values = {"m": cfg.plant.m, "sigma": cfg.friction.sigma, "kappa": cfg.friction.kappa, "beta": cfg.friction.beta}
    used = [s for s in ("m", "sigma", "kappa", "beta") if s in rate_name.replace("(", " ").replace("/", " ")
            .replace(")", " ").replace("+", " ").split()]
    return ", ".join(f"{_SYMBOLS[s]} = {values[s]:g}" for s in used)


def substeps_for(cfg: Config, dt: float, requested: int = 10, *, plant: str = "physical") -> int:
    """Heun substeps per sample: ``requested`` if the step is stable, else the fewest that are.

    Parameters
    ----------
    cfg : Config
        The design (plant and friction parameters).
    dt : float
        Sample time [s].
    requested : int
        Substeps asked for (1 to :data:`MAX_SUBSTEPS`).
    plant : str
        The simulated plant structure, a name of :data:`obsdesign.sampled.choices.PLANTS`.

    Returns
    -------
    int
        ``max(requested, ceil(dt * fastest rate / MAX_STEP_RATE))``.

    Raises
    ------
    ValueError
        When more than :data:`MAX_SUBSTEPS` substeps are needed (naming the rate and its parameters).
    """
    requested = check_integer("substeps", requested, minimum=1, maximum=MAX_SUBSTEPS)
    name, rate = fastest_rate(cfg, plant=plant)
    needed = max(1, math.ceil(dt * rate / MAX_STEP_RATE * (1.0 - 1e-12)))
    if needed > MAX_SUBSTEPS:
        raise ValueError(
            f"substeps: the plant's fastest rate {name} = {rate:.3g} 1/s ({_named_parameters(cfg, name)}) needs "
            f"h = dt/substeps <= {MAX_STEP_RATE / rate:.4g} s, more than {MAX_SUBSTEPS} substeps per sample of "
            f"dt = {dt:g} s; use a smaller observer.dt or a slower plant")
    return max(requested, needed)


def step_is_stable(*, dt: float, n_sub: int, m: float, sigma: float, kappa: float, beta: float | None,
                   model_lag: bool = False) -> bool:
    """Whether ``h = dt / n_sub`` satisfies the rule (used to label a divergence numerical).

    Parameters
    ----------
    dt : float
        Sample time [s].
    n_sub : int
        Substeps per sample.
    m, sigma, kappa, beta : float
        Plant parameters as in :func:`plant_rates`.
    model_lag : bool
        The plant is the 3-state ``model`` of variant ``lag``.

    Examples
    --------
    >>> step_is_stable(dt=1e-4, n_sub=10, m=0.538, sigma=21.1, kappa=8000.0, beta=None)
    True
    >>> step_is_stable(dt=1e-4, n_sub=10, m=1e-6, sigma=21.1, kappa=8000.0, beta=None)
    False
    """
    rate = max(plant_rates(m=m, sigma=sigma, kappa=kappa, beta=beta, model_lag=model_lag).values())
    return dt / n_sub * rate <= MAX_STEP_RATE * (1.0 + 1e-9)


def saturation_warning(loop) -> str | None:
    """A warning when an open-loop force exceeds what the saturated actuator can apply (else None).

    The kernel applies ``u = K clip((u_open + G)/K, -u_max, u_max) - G``, so the net force lies
    in ``[-K u_max - G, K u_max - G]``; a larger requested force is clipped.

    Parameters
    ----------
    loop : LoopInputs
        The inputs of a run (:func:`obsdesign.loop.prepare`).

    Examples
    --------
    >>> import obsdesign as od
    >>> from obsdesign.loop import prepare
    >>> from obsdesign.loop.scenarios import ConstantForce
    >>> cfg = od.load_preset("vcm")
    >>> saturation_warning(prepare(cfg, "constant", duration=0.01)) is None
    True
    >>> print(saturation_warning(prepare(cfg, ConstantForce(force=1e30), duration=0.01)))
    the open-loop force reaches 1e+30 N, beyond the saturated actuator's range [-38.07, 27.53] N (K = 3.28 N/V, u_max = 10 V, G = 5.27 N): it is clipped
    """
    if loop.controller != "open-loop" or len(loop.u_open) == 0:
        return None
    import numpy as np

    pl = loop.config.plant
    low, high = -pl.K * pl.u_max - pl.G, pl.K * pl.u_max - pl.G
    peak_hi, peak_lo = float(np.max(loop.u_open)), float(np.min(loop.u_open))
    if peak_hi <= high * (1 + 1e-12) and peak_lo >= low * (1 + 1e-12):
        return None
    peak = peak_hi if peak_hi - high >= low - peak_lo else peak_lo
    return (f"the open-loop force reaches {peak:.4g} N, beyond the saturated actuator's range [{low:.4g}, {high:.4g}] N "
            f"(K = {pl.K:g} N/V, u_max = {pl.u_max:g} V, G = {pl.G:g} N): it is clipped")
