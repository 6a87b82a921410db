"""Observer shoot-out: every estimator on every plant friction model and scenario (compute only).

Each estimator of :data:`obsdesign.estimators.ESTIMATORS` is designed from one config
(the baselines tuned by the fair noise rule, :func:`obsdesign.estimators.tune`) and runs in
the closed loop (or open loop for ``excitation``) against plants whose friction model is
one of :data:`obsdesign.friction.FRICTION_MODELS` (``[plant_friction]``), at the
design's friction levels. The observer never knows the plant's model: ``paper`` is the
matched case, the others are model mismatch.

Scenarios and their lengths (chosen so the default 5 x 4 x 3 comparison runs in well under
a minute on two cores; see :data:`SCENARIOS`):

* ``excitation``: open loop, 1 N RMS band-limited to 5 Hz, 5 s;
* ``positioning``: 1 mm step up at 0.5 s and back at 3 s, 4 s;
* ``tracking``: a chirp from 0.5 to 3 Hz with 0.1 m/s peak velocity, 8 s.

Metrics per run (columns of :data:`COLUMNS`): RMS friction error of the compensation signal
(the paper's low-pass filtered estimate, the baselines' own estimate) and RMS velocity error
after :data:`TRANSIENT` s; the mean settling time and the largest overshoot of the two steps
(positioning); the RMS tracking error (tracking); the estimator's friction-noise RMS from the
sensor noise (analytic, :func:`obsdesign.estimators.friction_noise_rms`).

Examples
--------
>>> import obsdesign as od
>>> res = compare(od.load_preset("vcm"), plants=("paper",), estimators=("paper", "eso"),
...               scenarios=("excitation",), seeds=1, workers=1)
>>> [(r["estimator"], r["status"]) for r in res.rows]
[('paper', 'ok'), ('eso', 'ok')]
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from ._display import ResultDisplay
from ._validate import check_choice, check_integer
from .estimators import DiscreteEstimator, friction_noise_rms, noise_level, reference_noise_rms, tune
from .estimators.registry import ESTIMATORS, RULES
from .friction.registry import FRICTION_MODELS
from .loop.bands import SETTLE_DWELL
from .loop.inputs import prepare
from .params import Config
from .plant_spec import PlantFrictionSpec
from .sim.cases import CASES, TRANSIENT
from .sim.metrics import rms
from .sim.shared import run_shared
from .sim.simulate import run
from .sim.step_metrics import step_metrics
from .sweeps.pool import Executor

__all__ = ["COLUMNS", "SCENARIOS", "TRANSIENT", "JUDGED", "TIE", "ComparisonResult", "compare",
           "compare_one", "compare_rows", "summarize", "check_comparison_runs", "plant_config", "NOT_TUNED", "not_tuned_row",
           "not_tuned", "paper_design"]

#: Columns of ``compare.csv``, in order.
COLUMNS = ("plant", "estimator", "scenario", "seed", "friction_rms_error", "velocity_rms_error", "settling_time",
           "overshoot", "tracking_rms_error", "friction_noise_rms", "status")
#: Scenario name -> (spec, duration [s]) of the comparison (:data:`obsdesign.sim.cases.CASES`).
SCENARIOS = CASES
#: Relative difference below which two estimators tie, whatever the spread (deterministic runs).
TIE = 0.01
#: The metrics each scenario is judged by in the summary (lower is better): the friction
#: estimate everywhere, and the control result where there is a controller.
JUDGED = {"excitation": ("friction_rms_error",), "positioning": ("friction_rms_error", "settling_time"),
          "tracking": ("friction_rms_error", "tracking_rms_error"), "data": ("friction_rms_error",)}
#: Start of the ``status`` of a row whose baseline the tuning rule could not tune (the reason follows).
NOT_TUNED = "not tuned: "


def not_tuned_row(row: dict[str, Any], error: Exception) -> dict[str, Any]:
    """``row`` with no metrics and the status :data:`NOT_TUNED` followed by the first line of ``error``.

    Parameters
    ----------
    row : dict
        The row's keys (``plant``, ``estimator``, ``scenario``, ``seed``).
    error : Exception
        Why the tuning rule failed.

    >>> not_tuned_row({"estimator": "dob"}, ValueError("noise rule: no knob reaches the target"))["status"]
    'not tuned: noise rule: no knob reaches the target'
    """
    metrics = ("friction_rms_error", "velocity_rms_error", "settling_time", "overshoot", "tracking_rms_error",
               "friction_noise_rms")
    return {**row, **dict.fromkeys(metrics), "status": NOT_TUNED + (str(error).splitlines() or [""])[0]}


def not_tuned(rows: list[dict[str, Any]]) -> dict[str, str]:
    """Estimator -> reason, for every estimator with a row the tuning rule could not tune (:data:`NOT_TUNED`).

    An estimator of the measured rows (plant ``data:<source>``) is named with its plant.

    Parameters
    ----------
    rows : list of dict
        Rows of :func:`compare` or :func:`obsdesign.comparison_data.compare_data` (or of ``compare.csv``).

    >>> not_tuned([{"plant": "lugre", "estimator": "b1", "status": "not tuned: no knob"},
    ...            {"plant": "data:a.csv", "estimator": "b1", "status": "not tuned: no noise"},
    ...            {"plant": "lugre", "estimator": "b2", "status": "ok"}])
    {'b1': 'no knob', 'b1 (data:a.csv)': 'no noise'}
    """
    return {r["estimator"] + (f" ({r['plant']})" if str(r["plant"]).startswith("data:") else ""):
            r["status"][len(NOT_TUNED):] for r in rows if str(r["status"]).startswith(NOT_TUNED)}


def plant_config(cfg: Config, model: str) -> Config:
    """``cfg`` with the plant friction model ``model`` (at ``cfg``'s friction levels).

    Parameters
    ----------
    cfg : Config
        The design.
    model : str
        One of :data:`obsdesign.friction.FRICTION_MODELS`; ``cfg``'s own
        ``[plant_friction]`` parameters are kept when it names the same model.

    Examples
    --------
    >>> import obsdesign as od
    >>> plant_config(od.load_preset("vcm"), "dahl").plant_friction.model
    'dahl'
    """
    FRICTION_MODELS.check(model, kind="plant")
    own = cfg.plant_friction
    params = dict(own.parameters) if own is not None and own.model == model else {}
    return dataclasses.replace(cfg, plant_friction=PlantFrictionSpec(model=model, parameters=params))


def compare_one(cfg: Config, plant: Config, estimator: str | DiscreteEstimator, scenario: str, seed: int,
                noise_rms: float) -> dict[str, Any]:
    """One row of the comparison (never raises for a failed run: ``status`` says ``failed``).

    Parameters
    ----------
    cfg : Config
        The design of the observer and the controller.
    plant : Config
        The simulated plant (its ``[plant_friction]``).
    estimator : str or DiscreteEstimator
        ``paper``/``paper-k0`` or a tuned baseline.
    scenario : str
        A key of :data:`SCENARIOS`.
    seed : int
        Seed of the noise and the excitation.
    noise_rms : float
        The estimator's friction-noise RMS [N] for the row.
    """
    return compare_rows([(cfg, plant, estimator, scenario, seed, noise_rms)])[0]


def compare_rows(tasks: list[tuple]) -> list[dict[str, Any]]:
    """The rows of several runs: :func:`compare_one` of each task, with identical runs made once (the
    seeds of a closed-loop case without random sensor noise) and the open-loop runs that share their
    plant (the ``excitation`` rows of one plant and seed) simulating it once
    (:func:`obsdesign.sim.shared.run_shared`: the same rows, bit for bit).

    Parameters
    ----------
    tasks : list of tuple
        The arguments of :func:`compare_one`, one tuple per row.
    """
    rows, loops = [], []
    for cfg, plant, estimator, scenario, seed, noise_rms in tasks:
        name = estimator if isinstance(estimator, str) else estimator.name
        model = plant.plant_friction.model if plant.plant_friction is not None else "paper"
        row: dict[str, Any] = {"plant": model, "estimator": name, "scenario": scenario, "seed": seed,
                               "friction_rms_error": None, "velocity_rms_error": None, "settling_time": None,
                               "overshoot": None, "tracking_rms_error": None, "friction_noise_rms": noise_rms}
        rows.append(row)
        spec, duration = SCENARIOS[scenario]
        try:
            loops.append(prepare(cfg, spec, plant=plant, estimator=estimator, duration=duration, seed=seed))
        except (ValueError, TypeError, ArithmeticError) as e:
            row["status"] = _failed(e)
            loops.append(None)
    ran = [loop for loop in loops if loop is not None]
    try:
        results = iter(run_shared(ran))
    except (ValueError, TypeError, ArithmeticError):  # one run failed: each on its own, so only its row says so
        results = iter([_run_or_error(loop) for loop in ran])
    for row, loop in zip(rows, loops):
        if loop is None:
            continue
        res = next(results)
        if isinstance(res, Exception):
            row["status"] = _failed(res)
        else:
            _row_metrics(row, res)
    return rows


def _run_or_error(loop):
    try:
        return run(loop)
    except (ValueError, TypeError, ArithmeticError) as e:
        return e


def _failed(error: Exception) -> str:
    return "failed: " + f"{type(error).__name__}: {error}".splitlines()[0]


def _row_metrics(row: dict[str, Any], res) -> None:
    """Fill ``row``'s metrics and status from the run ``res`` of its scenario."""
    scenario = row["scenario"]
    spec, duration = SCENARIOS[scenario]
    keep = res.t >= TRANSIENT
    row["friction_rms_error"] = rms((res.f_hat_filtered - res.f)[keep])
    row["velocity_rms_error"] = rms((res.v_hat - res.v)[keep])
    if scenario == "positioning":
        times, over = [], []
        for t_step, y0, y1 in ((spec.step_up, 0.0, spec.step_size), (spec.step_down, spec.step_size, 0.0)):
            end = spec.step_down if t_step == spec.step_up else duration
            window = (res.t >= t_step) & (res.t < end)
            # the run's own band (obsdesign.loop.bands: 2 counts or 3 x the noise RMS) and the simulator's dwell
            m = step_metrics(res.t[window], res.x[window], t_step=t_step, y0=y0, y1=y1,
                             settle_band=res.metrics["settle_band"], dwell=SETTLE_DWELL)
            times.append(m["settling_time"])
            over.append(m["overshoot"])
        row["settling_time"] = None if any(t is None for t in times) else float(np.mean(times))
        row["overshoot"] = float(max(over))
    if scenario == "tracking":
        row["tracking_rms_error"] = rms(res.e[keep])
    row["status"] = "diverged" if res.metrics["diverged"] else "ok"


@dataclass(frozen=True, eq=False)
class ComparisonResult(ResultDisplay):
    """Rows of a comparison (one per plant, estimator, scenario and seed) and its summary.

    Attributes
    ----------
    rows : list of dict
        Keys :data:`COLUMNS`; None where a metric does not apply (or the run did not settle).
    config : Config
        The design.
    seeds : int
        Seeds per case.
    wall_s : float
        Wall time [s].
    rule : str
        The tuning rule of the baselines (:data:`obsdesign.estimators.RULES`).
    """

    rows: list
    config: Config
    seeds: int
    wall_s: float
    rule: str = "noise"

    _title = "Comparison with standard estimators"

    def _rows(self) -> list[tuple[str, object]]:
        out: list[tuple[str, object]] = [("runs", len(self.rows)), ("seeds", self.seeds), ("wall [s]", self.wall_s)]
        for s in self.summary():
            out.append((f"{s['plant']} / {s['scenario']} / {s['metric']}", f"{s['best']}: {s['verdict']}"))
        return out

    def summary(self) -> list[dict[str, Any]]:
        """See :func:`summarize`."""
        return summarize(self.rows)


def summarize(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per plant, scenario and judged metric: the best estimator and whether it wins.

    Each scenario is judged by the metrics of :data:`JUDGED`. A *win* needs the best estimator's worst seed to beat the runner-up's best seed (the
    spreads over seeds do not overlap) and a mean lower by more than :data:`TIE` (1 %);
    otherwise the verdict is ``"within spread"`` or ``"tie"``. With one seed there is no
    spread and the verdict is ``"single seed"``.

    Parameters
    ----------
    rows : list of dict
        Rows of :func:`compare`.

    Returns
    -------
    list of dict
        ``plant, scenario, metric, best, best_mean, best_range, runner_up, runner_up_mean,
        runner_up_range, verdict``.

    Examples
    --------
    >>> rows = [dict(plant="paper", scenario="excitation", estimator=e, seed=s, friction_rms_error=v, status="ok")
    ...         for e, vals in (("a", (1.0, 1.1)), ("b", (2.0, 2.2))) for s, v in enumerate(vals)]
    >>> summarize(rows)[0]["verdict"], summarize(rows)[0]["best"]
    ('win', 'a')
    """
    out = []
    plants = list(dict.fromkeys(r["plant"] for r in rows))
    scenarios = list(dict.fromkeys(r["scenario"] for r in rows))
    present = {(r["plant"], r["scenario"]) for r in rows}
    cases = [(p, s, m) for p in plants for s in scenarios if (p, s) in present for m in JUDGED[s]]
    for plant, scenario, metric in cases:
        stats = []
        for est in dict.fromkeys(r["estimator"] for r in rows):
            vals = [r[metric] for r in rows if (r["plant"], r["scenario"], r["estimator"]) == (plant, scenario, est)]
            ok = all(r["status"] == "ok" for r in rows
                     if (r["plant"], r["scenario"], r["estimator"]) == (plant, scenario, est))
            vals = [v for v in vals if v is not None and math.isfinite(v)]
            if vals and ok and len(vals) == len([r for r in rows if (r["plant"], r["scenario"], r["estimator"])
                                                 == (plant, scenario, est)]):
                stats.append((float(np.mean(vals)), min(vals), max(vals), est, len(vals)))
        stats.sort()
        entry: dict[str, Any] = {"plant": plant, "scenario": scenario, "metric": metric}
        if not stats:
            entry.update(best=None, verdict="no estimator has a finite value on every seed"
                         + (" (none settled within the band)" if metric == "settling_time" else ""))
            out.append(entry)
            continue
        best = stats[0]
        entry.update(best=best[3], best_mean=best[0], best_range=(best[1], best[2]))
        if len(stats) == 1:
            entry.update(runner_up=None, verdict="only one estimator completed every seed")
        else:
            second = stats[1]
            entry.update(runner_up=second[3], runner_up_mean=second[0], runner_up_range=(second[1], second[2]))
            if best[4] < 2:
                entry["verdict"] = "single seed"
            else:
                close = second[0] - best[0] <= TIE * abs(second[0])
                entry["verdict"] = "tie" if close else ("win" if best[2] < second[1] else "within spread")
        out.append(entry)
    return out


def check_comparison_runs(cases: int, seeds: int) -> int:
    """The runs of a comparison, ``cases x seeds``; ``ValueError`` above :data:`obsdesign.sweeps.plan.MAX_RUNS`.

    Parameters
    ----------
    cases : int
        Plants x estimators x scenarios.
    seeds : int
        Seeds per case.

    Examples
    --------
    >>> check_comparison_runs(60, 2)
    120
    >>> check_comparison_runs(1, 10**12)
    Traceback (most recent call last):
    ...
    ValueError: seeds: expected at most 1e+06 runs (plants x estimators x scenarios x seeds), found 1e+12 (1 cases x 1000000000000 seeds)
    """
    from .sweeps.plan import MAX_RUNS

    runs = cases * seeds
    if runs > MAX_RUNS:
        raise ValueError(f"seeds: expected at most {MAX_RUNS:.0e} runs (plants x estimators x scenarios x seeds), "
                         f"found {float(runs):.3g} ({cases} cases x {seeds} seeds)")
    return runs


def compare(cfg: Config, *, plants=FRICTION_MODELS.names(), estimators=ESTIMATORS.names(),
            scenarios=tuple(SCENARIOS), seeds: int = 2, workers: int | None = None,
            executor=None, rule: str = "noise") -> ComparisonResult:
    """Run every estimator on every plant friction model and scenario.

    Parameters
    ----------
    cfg : Config
        The design (observer, PID, sensor); the plant's friction levels and mass come from it too.
    plants : sequence of str
        Plant friction models (:data:`obsdesign.friction.FRICTION_MODELS`).
    estimators : sequence of str
        Names of :data:`obsdesign.estimators.ESTIMATORS`; baselines are tuned by the fair
        noise rule (:func:`obsdesign.estimators.tune`).
    scenarios : sequence of str
        Keys of :data:`SCENARIOS`.
    seeds : int
        Seeds (noise and excitation) per case, 0 .. seeds-1.
    workers : int, optional
        Processes of the pool (default all cores; 1 runs here).
    executor : optional
        A ``concurrent.futures.Executor`` or ``dask.distributed.Client`` (as :func:`obsdesign.sweep`).
    rule : str
        How the baselines are tuned against the paper's observer, a name of
        :data:`obsdesign.estimators.RULES`: ``noise`` (equal friction-noise RMS, the default),
        ``rate`` (equal slowest error pole): the paper's observer keeps its design; or ``min-error``:
        every estimator, the paper's rho and omega_co included, tuned for the least predicted
        friction-estimate error (docs/tune.md).

    Returns
    -------
    ComparisonResult

    Raises
    ------
    ValueError
        An unknown plant, estimator or scenario name; ``seeds < 1``; more than
        :data:`obsdesign.sweeps.plan.MAX_RUNS` runs (plants x estimators x scenarios x seeds).

    Notes
    -----
    A baseline the rule cannot tune (no sensor noise and no quantization; no knob in its range reaches
    the target) does not stop the comparison: each of its rows has no metrics and the status
    ``"not tuned: <reason>"`` (:data:`NOT_TUNED`, :func:`not_tuned`), and the other estimators run.
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    plants = tuple(FRICTION_MODELS.check(p, kind="plants") for p in plants)
    estimators = tuple(ESTIMATORS.check(e, kind="estimators") for e in estimators)
    scenarios = tuple(check_choice("scenarios", s, tuple(SCENARIOS)) for s in scenarios)
    seeds = check_integer("seeds", seeds, minimum=1)
    rule = check_choice("rule", rule, RULES)
    check_comparison_runs(len(plants) * len(estimators) * len(scenarios), seeds)
    t0 = time.perf_counter()
    pool = Executor(executor, workers)  # first: our own workers start (and warm) while the baselines are tuned
    tuned: dict[str, Any] = {}
    noise: dict[str, float] = {}
    design = {name: cfg for name in estimators}  # the design each estimator's controller is built from
    done: dict[int, dict] = {}
    try:
        eta, band = noise_level(cfg)
        for name in estimators:
            if not ESTIMATORS[name].baseline:  # the paper's observer: run by name, the kernel schedules it
                design[name] = paper_design(cfg, rule)
                tuned[name] = name
                noise[name] = reference_noise_rms(design[name]) if eta > 0 else 0.0
            else:
                try:
                    tuned[name] = tune(name, cfg, rule=rule)
                except ValueError as e:  # a row with its reason, and the others run (issue 17 item 8)
                    tuned[name] = e
                    continue
                noise[name] = friction_noise_rms(tuned[name], eta, band)
        cases = [(p, e, s, seed) for p in plants for e in estimators for s in scenarios for seed in range(seeds)]
        plant_cfgs = {p: plant_config(cfg, p) for p in plants}
        ran_cases = [c for c in cases if not isinstance(tuned[c[1]], Exception)]
        tasks = [(design[e], plant_cfgs[p], tuned[e], s, seed, noise[e]) for p, e, s, seed in ran_cases]
        # the runs that may share work go in one unit (obsdesign.sim.shared): the open-loop runs of a plant
        # and seed (one plant, every estimator), the seeds of a closed-loop case (the same run where the
        # sensor draws no random noise)
        units: dict[tuple, list[int]] = {}
        for i, (p, e, s, seed) in enumerate(ran_cases):
            units.setdefault((p, s, seed) if SCENARIOS[s][0].open_loop else (p, e, s), []).append(i)
        work = [[(i, tasks[i]) for i in unit] for unit in units.values()]
        for batch in pool.map_batches(_run_batch, [work[i:i + 4] for i in range(0, len(work), 4)]):
            done.update(batch)
    except BaseException:
        pool.abort()
        raise
    pool.close()
    ran = iter(done[i] for i in range(len(tasks)))
    rows = [not_tuned_row({"plant": p, "estimator": e, "scenario": s, "seed": seed}, tuned[e])
            if isinstance(tuned[e], Exception) else next(ran) for p, e, s, seed in cases]
    return ComparisonResult(rows=rows, config=cfg, seeds=seeds, wall_s=time.perf_counter() - t0, rule=rule)


def paper_design(cfg: Config, rule: str) -> Config:
    """The paper observer's design under ``rule``: ``cfg`` itself, or for ``min-error`` its rho and omega_co
    tuned by the same objective as the baselines (:func:`obsdesign.design.tune`, ``estimate-error``, the
    compensation gain kept, the certificate required).

    Parameters
    ----------
    cfg : Config
        The design.
    rule : str
        A name of :data:`obsdesign.estimators.RULES`.
    """
    if rule != "min-error":
        return cfg
    from .design.tune import tune as tune_design

    return tune_design(cfg, objective="estimate-error", tune_gain=False).config


def _run_batch(batch: list[list[tuple[int, tuple]]]) -> list[tuple[int, dict]]:
    """The rows of a batch of units (lists of ``(index, task)``), each unit's runs together."""
    return [(i, row) for unit in batch for i, row in zip((i for i, _ in unit), compare_rows([t for _, t in unit]))]
