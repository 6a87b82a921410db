"""Observer gains from rho (Proposition 2) and the stability verdicts of a design.

Examples
--------
>>> import obsdesign as od
>>> rep = od.check_stability(od.load_preset("table1"))
>>> rep.stable, rep.eigenvalues_real, round(rep.dominant_pole, 3)
(True, True, -2.439)
>>> od.check_stability(od.load_preset("table1").override(rho=0.98)).failed()
('Proposition 1: L_2 < sigma/beta', 'eigenvalues negative on [0, kappa]', 'Ignatyev (ii) at kdot = 0', 'discrete poles inside unit circle', 'switched sampled observer certified')
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import NamedTuple

from typing import TYPE_CHECKING

import numpy as np

from .._display import Condition, ResultDisplay
from ..params import Config
from .certificate import StabilityCertificate, certify
from .numeric import compiled, model_values, stability_conditions

if TYPE_CHECKING:  # python-control loads on first use: `obsdesign check` does not need it
    import control as ct

__all__ = [
    "ObserverDesign",
    "ObserverArrays",
    "FrozenSystems",
    "StabilityReport",
    "design_observer",
    "check_stability",
    "is_stable",
]

#: Relative tolerance on the discriminant at k = kappa, where the design puts a double pole.
DISCRIMINANT_RTOL = 1e-9


@dataclass(frozen=True)
class FrozenSystems:
    """The plant model and the observer frozen at one stiffness (python-control).

    Attributes
    ----------
    stiffness : float
        The pre-sliding stiffness k [N/m] they are frozen at.
    plant : control.StateSpace
        eq:3:1 with states ``x, v, f``, input ``u`` [N], output ``x``.
    observer : control.StateSpace
        eq:3:1:2-3 with states ``ytilde``, inputs ``u, x_meas`` and outputs
        ``v_hat, f_hat`` (the back transformation is the feedthrough ``L``).
    """

    stiffness: float
    plant: ct.StateSpace
    observer: ct.StateSpace


@dataclass(frozen=True, kw_only=True)
class ObserverDesign(ResultDisplay):
    """Observer gains for one config, with the numeric observer matrices.

    Use :func:`design_observer` to build one.

    Attributes
    ----------
    variant : {"lag", "static"}
        The model variant the gains are derived for.
    m, sigma, beta, Cf, s, kappa : float
        Plant and friction values of the config (``beta`` None: static viscous friction).
    rho : float
        The gain design parameter.
    L1, L2 : float
        The observer gains (eq:3:3:3-4 for ``lag``, section 4 for ``static``).
    dt : float
        Controller sample time [s].
    """

    _title = "Observer design"
    variant: str
    m: float
    sigma: float
    beta: float | None
    Cf: float
    s: float
    kappa: float
    rho: float
    L1: float
    L2: float
    dt: float

    def parameter_values(self, stiffness: float) -> dict[str, float]:
        """Arguments of the compiled derivation functions (:mod:`obsdesign.design.numeric`) at stiffness k."""
        return model_values(
            m=self.m, sigma=self.sigma, beta=math.nan if self.beta is None else self.beta,
            Cf=self.Cf, s=self.s, kappa=self.kappa, rho=self.rho, k=stiffness, L1=self.L1, L2=self.L2,
        )

    def coefficients(self, stiffness: float) -> tuple[float, float]:
        """``(a0, a1)`` of the characteristic polynomial (eq:3:2:3-4) at stiffness k."""
        a0, a1 = compiled(self.variant, "coefficients")(**self.parameter_values(stiffness))
        return float(a0), float(a1)

    def eigenvalues(self, stiffness: float) -> np.ndarray:
        """The two observer eigenvalues (eq:3:3:1) at stiffness k [N/m], larger real part first.

        >>> d = design_observer(__import__("obsdesign").load_preset("vcm"))
        >>> np.round(d.eigenvalues(d.kappa).real, 3)  # the designed double pole
        array([-487.769, -487.769])
        """
        a0, a1 = self.coefficients(stiffness)
        root = np.lib.scimath.sqrt(a1 * a1 - 4.0 * a0)
        return np.array([(-a1 + root) / 2.0, (-a1 - root) / 2.0], dtype=complex)

    def matrices(self, stiffness: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(A22 - L A12, B2 - L B1, A21 - L A11 + A22 L - L A12 L)`` as arrays (eq:3:1:2)."""
        v = self.parameter_values(stiffness)
        A_obs = np.asarray(compiled(self.variant, "observer_matrix")(**v), float)
        b_u = np.asarray(compiled(self.variant, "observer_input")(**v), float).ravel()
        g_x = np.asarray(compiled(self.variant, "observer_output_gain")(**v), float).ravel()
        return A_obs, b_u, g_x

    def to_statespace(self, stiffness: float) -> FrozenSystems:
        """Plant model and observer frozen at stiffness k, as python-control systems.

        >>> import obsdesign as od
        >>> sys = design_observer(od.load_preset("vcm")).to_statespace(0.0)
        >>> sys.observer.ninputs, sys.observer.noutputs, sys.plant.nstates
        (2, 2, 3)
        """
        if isinstance(stiffness, bool) or not isinstance(stiffness, (int, float)) or not (
            math.isfinite(stiffness) and stiffness >= 0
        ):
            raise ValueError(f"stiffness: expected a finite number >= 0 [N/m], found {stiffness!r}")
        import control as ct

        v = self.parameter_values(float(stiffness))
        A, B, C = (np.asarray(compiled(self.variant, n)(**v), float) for n in ("A", "B", "C"))
        plant = ct.ss(A, B.reshape(3, 1), C.reshape(1, 3), 0.0, states=["x", "v", "f"], inputs=["u"], outputs=["x"])
        A_obs, b_u, g_x = self.matrices(float(stiffness))
        observer = ct.ss(
            A_obs, np.column_stack([b_u, g_x]), np.eye(2), np.array([[0.0, self.L1], [0.0, self.L2]]),
            states=["ytilde1", "ytilde2"], inputs=["u", "x_meas"], outputs=["v_hat", "f_hat"],
        )
        return FrozenSystems(stiffness=float(stiffness), plant=plant, observer=observer)

    def affine(self) -> "ObserverArrays":
        """The observer in the affine-in-stiffness form the simulator and the exports use.

        ``A(k) = A0 + k A1`` (eq:3:2:1), and likewise the input vector ``b`` and the measurement
        gain ``g`` of eq:3:1:2; the affinity is proved symbolically when the numeric functions are
        generated (:mod:`obsdesign.symbolic.generate`).

        >>> import obsdesign as od
        >>> arr = design_observer(od.load_preset("vcm")).affine()
        >>> arr.A1.tolist()  # only A(2,1) depends on k ...
        [[0.0, 0.0], [1.0, 0.0]]
        >>> float(arr.g1[0]), round(float(arr.g1[1] / arr.design.L1), 9)  # ... and g2, through A22 L = (., k L1)
        (0.0, 1.0)
        """
        at0, at1 = self.matrices(0.0), self.matrices(1.0)
        A0, b0, g0 = at0
        A1, b1, g1 = (np.asarray(x1) - np.asarray(x0) for x0, x1 in zip(at0, at1))
        return ObserverArrays(self, np.ascontiguousarray(A0), np.ascontiguousarray(A1), b0, b1, g0, g1)

    def _rows(self):
        return [("variant", self.variant), ("rho", self.rho), ("kappa [N/m]", self.kappa),
                ("L1 [1/s]", self.L1), ("L2 [N/m]", self.L2)]


