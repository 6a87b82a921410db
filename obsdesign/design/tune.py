"""Tuning: rho, the low-pass cutoff omega_co and the compensation gain for a config, by a named objective.

Objectives (:data:`OBJECTIVES`, lower is better):

``estimate-error``
    The predicted RMS error [N] of the compensated estimate ``gain f_hat_filtered`` under the
    config's sensor noise: noise propagation plus the tracking lag of Coulomb reversals
    (:func:`obsdesign.estimators.prediction.predict_error`, the paper's observer at ``k = 0``
    with its low-pass eq:3:4:5).
``tracking``
    The RMS tracking error [m] of a scenario of :data:`obsdesign.sim.cases.CASES` (the comparison's;
    default ``tracking``), by simulation (seed 0, after :data:`obsdesign.sim.cases.TRANSIENT`).

Constraints (:class:`Constraints`):

* the certificate holds (:func:`obsdesign.design.certify`: the switched sampled observer);
* ``min_phase_margin_deg``: phase margin of the sampled loop that runs with the compensation,
  ``L(z) = z^-d (C - g Gy / K) H - g Gu`` broken at the controller's output: the plant ``H_zoh`` and the
  discrete PID ``C`` of :mod:`obsdesign.design.sampled_loop`, the drive's delay ``d``, and the path from
  the measurement (``Gy``) and from the commanded force (``Gu``) to the filtered friction estimate
  (:mod:`obsdesign.design.compensated_loop`); the closed loop must be stable;
* ``max_command_noise``: RMS [V] of the command from the measurement noise through the same loop,
  ``(-C + g Gy / K) / (1 + L)``, for band-limited noise as :func:`obsdesign.estimators.noise_level`.

Search (deterministic): a grid over ``log rho x log omega_co x gain`` (:data:`GRID`), the best
feasible point refined by bounded Powell (``scipy.optimize.minimize``) on the objective with a
penalty outside the constraints; the starting design is a candidate too, so the result is never
worse than it when it is feasible.

Examples
--------
>>> import obsdesign as od
>>> e = evaluate(od.load_preset("vcm"))   # the start of a tuning: objective and constraint values
>>> round(e.objective, 5), round(e.parts["noise_part"], 6), e.certified, round(e.phase_margin_deg, 2)
(0.06539, 0.001232, True, 20.12)

See docs/tune.md for a whole tuning.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._display import ResultDisplay
from .._validate import check_choice
from ..params import Config
from .compensated_loop import compensated_loop as _loop
from .objectives import OBJECTIVES, TRACKING_SCENARIOS

__all__ = ["OBJECTIVES", "TRACKING_SCENARIOS", "Constraints", "Evaluation", "TuneResult", "tune", "evaluate", "GRID"]

#: Grid points per variable (rho, omega_co, gain) of the coarse search, per objective.
GRID = {"estimate-error": (7, 7, 3), "tracking": (4, 4, 2)}
#: Search box: rho, omega_co as multiples of the Nyquist rate, gain.
RHO_RANGE = (1.05, 50.0)
OMEGA_RANGE = (1e-4, 0.5)
GAIN_RANGE = (0.1, 1.0)


@dataclass(frozen=True, kw_only=True)
class Constraints:
    """What a tuned design must satisfy.

    Parameters
    ----------
    min_phase_margin_deg : float, optional
        Least phase margin [deg] of the sampled loop with the compensation.
    max_command_noise : float, optional
        Largest RMS [V] of the command from the measurement noise.
    certificate : bool
        The switched sampled observer must be certified.
    """

    min_phase_margin_deg: float | None = None
    max_command_noise: float | None = None
    certificate: bool = True

    def __post_init__(self) -> None:
        pm = self.min_phase_margin_deg
        if pm is not None and not (isinstance(pm, (int, float)) and 0.0 <= pm < 180.0):
            raise ValueError(f"min_phase_margin_deg: expected a number in [0, 180) [deg], found {pm!r}")
        cn = self.max_command_noise
        if cn is not None and not (isinstance(cn, (int, float)) and math.isfinite(cn) and cn > 0.0):
            raise ValueError(f"max_command_noise: expected a finite number > 0 [V], found {cn!r}")


@dataclass(frozen=True, kw_only=True)
class Evaluation:
    """Objective and constraint values of one design.

    Attributes
    ----------
    rho, omega_co, gain : float
        The design: gain parameter [-], low-pass cutoff [rad/s], compensation gain [-].
    objective : float
        The objective's value (``inf``: no value, e.g. an unstable observer or a diverged run).
    certified : bool
        The certificate holds (True without computing it where the search skipped it).
    decay_rate : float or None
        The certified decay rate [1/s].
    phase_margin_deg : float
        Phase margin [deg] of the sampled loop with the compensation (``-inf``: unstable loop).
    stable_loop : bool
        The closed sampled loop with the compensation is stable.
    command_noise : float
        RMS [V] of the command from the sensor noise.
    parts : dict
        The objective's parts (``estimate-error``: ``noise_part``, ``lag_part`` [N]).
    """

    rho: float
    omega_co: float
    gain: float
    objective: float
    certified: bool
    decay_rate: float | None
    phase_margin_deg: float
    stable_loop: bool
    command_noise: float
    parts: dict = field(default_factory=dict)

    def violations(self, c: Constraints) -> dict[str, float]:
        """Constraint name -> how far it is violated (> 0), for the violated ones.

        Parameters
        ----------
        c : Constraints
            The constraints.
        """
        out = {}
        if c.certificate and not self.certified:
            out["certificate"] = 1.0
        if not self.stable_loop:
            out["loop stability"] = 1.0
        if c.min_phase_margin_deg is not None and not self.phase_margin_deg >= c.min_phase_margin_deg:
            pm = self.phase_margin_deg if math.isfinite(self.phase_margin_deg) else -180.0
            out["min_phase_margin"] = (c.min_phase_margin_deg - pm) / max(c.min_phase_margin_deg, 1.0)
        if c.max_command_noise is not None and not self.command_noise <= c.max_command_noise:
            out["max_command_noise"] = min(self.command_noise / c.max_command_noise - 1.0, 1e6)
        return out

    def to_dict(self) -> dict:
        """JSON-ready values."""
        return {"rho": self.rho, "omega_co": self.omega_co, "gain": self.gain, "objective": self.objective,
                "certified": self.certified, "decay_rate": self.decay_rate,
                "phase_margin_deg": self.phase_margin_deg if math.isfinite(self.phase_margin_deg) else None,
                "stable_loop": self.stable_loop, "command_noise": self.command_noise, **self.parts}


@dataclass(frozen=True, kw_only=True)
class TuneResult(ResultDisplay):
    """The tuned design and why.

    Attributes
    ----------
    objective : str
        The objective's name (:data:`OBJECTIVES`).
    config : Config
        The tuned config (``rho``, ``omega_co``, ``gain`` replaced).
    start, chosen : Evaluation
        The starting and the chosen design's values.
    constraints : Constraints
    before, after : float
        The objective of the start and of the chosen design.
    feasible : bool
        Whether the chosen design meets every constraint.
    evaluations : int
        Designs evaluated.
    wall_s : float
        Wall time [s].
    """

    _title = "Tuning"
    objective: str
    config: Config
    start: Evaluation
    chosen: Evaluation
    constraints: Constraints
    before: float
    after: float
    feasible: bool
    evaluations: int
    wall_s: float

    def constraint_rows(self) -> list[dict]:
        """Each constraint: its bound, the start's and the chosen design's value, and the margin."""
        c, s, d = self.constraints, self.start, self.chosen
        rows = []
        if c.certificate:
            rows.append({"constraint": "certificate", "bound": "certified", "start": s.certified,
                         "chosen": d.certified, "margin": d.decay_rate})
        rows.append({"constraint": "loop stability", "bound": "stable", "start": s.stable_loop,
                     "chosen": d.stable_loop, "margin": None})
        if c.min_phase_margin_deg is not None:
            rows.append({"constraint": "min_phase_margin [deg]", "bound": c.min_phase_margin_deg,
                         "start": s.phase_margin_deg, "chosen": d.phase_margin_deg,
                         "margin": d.phase_margin_deg - c.min_phase_margin_deg})
        if c.max_command_noise is not None:
            rows.append({"constraint": "max_command_noise [V]", "bound": c.max_command_noise,
                         "start": s.command_noise, "chosen": d.command_noise,
                         "margin": c.max_command_noise - d.command_noise})
        return rows

    def simulated_plant(self):
        """The PID loop (without the compensation) around the simulated plant in sliding, with the drive's
        delay (:func:`obsdesign.design.plant_loop.plant_loop`): tuning does not change it."""
        from .plant_loop import plant_loop

        return plant_loop(self.config)

    def to_dict(self) -> dict:
        """JSON-ready values (``tune --json``)."""
        return {"objective": self.objective, "before": self.before, "after": self.after, "feasible": self.feasible,
                "start": self.start.to_dict(), "chosen": self.chosen.to_dict(),
                "constraints": self.constraint_rows(), "evaluations": self.evaluations, "wall_s": self.wall_s,
                "simulated_plant": self.simulated_plant().to_dict()}

    def _rows(self):
        s, d = self.start, self.chosen
        rows = [("objective", f"{self.objective}: {self.before:.6g} -> {self.after:.6g}"),
                ("rho", f"{s.rho:.6g} -> {d.rho:.6g}"), ("omega_co [rad/s]", f"{s.omega_co:.6g} -> {d.omega_co:.6g}"),
                ("compensation gain", f"{s.gain:.4g} -> {d.gain:.4g}")]
        for key in d.parts:
            rows.append((f"  {key.replace('_', ' ')}", f"{s.parts.get(key, math.nan):.6g} -> {d.parts[key]:.6g}"))
        def show(x):
            return f"{x:.4g}" if isinstance(x, float) else str(x)

        for r in self.constraint_rows():
            label = "decay rate [1/s]" if r["constraint"] == "certificate" else "margin"
            margin = "" if r["margin"] is None else f" ({label} {r['margin']:.4g})"
            rows.append((r["constraint"], f"bound {show(r['bound'])}: start {show(r['start'])}, "
                                          f"chosen {show(r['chosen'])}{margin}"))
        pl = self.simulated_plant()
        rows.append(("PID loop, simulated plant", f"phase margin {pl.phase_margin_deg:.4g} deg, gain margin "
                                                  f"{pl.gain_margin_db:.4g} dB ({pl.system})"))
        rows.append(("evaluations", f"{self.evaluations} in {self.wall_s:.1f} s"))
        return rows


def _paper_estimator(cfg: Config):
    from ..estimators import reference_estimator

    return reference_estimator(cfg)


class _Evaluator:
    """Objective and constraints of designs ``(rho, omega_co, gain)``, with the certificate cached per rho."""

    def __init__(self, cfg: Config, objective: str, scenario: str, reversal_rate: float) -> None:
        self.cfg, self.objective, self.scenario, self.reversal_rate = cfg, objective, scenario, reversal_rate
        self._cert: dict[float, tuple[bool, float | None]] = {}
        self.count = 0

    def certificate(self, cfg: Config) -> tuple[bool, float | None]:
        rho = cfg.observer.rho
        if rho not in self._cert:
            from .certificate import certify
            from .observer import design_observer

            c = certify(design_observer(cfg))
            self._cert[rho] = (c.certified, c.decay_rate)
        return self._cert[rho]

    def __call__(self, rho: float, omega_co: float, gain: float, *, certificate: bool = True) -> Evaluation:
        """The values of one design (``certificate=False``: the certificate is not computed, reported as held)."""
        self.count += 1
        cfg = self.cfg.override(rho=float(rho), omega_co=float(omega_co), gain=float(gain))
        certified, decay = self.certificate(cfg) if certificate else (True, None)
        try:
            est = _paper_estimator(cfg)
        except ValueError:  # rho <= 1: the paper's observer is unstable at k = 0
            return Evaluation(rho=rho, omega_co=omega_co, gain=gain, objective=math.inf, certified=certified,
                              decay_rate=decay, phase_margin_deg=-math.inf, stable_loop=False, command_noise=math.inf)
        pm, stable, noise = _loop(cfg, est, gain)
        parts: dict = {}
        if self.objective == "estimate-error":
            from ..estimators.prediction import predict_error

            p = predict_error(est, cfg, gain=gain, reversal_rate=self.reversal_rate)
            value, parts = p.total, {"noise_part": p.noise, "lag_part": p.lag}
        else:
            value = _tracking_error(cfg, self.scenario)
        return Evaluation(rho=float(rho), omega_co=float(omega_co), gain=float(gain), objective=value,
                          certified=certified, decay_rate=decay, phase_margin_deg=pm, stable_loop=stable,
                          command_noise=noise, parts=parts)


def _tracking_error(cfg: Config, scenario: str) -> float:
    from ..sim.cases import CASES, TRANSIENT
    from ..sim.metrics import rms
    from ..sim.simulate import simulate

    spec, duration = CASES[scenario]
    try:
        res = simulate(cfg, spec, duration=duration, seed=0)
    except (ValueError, ArithmeticError):
        return math.inf
    if res.metrics["diverged"]:
        return math.inf
    value = rms(res.e[res.t >= TRANSIENT])
    return value if value is not None and math.isfinite(value) else math.inf


def evaluate(cfg: Config, *, objective: str = "estimate-error", scenario: str = "tracking",
             reversal_rate: float | None = None) -> Evaluation:
    """Objective and constraint values of ``cfg`` as it is (see :func:`tune`).

    Parameters
    ----------
    cfg : Config
        The design.
    objective, scenario, reversal_rate
        As :func:`tune`.

    Examples
    --------
    >>> import obsdesign as od
    >>> e = evaluate(od.load_preset("vcm"))
    >>> e.certified, e.stable_loop, round(e.objective, 5)
    (True, True, 0.06539)
    """
    from ..estimators.prediction import REVERSAL_RATE

    ev = _Evaluator(_check(cfg), check_choice("objective", objective, OBJECTIVES.names()),
                    check_choice("scenario", scenario, TRACKING_SCENARIOS),
                    REVERSAL_RATE if reversal_rate is None else reversal_rate)
    return ev(cfg.observer.rho, cfg.observer.omega_co, cfg.compensation.gain)


def _check(cfg) -> Config:
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    return cfg


def tune(cfg: Config, *, objective: str = "estimate-error", constraints: Constraints | None = None,
         scenario: str = "tracking", reversal_rate: float | None = None,
         tune_gain: bool = True) -> TuneResult:
    """Choose ``rho``, ``omega_co`` and the compensation gain of ``cfg`` by ``objective`` (module docstring).

    Parameters
    ----------
    cfg : Config
        The starting design (typically identified: :meth:`obsdesign.data.Identification.to_config`).
    objective : str
        A name of :data:`OBJECTIVES`.
    constraints : Constraints, optional
        Default: the certificate only.
    scenario : str
        The ``tracking`` objective's scenario, one of :data:`TRACKING_SCENARIOS`.
    reversal_rate : float, optional
        Reversals per second [1/s] of the ``estimate-error`` lag model (default
        :data:`obsdesign.estimators.prediction.REVERSAL_RATE`).
    tune_gain : bool
        Tune the compensation gain too (False: keep ``cfg``'s).

    Returns
    -------
    TuneResult

    Raises
    ------
    ValueError
        An unknown objective or scenario; no design in the search box meets the constraints
        (the message names the constraint and the best value found).
    """
    import time

    import scipy.optimize

    from ..estimators.prediction import REVERSAL_RATE

    t0 = time.perf_counter()
    cfg = _check(cfg)
    objective = check_choice("objective", objective, OBJECTIVES.names())
    scenario = check_choice("scenario", scenario, TRACKING_SCENARIOS)
    constraints = Constraints() if constraints is None else constraints
    if not isinstance(constraints, Constraints):
        raise TypeError(f"constraints: expected a Constraints, found {type(constraints).__name__}")
    ev = _Evaluator(cfg, objective, scenario, REVERSAL_RATE if reversal_rate is None else reversal_rate)
    start = ev(cfg.observer.rho, cfg.observer.omega_co, cfg.compensation.gain)
    n_rho, n_w, n_g = GRID[objective]
    w_nyq = math.pi / cfg.observer.dt
    box = [(math.log(RHO_RANGE[0]), math.log(RHO_RANGE[1])),
           (math.log(OMEGA_RANGE[0] * w_nyq), math.log(OMEGA_RANGE[1] * w_nyq)),
           GAIN_RANGE if tune_gain else (cfg.compensation.gain, cfg.compensation.gain)]
    gains = np.linspace(*GAIN_RANGE, n_g) if tune_gain else [cfg.compensation.gain]
    grid = [ev(math.exp(a), math.exp(b), float(g)) for a in np.linspace(*box[0], n_rho)
            for b in np.linspace(*box[1], n_w) for g in gains]
    feasible = [e for e in (start, *grid) if not e.violations(constraints) and math.isfinite(e.objective)]
    if not feasible:
        raise ValueError(_infeasible(constraints, [start, *grid]))
    best = min(feasible, key=lambda e: e.objective)
    worst = max(e.objective for e in feasible)
    seen: dict[tuple, Evaluation] = {}

    incumbent = [best]

    def penalised(x) -> float:
        # the certificate (the costly constraint, cached per rho) is computed only for a design that
        # would improve on the incumbent: every design that can be chosen is verified
        key = tuple(np.round(x, 12))
        if key not in seen:
            e = ev(math.exp(x[0]), math.exp(x[1]), float(x[2]), certificate=False)
            if not e.violations(constraints) and e.objective < incumbent[0].objective:
                e = ev(e.rho, e.omega_co, e.gain)
                if not e.violations(constraints):
                    incumbent[0] = e
            seen[key] = e
        e = seen[key]
        bad = e.violations(constraints)
        if bad or not math.isfinite(e.objective):
            return 2.0 * worst + worst * sum(bad.values())
        return e.objective

    x0 = [math.log(best.rho), math.log(best.omega_co), best.gain]
    bounds = [box[0], box[1], box[2] if tune_gain else (best.gain, best.gain)]
    scipy.optimize.minimize(penalised, x0, method="Powell", bounds=bounds,
                            options={"maxfev": 80 if objective == "estimate-error" else 20, "xtol": 1e-3,
                                     "ftol": 1e-6})
    chosen = incumbent[0]
    if not start.violations(constraints) and start.objective <= chosen.objective:
        chosen = start
    tuned = cfg.override(rho=chosen.rho, omega_co=chosen.omega_co, gain=chosen.gain)
    return TuneResult(objective=objective, config=tuned, start=start, chosen=chosen, constraints=constraints,
                      before=start.objective, after=chosen.objective, feasible=True, evaluations=ev.count,
                      wall_s=time.perf_counter() - t0)


def _infeasible(c: Constraints, evals: list[Evaluation]) -> str:
    """The message for a search box where no design meets the constraints: each violated one and its best value."""
    parts = []
    if c.certificate and not any(e.certified for e in evals):
        parts.append("certificate: no rho in the search box is certified")
    if c.min_phase_margin_deg is not None:
        pm = max(e.phase_margin_deg for e in evals)
        if not pm >= c.min_phase_margin_deg:
            parts.append(f"min_phase_margin: expected >= {c.min_phase_margin_deg:g} deg, the best design in the "
                         f"search box has {pm:.4g} deg")
    if c.max_command_noise is not None:
        cn = min(e.command_noise for e in evals)
        if not cn <= c.max_command_noise:
            parts.append(f"max_command_noise: expected <= {c.max_command_noise:g} V, the quietest design in the "
                         f"search box has {cn:.4g} V")
    if not parts:
        parts.append("the constraints cannot hold together: each is met by some design in the search box, none meets all")
    return "infeasible constraint: " + "; ".join(parts)
