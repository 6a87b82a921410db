"""The registry of estimators: integer codes, knobs, builders and tuners.

Examples
--------
>>> import obsdesign as od
>>> [(name, info.code, info.knob) for name, info in ESTIMATORS.items()]
[('paper', 0, 'stiffness'), ('paper-k0', 1, None), ('eso', 2, 'omega_o'), ('kalman', 3, 'q'), ('dob', 4, 'omega_q')]
>>> build("eso", od.load_preset("vcm"), omega_o=100.0).params["omega_o"]
100.0
>>> build("eso", od.load_preset("vcm"))
Traceback (most recent call last):
...
ValueError: omega_o: 'eso' needs it, expected a finite number > 0 [rad/s], found None
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import Callable

from ..params import Config
from .base import DiscreteEstimator
from .dob import build_dob
from .eso import build_eso
from .kalman import build_kalman
from .paper import build_paper, build_paper_k0
from .tuning import tune

__all__ = ["EstimatorInfo", "ESTIMATORS", "build", "estimator_names"]


@dataclass(frozen=True, kw_only=True)
class EstimatorInfo:
    """One entry of :data:`ESTIMATORS`.

    Attributes
    ----------
    code : int
        Integer code for numba kernels.
    doc : str
        One line.
    knob, knob_unit : str or None
        The design parameter :func:`build` takes (None: none) and its unit.
    lowpass : bool
        Whether the closed loop passes ``f_hat`` through eq:3:4:5 before compensating
        (the paper entries); the baselines' bandwidth is their own knob.
    build : callable
        ``build(cfg, *, <knob>=..., sigma_model=None) -> DiscreteEstimator``.
    tune : callable
        ``tune(cfg, *, rule="noise", sigma_model=None) -> DiscreteEstimator`` (the fair rule).
    """

    code: int
    doc: str
    knob: str | None
    knob_unit: str | None
    lowpass: bool
    build: Callable[..., DiscreteEstimator]
    tune: Callable[..., DiscreteEstimator]


ESTIMATORS: dict[str, EstimatorInfo] = {
    "paper": EstimatorInfo(code=0, doc="the paper's reduced-order observer (fixed-k form; the kernel schedules k)",
                           knob="stiffness", knob_unit="N/m", lowpass=True, build=build_paper, tune=partial(tune, "paper")),
    "paper-k0": EstimatorInfo(code=1, doc="the paper's gains with the stiffness schedule off (k = 0): ablation",
                              knob=None, knob_unit=None, lowpass=True, build=build_paper_k0, tune=partial(tune, "paper-k0")),
    "eso": EstimatorInfo(code=2, doc="linear extended state observer, all three poles at -omega_o (Gao 2003)",
                         knob="omega_o", knob_unit="rad/s", lowpass=False, build=build_eso, tune=partial(tune, "eso")),
    "kalman": EstimatorInfo(code=3, doc="steady-state Kalman filter (current estimator), friction random walk",
                            knob="q", knob_unit="N^2/s", lowpass=False, build=build_kalman, tune=partial(tune, "kalman")),
    "dob": EstimatorInfo(code=4, doc="disturbance observer, Q(s) = omega_q^2/(s + omega_q)^2, v_hat = s Q y",
                         knob="omega_q", knob_unit="rad/s", lowpass=False, build=build_dob, tune=partial(tune, "dob")),
}


def estimator_names() -> tuple[str, ...]:
    """Names of the registry, in code order."""
    return tuple(ESTIMATORS)


def _info(name) -> EstimatorInfo:
    if not isinstance(name, str) or name not in ESTIMATORS:
        raise ValueError(f"name: expected one of {', '.join(ESTIMATORS)}, found {name!r}")
    return ESTIMATORS[name]


def build(name: str, cfg: Config, *, stiffness: float = 0.0, omega_o: float | None = None, q: float | None = None,
          omega_q: float | None = None, sigma_model: float | None = None) -> DiscreteEstimator:
    """An estimator of the registry with its knob given explicitly.

    Parameters
    ----------
    name : {"paper", "paper-k0", "eso", "kalman", "dob"}
    cfg : Config
    stiffness : float
        ``paper`` only: the fixed stiffness k [N/m] (default 0).
    omega_o, q, omega_q : float
        The knob of ``eso`` [rad/s], ``kalman`` [N^2/s], ``dob`` [rad/s]; required for that entry.
    sigma_model : float, optional
        Viscous coefficient of the model [N s/m]; default ``sigma`` for ``static``, 0 for ``lag``.

    Raises
    ------
    ValueError
        Unknown name; a knob missing, not positive, or given to an entry that has another knob.
    """
    info = _info(name)
    knobs = {"omega_o": omega_o, "q": q, "omega_q": omega_q}
    extra = [k for k, v in knobs.items() if v is not None and k != info.knob]
    if extra:
        raise ValueError(f"{extra[0]}: {name!r} takes {info.knob or 'no knob'}, found {extra[0]} = {knobs[extra[0]]!r}")
    if name == "paper":
        return build_paper(cfg, stiffness=stiffness, sigma_model=sigma_model)
    if stiffness != 0.0:
        raise ValueError(f"stiffness: only 'paper' takes a stiffness, found {stiffness!r} for {name!r}")
    if name == "paper-k0":
        return build_paper_k0(cfg, sigma_model=sigma_model)
    if knobs[info.knob] is None:
        raise ValueError(f"{info.knob}: {name!r} needs it, expected a finite number > 0 [{info.knob_unit}], found None")
    builder = {"eso": build_eso, "kalman": build_kalman, "dob": build_dob}[name]
    return builder(cfg, **{info.knob: knobs[info.knob]}, sigma_model=sigma_model)
