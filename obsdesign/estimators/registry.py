"""The one catalogue of estimators: names, kernel codes, knobs, tuning rules and builders.

:data:`ESTIMATORS` is a :class:`~obsdesign._registry.Registry` of :class:`EstimatorInfo`
entries, read by the simulator and its kernel (the integer codes), the command line (the
choices), the fair tuning rule (knob, search range, rules) and the docs. It is light: the
builders are named by their module and imported on first use, so the command line reads it
without loading NumPy, SciPy or python-control.

Codes: ``paper`` and ``paper-k0`` (below :data:`FIRST_BASELINE_CODE`) are the paper's
observer, run by the kernel itself with its stiffness schedule; the baselines (codes from
:data:`FIRST_BASELINE_CODE` on) are linear :class:`~obsdesign.estimators.DiscreteEstimator`
run by :func:`~obsdesign.estimators.estimator_step`. Codes are append-only (numba caches them).

Adding a linear estimator: its module (a ``build_<name>(cfg, *, <knob>, sigma_model=None,
tuning="manual")`` returning a ``DiscreteEstimator``) and one entry below; see
docs/estimators.md, "Adding an estimator".

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
>>> ESTIMATORS.code("kalman"), [n for n, info in ESTIMATORS.items() if info.baseline]
(3, ['eso', 'kalman', 'dob'])
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING, Callable

from .._registry import Entry, Registry

if TYPE_CHECKING:
    from ..params import Config
    from .base import DiscreteEstimator

__all__ = ["EstimatorInfo", "ESTIMATORS", "RULES", "RULE_FLAGS", "FIRST_BASELINE_CODE", "build", "estimator_names"]

#: Fair tuning rules (:func:`obsdesign.estimators.tune`): equal friction-noise RMS, equal slowest pole,
#: least predicted friction-estimate error (:func:`obsdesign.estimators.prediction.predict_error`;
#: in :func:`obsdesign.comparison.compare` the paper's rho and omega_co too, :func:`obsdesign.design.tune`).
RULES = ("noise", "rate", "min-error")
#: The names ``compare --rule`` takes -> the rules above (the one list of the command line's choices).
RULE_FLAGS = dict(zip(("equal-noise", "rate", "min-error"), RULES))


@dataclass(frozen=True, kw_only=True)
class EstimatorInfo(Entry):
    """One entry of :data:`ESTIMATORS`: everything the package knows about an estimator by name.

    Attributes
    ----------
    name, code, doc : str, int, str
        The name, the kernel's integer code and one line of description.
    parameters : tuple
        Unused by estimators (their knob is ``knob``): empty.
    knob, knob_unit : str or None
        The design parameter :func:`build` takes (None: none) and its unit.
    knob_default : float or None
        The knob's value when :func:`build` is not given one (None: required).
    knob_range : (float, float) or None
        Search range of the fair tuning rule (log-uniform ``brentq``); None for the paper's
        entries, which are the reference and are not tuned.
    knob_noise_power : int
        The range is for a measurement RMS of 1 um and scales with ``(eta / 1 um)**power``
        (the Kalman filter's ``q``: 2, its gain depends on ``q / eta^2``); such an
        estimator needs measurement noise ``eta > 0``.
    knob_is_rate : bool
        The knob is the slowest error pole's rate [rad/s], so ``rule="rate"`` sets it to the
        paper's dominant rate in closed form (otherwise the rate rule solves for it).
    rules : tuple of str
        The tuning rules (of :data:`RULES`) it supports.
    lowpass : bool
        Whether the closed loop passes ``f_hat`` through eq:3:4:5 before compensating
        (the paper entries); the baselines' bandwidth is their own knob.
    builder : str
        ``"module:function"`` in :mod:`obsdesign.estimators`, imported on first use:
        ``build(cfg, *, <knob>=..., sigma_model=None[, tuning=...]) -> DiscreteEstimator``.
    """

    knob: str | None
    knob_unit: str | None
    knob_default: float | None = None
    knob_range: tuple[float, float] | None = None
    knob_noise_power: int = 0
    knob_is_rate: bool = False
    rules: tuple[str, ...] = RULES
    lowpass: bool
    builder: str

    @property
    def baseline(self) -> bool:
        """A linear estimator run by ``estimator_step``, its knob set by the fair rule (not the paper's)."""
        return self.knob_range is not None

    @property
    def build(self) -> Callable[..., "DiscreteEstimator"]:
        """The builder, imported on first use."""
        module, _, function = self.builder.partition(":")
        return getattr(importlib.import_module(f"{__package__}.{module}"), function)

    @property
    def tune(self) -> Callable[..., "DiscreteEstimator"]:
        """``tune(cfg, *, rule="noise", sigma_model=None)``: :func:`obsdesign.estimators.tune` of this entry."""
        return partial(importlib.import_module(f"{__package__}.tuning").tune, self.name)


#: The estimators, in code order.
ESTIMATORS = Registry("estimator", [
    EstimatorInfo(name="paper", code=0,
                  doc="the paper's reduced-order observer with its stiffness schedule (eq:3:1:2, Prop. 2); "
                      "fixed-k form outside the kernel",
                  knob="stiffness", knob_unit="N/m", knob_default=0.0, lowpass=True, builder="paper:build_paper"),
    EstimatorInfo(name="paper-k0", code=1,
                  doc="the same gains with the schedule off (k = 0 always: a linear reduced-order observer), "
                      "the ablation of the pre-sliding schedule",
                  knob=None, knob_unit=None, lowpass=True, builder="paper:build_paper_k0"),
    EstimatorInfo(name="eso", code=2,
                  doc="linear extended state observer, all three poles at -omega_o (Gao 2003)",
                  knob="omega_o", knob_unit="rad/s", knob_range=(1e-3, 1e5), knob_is_rate=True,
                  lowpass=False, builder="eso:build_eso"),
    EstimatorInfo(name="kalman", code=3,
                  doc="steady-state Kalman filter (current estimator) with a random-walk friction",
                  knob="q", knob_unit="N^2/s", knob_range=(1e-20, 1e8), knob_noise_power=2,
                  lowpass=False, builder="kalman:build_kalman"),
    EstimatorInfo(name="dob", code=4,
                  doc="disturbance observer, Q(s) = omega_q^2/(s + omega_q)^2",
                  knob="omega_q", knob_unit="rad/s", knob_range=(1e-3, 1e5), knob_is_rate=True,
                  lowpass=False, builder="dob:build_dob"),
])

#: Codes from this one on are baselines (linear, ``estimator_step``); those below are the paper's observer.
FIRST_BASELINE_CODE = min(info.code for info in ESTIMATORS.values() if info.baseline)
if any(info.baseline != (info.code >= FIRST_BASELINE_CODE) or (info.baseline and info.lowpass)
       for info in ESTIMATORS.values()):  # what the kernel assumes
    raise RuntimeError("estimators: every baseline follows the paper's codes and compensates with its own estimate")


def estimator_names() -> tuple[str, ...]:
    """Names of the registry, in code order."""
    return ESTIMATORS.names()


def build(name: str, cfg: "Config", *, sigma_model: float | None = None, **knob: float) -> "DiscreteEstimator":
    """An estimator of :data:`ESTIMATORS` with its knob given explicitly.

    Parameters
    ----------
    name : str
        A name of :data:`ESTIMATORS`.
    cfg : Config
        The design.
    sigma_model : float, optional
        Viscous coefficient of the model [N s/m]; default ``sigma`` for ``static``, 0 for ``lag``.
    **knob : float
        The entry's knob by its name (:attr:`EstimatorInfo.knob`, e.g. ``omega_o=300.0`` for
        ``eso``, ``stiffness=`` [N/m] for ``paper``); required unless the entry has a default.
        ``None`` counts as not given.

    Raises
    ------
    ValueError
        Unknown name; a knob missing, not positive, or given to an entry that has another knob.
    """
    info = ESTIMATORS[ESTIMATORS.check(name, kind="name")]
    given = {k: v for k, v in knob.items() if v is not None}
    extra = [k for k in given if k != info.knob]
    if extra:
        raise ValueError(f"{extra[0]}: {name!r} takes {info.knob or 'no knob'}, found {extra[0]} = {given[extra[0]]!r}")
    if info.knob is None:
        return info.build(cfg, sigma_model=sigma_model)
    value = given.get(info.knob, info.knob_default)
    if value is None:
        raise ValueError(f"{info.knob}: {name!r} needs it, expected a finite number > 0 [{info.knob_unit}], found None")
    return info.build(cfg, **{info.knob: value}, sigma_model=sigma_model)