@dataclass(frozen=True, eq=False)
class ObserverArrays:
    """A designed observer in the affine-in-stiffness form: ``A(k) = A0 + k A1``, ``b(k) = b0 + k b1``,
    ``g(k) = g0 + k g1`` (observer matrix, input vector and measurement gain of eq:3:1:2).

    Built by :meth:`ObserverDesign.affine`.

    Attributes
    ----------
    design : ObserverDesign
        The design the arrays come from.
    A0, A1 : ndarray, shape (n, n)
        Observer matrix at ``k = 0`` and its slope in ``k``.
    b0, b1 : ndarray, shape (n,)
        Input vector and its slope.
    g0, g1 : ndarray, shape (n,)
        Measurement gain and its slope.
    """

    design: ObserverDesign
    A0: np.ndarray
    A1: np.ndarray
    b0: np.ndarray
    b1: np.ndarray
    g0: np.ndarray
    g1: np.ndarray


def design_observer(cfg: Config) -> ObserverDesign:
    """Observer gains from rho by the gain rule of Proposition 2 (eq:3:3:3-4).

    Parameters
    ----------
    cfg : Config
        The design (change values with :meth:`obsdesign.Config.override` before).

    Returns
    -------
    ObserverDesign

    Examples
    --------
    >>> import obsdesign as od
    >>> d = design_observer(od.load_preset("table1"))
    >>> round(d.L1, 4), round(d.L2, 3)  # 2 rho sqrt(kappa/m), sigma/beta + kappa (1 - rho^2)
    (248.762, 20776.8)
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    fr, ob = cfg.friction, cfg.observer
    vals = model_values(m=cfg.plant.m, sigma=fr.sigma, beta=fr.beta if ob.variant == "lag" else math.nan,
                        Cf=fr.Cf, s=fr.s, kappa=fr.kappa, rho=ob.rho)
    L1, L2 = compiled(ob.variant, "gain_rule")(**vals)
    return ObserverDesign(
        variant=ob.variant, m=cfg.plant.m, sigma=fr.sigma, beta=fr.beta if ob.variant == "lag" else None,
        Cf=fr.Cf, s=fr.s, kappa=fr.kappa, rho=ob.rho, L1=float(L1), L2=float(L2), dt=ob.dt,
    )


@dataclass(frozen=True, kw_only=True)
class StabilityReport(ResultDisplay):
    """Stability verdicts of an observer design over the stiffness range [0, kappa].

    Attributes
    ----------
    design : ObserverDesign
    stable : bool
        Proposition 1 holds and both eigenvalues are negative on [0, kappa].
    eigenvalues_real, observable : bool
    dominant_pole, fastest_pole : float
        Largest and smallest real part of the eigenvalues over [0, kappa] [1/s].
    eigenvalues_at_ends : dict
        ``{0.0: array, kappa: array}``.
    alpha1, alpha2 : float or None
        Constants of Ignatyev's conditions (i), (ii) with ``kdot = 0``; None where none exists.
    presliding_velocity_bound : dict
        Largest ``|dx/dt|`` [m/s] for which condition (ii) holds along a whole pre-sliding
        transition with the stiffness rate of eq:3:2:7 (corrected sign), for ``D = 2``
        (reversal from gross sliding) and ``D = 1`` (start from rest).
    discrete_pole_radii : dict
        Radii of the exactly discretized observer poles at ``dt``, at k = 0 and kappa (frozen
        stiffness: this does not prove stability under switching).
    certificate : StabilityCertificate
        The verdict on the switched, exactly discretized observer that runs
        (:func:`obsdesign.design.certificate.certify`): its own condition of ``check``.
    conditions : tuple of Condition
    warnings : tuple of str
    """

    _title = "Observer stability check"
    design: ObserverDesign
    stable: bool
    eigenvalues_real: bool
    observable: bool
    dominant_pole: float
    fastest_pole: float
    eigenvalues_at_ends: dict
    alpha1: float | None
    alpha2: float | None
    presliding_velocity_bound: dict
    discrete_pole_radii: dict
    certificate: "StabilityCertificate"
    conditions: tuple[Condition, ...]
    warnings: tuple[str, ...] = field(default=())

    @property
    def all_hold(self) -> bool:
        """True when every condition holds (``obsdesign check`` exits 0)."""
        return all(c.holds for c in self.conditions)

    def failed(self) -> tuple[str, ...]:
        """Names of the conditions that do not hold."""
        return tuple(c.name for c in self.conditions if not c.holds)

    def to_dict(self) -> dict:
        """JSON-ready summary (the keys of ``obsdesign check --json``)."""
        return {
            "L1": self.design.L1, "L2": self.design.L2, "stable": self.stable,
            "eigenvalues_real": self.eigenvalues_real, "observable": self.observable,
            "dominant_pole": self.dominant_pole, "fastest_pole": self.fastest_pole,
            "alpha1": self.alpha1, "alpha2": self.alpha2,
            "presliding_velocity_bound": self.presliding_velocity_bound,
            "discrete_pole_radii": {str(k): v for k, v in self.discrete_pole_radii.items()},
            "certificate": self.certificate.to_dict(),
            "conditions": [c.to_dict() for c in self.conditions], "warnings": list(self.warnings),
        }

    def _rows(self):
        d = self.design
        return d._rows() + [
            ("stable", self.stable), ("eigenvalues real", self.eigenvalues_real),
            ("observable", self.observable), ("dominant pole [1/s]", self.dominant_pole),
            ("fastest pole [1/s]", self.fastest_pole), ("Ignatyev alpha1", self.alpha1),
            ("Ignatyev alpha2", self.alpha2),
            ("pre-sliding |v| bound for (ii), D=2 [m/s]", self.presliding_velocity_bound.get("D=2")),
            ("pre-sliding |v| bound for (ii), D=1 [m/s]", self.presliding_velocity_bound.get("D=1")),
        ]

    def _conditions(self):
        return self.conditions


def _presliding_velocity_bound(d: ObserverDesign, a0_ends: tuple[float, float], a1: float, D: float) -> float | None:
    """Largest |x'| with a0' + 2 a0 a1 > 0 along k(z) = -s Cf D ln z, k in [0, kappa].

    With a0' = (da0/dk) dk/dt and dk/dt = -s^2 Cf D x' exp(k / (s Cf D)), condition (ii)
    reads ``|x'| < 2 a1 a0(k) exp(-k/(s Cf D)) / ((da0/dk) s^2 Cf D)``. ``a0`` is affine
    in k, so ``a0(k) exp(-k/c)`` is unimodal and its minimum on [0, kappa] is at an end.
    """
    if not (a1 > 0 and min(a0_ends) > 0):
        return None
    slope = (a0_ends[1] - a0_ends[0]) / d.kappa
    c = d.s * d.Cf * D
    worst = min(a0_ends[0], a0_ends[1] * math.exp(-d.kappa / c))
    return 2.0 * a1 * worst / (slope * d.s * c)


class IntervalVerdicts(NamedTuple):
    """The verdicts over the stiffness range [0, kappa] that decide ``stable``, by name."""

    proposition1_L1: Condition
    proposition1_L2: Condition
    eigenvalues_real: Condition
    eigenvalues_negative: Condition

    @property
    def stable(self) -> bool:
        """Proposition 1 (both inequalities) and negative eigenvalues on [0, kappa].

        Ignatyev's (ii) at kdot = 0 follows: a1 > 0 and a0 > 0 give 2 a0 a1 > 0.
        """
        return self.proposition1_L1.holds and self.proposition1_L2.holds and self.eigenvalues_negative.holds


def _interval_verdicts(d: ObserverDesign) -> tuple[IntervalVerdicts, tuple[float, float], float]:
    """Proposition 1 and real/negative eigenvalues on [0, kappa] (exact: a0 affine, a1 constant in k)."""
    a0_ends = (d.coefficients(0.0)[0], d.coefficients(d.kappa)[0])
    a1 = d.coefficients(0.0)[1]
    prop1: dict[str, Condition] = {}
    bounds = compiled(d.variant, "stability_bounds")(**d.parameter_values(0.0))
    for (gain, lhs, rel_op, text), bound in zip(stability_conditions(d.variant), bounds):
        value = d.L1 if gain == "L1" else d.L2
        holds = bool(value > bound) if rel_op == ">" else bool(value < bound)
        prop1[gain] = Condition(f"Proposition 1: {text}", holds,
                                f"{lhs} = {value + 0.0:.6g} (needs {rel_op} {float(bound) + 0.0:.6g})")
    disc = [a1 * a1 - 4.0 * a0 for a0 in a0_ends]
    real = Condition("eigenvalues real on [0, kappa]", all(x >= -DISCRIMINANT_RTOL * a1 * a1 for x in disc),
                     f"discriminant a1^2 - 4 a0 = {disc[0]:.6g} at k = 0, {disc[1]:.6g} at k = kappa")
    negative = Condition("eigenvalues negative on [0, kappa]", bool(a1 > 0 and min(a0_ends) > 0),
                         f"a1 = {a1:.6g}, a0 = {a0_ends[0]:.6g} at k = 0, {a0_ends[1]:.6g} at k = kappa")
    return IntervalVerdicts(prop1["L1"], prop1["L2"], real, negative), a0_ends, a1


def is_stable(cfg: Config) -> bool:
    """The ``stable`` verdict of :func:`check_stability` alone (Proposition 1 and negative
    eigenvalues on [0, kappa]), without observability or discretization checks; for sweeps.

    Parameters
    ----------
    cfg : Config
        The design.

    >>> import obsdesign as od
    >>> is_stable(od.load_preset("table1")), is_stable(od.load_preset("table1").override(rho=0.98))
    (True, False)
    """
    return _interval_verdicts(design_observer(cfg))[0].stable


def check_stability(cfg: Config, *, search: bool = True) -> StabilityReport:
    """Check an observer design over the whole stiffness range [0, kappa].

    The characteristic polynomial ``lambda^2 + a1 lambda + a0(k)`` has ``a1``
    constant and ``a0`` affine in ``k`` (proved symbolically), so the
    discriminant is affine in ``k`` too: checking the two ends of the interval
    is exact for realness and for negativity of both eigenvalues.

    Parameters
    ----------
    cfg : Config
        The design (change values with :meth:`obsdesign.Config.override` before).
    search : bool
        Passed to :func:`~obsdesign.design.certificate.certify`: False for a caller that needs the
        verdicts only (the same verdicts; the certificate's decay rate may be weaker).

    Returns
    -------
    StabilityReport
        Emits a ``UserWarning`` when the fastest pole times ``dt`` exceeds 1.

    Examples
    --------
    >>> import obsdesign as od
    >>> rep = check_stability(od.load_preset("vcm"))
    >>> rep.all_hold, round(rep.fastest_pole, 1)
    (True, -609.7)
    """
    d = design_observer(cfg)
    ends = (0.0, d.kappa)
    verdicts, a0_ends, a1 = _interval_verdicts(d)
    if not all(math.isfinite(x) for x in (*a0_ends, a1, 2.0 * a1 * min(a0_ends), a1 * a1)):
        raise FloatingPointError(f"the characteristic coefficients overflow (a1 = {a1:.6g}, a0 = {a0_ends[0]:.6g} "
                                 f"at k = 0, {a0_ends[1]:.6g} at k = kappa)")
    conditions = list(verdicts)
    stable, real_ok = verdicts.stable, verdicts.eigenvalues_real.holds
    eig = {k: d.eigenvalues(k) for k in ends}

    # Ignatyev's theorem with kdot = 0 (gross sliding and stiffness held at its bound).
    alpha1 = abs(a1)
    alpha2 = 2.0 * a1 * min(a0_ends)
    conditions.append(Condition("Ignatyev (i) at kdot = 0", True, f"|a0'| + |a1| <= alpha1 = {alpha1:.6g}"))
    ig2 = alpha2 > 0
    conditions.append(Condition("Ignatyev (ii) at kdot = 0", ig2, f"min 2 a0 a1 = {alpha2:.6g} (needs > 0)"))
    velocity_bound = {f"D={D:g}": _presliding_velocity_bound(d, a0_ends, a1, D) for D in (2.0, 1.0)}

    # Observability at both ends: rank of [C; C A; C A^2] (python-control's obsv, without importing it).
    observable = True
    for k in ends:
        A, C = (np.asarray(compiled(d.variant, n)(**d.parameter_values(float(k))), float) for n in ("A", "C"))
        C = C.reshape(1, 3)
        rank = int(np.linalg.matrix_rank(np.vstack([C, C @ A, C @ A @ A])))
        observable &= rank == 3
        conditions.append(Condition(f"observable at k = {k:g}", rank == 3, f"rank of obsv(A, C) = {rank} (needs 3)"))

    # Discrete-time view: exact discretization of the observer at dt.
    # eigenvalues of expm(A dt) are exp(lambda dt): |.| = exp(Re(lambda) dt)
    radii = {k: np.exp(np.linalg.eigvals(d.matrices(k)[0]).real * d.dt) for k in ends}
    rmax = max(float(r.max()) for r in radii.values())
    conditions.append(Condition("discrete poles inside unit circle", rmax < 1.0,
                                f"largest pole radius at dt = {d.dt:g} s (frozen stiffness): {rmax:.6g}"))
    # ... and under switching: a common Lyapunov function of the sampled observer (or a refutation)
    certificate = certify(d, search=search)
    conditions.append(certificate.condition())

    reals = np.concatenate([e.real for e in eig.values()])
    dominant, fastest = float(reals.max()), float(reals.min())
    notes = []
    if abs(fastest) * d.dt > 1.0:
        notes.append(
            f"fastest observer pole {fastest:.4g} 1/s times dt = {d.dt:g} s is {abs(fastest) * d.dt:.3g} > 1: "
            "the observer is faster than the sampling; use an exact (not Euler) discretization "
            "and expect noise amplification"
        )
        warnings.warn(notes[-1], UserWarning, stacklevel=2)
    return StabilityReport(
        design=d, stable=bool(stable), eigenvalues_real=bool(real_ok),
        observable=bool(observable), dominant_pole=dominant, fastest_pole=fastest,
        eigenvalues_at_ends=eig, alpha1=alpha1, alpha2=alpha2 if ig2 else None,
        presliding_velocity_bound=velocity_bound,
        discrete_pole_radii={k: tuple(float(x) for x in r) for k, r in radii.items()},
        certificate=certificate, conditions=tuple(conditions), warnings=tuple(notes),
    )
