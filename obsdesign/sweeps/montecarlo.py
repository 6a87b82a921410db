"""A Monte-Carlo robustness study streamed to disk: 10^5 runs in constant memory, resumable.

One design (the config) is simulated ``samples`` times with the ``uncertain`` parameters drawn
uniformly (run ``r``'s draws and noise seed from ``SeedSequence(seed, spawn_key=(r,))``, as in
every sweep: :func:`obsdesign.sweeps.plan.plan_runs`). The runs go to the workers in batches
of ``batch`` runs, named by their first and last run only; a worker returns the batch's metrics
(never a trace), and the batch is written at once to ``DIR/batches/bNNNNNN.npz`` (write to a
temporary file, then rename: a batch file is complete or absent). At most two batches per worker
are in flight. So the memory of the study does not grow with its number of runs, a killed
study keeps every finished batch, and ``resume=True`` runs only the missing ones.

The statistics are reduced at the end from the batch files read one at a time in batch order,
so a resumed study gives the same numbers, to the last bit, as one never interrupted:

* the quantiles of every metric over the runs that ended ``ok`` (:class:`~obsdesign.sweeps.sketch.QuantileSketch`,
  within a relative error ``alpha`` = 1e-3 of ``numpy.quantile(..., method="lower")``),
  mean and standard deviation, and the count of non-finite values (a step that never settles);
* the failure probability against the ``criteria`` (a run fails when it did not end ``ok``, or
  a criterion's metric is non-finite or outside its limit) with its Clopper-Pearson interval
  (``scipy.stats.binomtest(...).proportion_ci(method="exact")``);
* the ``worst`` runs by ``metric`` (runs that failed, diverged or have no value first), with
  their run index, seed and drawn parameters: :func:`replay` runs one again.

Examples
--------
>>> import obsdesign as od, tempfile
>>> from obsdesign.sweeps.montecarlo import monte_carlo, replay
>>> cfg = od.load_preset("vcm")
>>> with tempfile.TemporaryDirectory() as tmp:
...     res = monte_carlo(cfg, "positioning", uncertain={"Cf": (0.3, 0.4)}, samples=6, batch=3,
...                       criteria=["settling_time_1<=0.05"], out_dir=tmp, workers=1, duration=4.0)
...     again = replay(tmp, res.worst[0]["run"])
>>> res.runs, res.counts["ok"], len(res.worst) == 6
(6, 6, True)
>>> again["rms_error"] == res.worst[0]["rms_error"]
True
"""

from __future__ import annotations

import heapq
import json
import math
import os
import re
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_path, atomic_write
from .._validate import check_integer
from ..loop.scenarios import build_scenario, scenario_spec
from ..params import Config
from .criteria import Criterion, numeric_metrics, parse_criterion
from .folder import SweepLock, check_start, read_manifest
from .plan import check_axes, plan_runs
from .pool import Executor
from .run import check_controller, metric_columns, run_one
from .sketch import Moments, QuantileSketch
from .summary import STATUS_VALUES

__all__ = ["monte_carlo", "MonteCarloResult", "Criterion", "parse_criterion", "replay", "QUANTILES", "BATCH_DIR",
           "ALPHA"]

#: Probabilities at which every metric's quantile is reported.
QUANTILES = (0.001, 0.01, 0.05, 0.1, 0.25, 0.5, 0.75, 0.9, 0.95, 0.99, 0.999)
#: Relative error of the reported quantiles (:class:`~obsdesign.sweeps.sketch.QuantileSketch`).
ALPHA = 1e-3
#: Folder of the batch files inside the study's folder.
BATCH_DIR = "batches"
_BATCH_NAME = re.compile(r"b(\d{6})\.npz")


@dataclass(frozen=True, eq=False)
class MonteCarloResult:
    """The statistics of a finished Monte-Carlo study (also written to ``DIR/montecarlo.json``).

    Attributes
    ----------
    runs : int
        Runs in the study.
    counts : dict
        Runs by status (``ok``, ``diverged``, ``failed``).
    criteria : tuple of str
        The pass criteria.
    failures : int
        Runs that failed the criteria (or did not end ``ok``).
    failure_probability : float
        ``failures / runs``.
    interval : tuple of float
        Its Clopper-Pearson interval at ``confidence``.
    confidence : float
    metrics : dict
        Metric -> ``{"quantiles": {q: value}, "mean", "std", "count", "nonfinite", "min", "max"}``
        over the runs that ended ``ok``.
    worst : list of dict
        The worst runs by ``metric``, worst first: ``run``, ``seed``, ``status``, the drawn
        parameters, every metric (None where absent) and ``error``.
    metric : str
    alpha : float
        Relative error of the quantiles.
    resumed_runs : int
        Runs found finished in the folder when the study started.
    wall_s : float
        Wall time of this call [s].
    out_dir : Path
    """

    runs: int
    counts: dict
    criteria: tuple
    failures: int
    failure_probability: float
    interval: tuple
    confidence: float
    metrics: dict
    worst: list
    metric: str
    alpha: float
    resumed_runs: int
    wall_s: float
    out_dir: Path

    def to_dict(self) -> dict[str, Any]:
        """The JSON object of ``montecarlo.json`` (no wall time or resume count: equal for equal studies)."""
        return {"runs": self.runs, **{k: self.counts[k] for k in STATUS_VALUES}, "criteria": list(self.criteria),
                "failures": self.failures, "failure_probability": self.failure_probability,
                "interval": list(self.interval), "confidence": self.confidence, "interval_method": "clopper-pearson",
                "quantile_relative_error": self.alpha, "metric": self.metric, "metrics": self.metrics,
                "worst": self.worst}


@dataclass(frozen=True)
class _Batch:
    """A picklable ``(index, start, stop) -> arrays`` function for the workers."""

    cfg: Config
    scenario: str
    options: dict
    uncertain: dict
    samples: int
    seed: int
    columns: tuple

    def __call__(self, job: tuple[int, int, int]) -> tuple[int, dict]:
        index, start, stop = job
        specs = plan_runs({}, self.uncertain, self.samples, self.seed, start, stop)
        rows = [run_one(self.cfg, self.scenario, spec, self.options) for spec in specs]
        return index, _arrays(rows, specs, self.uncertain, self.columns)


def _value(v) -> float:
    return math.nan if v is None or v == "" else float(v)


def _arrays(rows: list[dict], specs, uncertain: dict, columns: tuple) -> dict[str, np.ndarray]:
    return {
        "run": np.array([s.run for s in specs], dtype=np.int64),
        "seed": np.array([s.seed for s in specs], dtype=np.int64),
        "status": np.array([STATUS_VALUES.index(r["status"]) for r in rows], dtype=np.int8),
        "params": np.array([[s.params[n] for n in uncertain] for s in specs], dtype=float).reshape(len(specs), -1),
        "metrics": np.array([[_value(r.get(c)) for c in columns] for r in rows], dtype=float).reshape(len(rows), -1),
        "error": np.array([r["error"] for r in rows], dtype=str),
    }


def _write_batch(path: Path, arrays: dict) -> None:
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        np.savez(fh, **arrays)


def _read_batch(path: Path, start: int, stop: int, uncertain: dict, samples: int, seed: int,
                n_metrics: int) -> dict[str, np.ndarray]:
    """A batch file, checked against the plan (``ValueError`` naming it otherwise)."""
    hint = "delete it to recompute the batch"
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in ("run", "seed", "status", "params", "metrics", "error")}
    except (OSError, ValueError, KeyError, EOFError) as e:
        raise ValueError(f"resume: {str(path)!r} is not a batch file of this study ({type(e).__name__}); {hint}") from None
    n = stop - start
    if not np.array_equal(arrays["run"], np.arange(start, stop)) or arrays["metrics"].shape != (n, n_metrics):
        raise ValueError(f"resume: {str(path)!r} does not hold runs {start} to {stop - 1} with {n_metrics} metrics; {hint}")
    specs = plan_runs({}, uncertain, samples, seed, start, stop)
    planned = _arrays([{"status": "ok", "error": ""}] * n, specs, uncertain, ())
    for key in ("seed", "params"):
        if not np.array_equal(arrays[key], planned[key]):
            raise ValueError(f"resume: {str(path)!r}: its {key} differ from the planned ones; {hint}")
    if arrays["status"].min(initial=0) < 0 or arrays["status"].max(initial=0) >= len(STATUS_VALUES):
        raise ValueError(f"resume: {str(path)!r}: a status code outside 0 to {len(STATUS_VALUES) - 1}; {hint}")
    return arrays


def _batch_path(out: Path, index: int) -> Path:
    return out / BATCH_DIR / f"b{index:06d}.npz"


def monte_carlo(cfg: Config, scenario: str, *, uncertain: dict, samples: int, out_dir: str | os.PathLike,
                criteria: tuple | list = (), seed: int = 0, metric: str = "rms_error", worst: int = 10,
                confidence: float = 0.95, quantiles: tuple = QUANTILES, batch: int = 200, executor=None,
                workers: int | None = None,
                resume: bool = False, force: bool = False, progress: bool | int = False,
                duration: float | None = None, controller: str | None = None) -> MonteCarloResult:
    """Run a Monte-Carlo study of one design, streamed to ``out_dir`` (see the module notes).

    Parameters
    ----------
    cfg : Config
        The design.
    scenario : str
        Scenario of :func:`obsdesign.simulate`.
    uncertain : dict
        ``{name: (low, high)}``: uniform draws (config fields, or ``plant.NAME`` for the simulated plant only).
    samples : int
        Runs (at least 1; at most :data:`obsdesign.sweeps.plan.MAX_RUNS`).
    out_dir : path
        Folder of ``sweep.json``, ``batches/`` and ``montecarlo.json``.
    criteria : sequence of str
        Pass criteria ``'NAME<=LIMIT'`` / ``'NAME>=LIMIT'`` on the metrics of a run.
    seed : int
        Study seed (integer >= 0).
    metric : str
        The metric that ranks the worst runs.
    worst : int
        Worst runs kept (at least 1).
    confidence : float
        Confidence level of the failure probability's interval (``0 < confidence < 1``).
    quantiles : sequence of float
        Probabilities of the reported quantiles (each in [0, 1]; default :data:`QUANTILES`).
    batch : int
        Runs per batch (at least 1): per task sent to a worker and per file.
    executor : optional
        A ``dask.distributed.Client`` or a ``concurrent.futures.Executor``; default our own pool.
    workers : int, optional
        Processes of our own pool (default all cores; 1 runs in this process).
    resume : bool
        Continue the study in ``out_dir`` (same settings; every batch file checked).
    force : bool
        Replace the results in ``out_dir``.
    progress : bool or int
        ``True``: a tqdm bar with an ETA on stderr; an integer N: one line every N runs; ``False``: quiet.
    duration : float, optional
        Run length [s] (the scenario's default).
    controller : str, optional
        The controller (it must suit the scenario).

    Returns
    -------
    MonteCarloResult
    """
    t0 = time.perf_counter()
    samples = check_integer("samples", samples, minimum=1)
    seed = check_integer("seed", seed, minimum=0)
    batch = check_integer("batch", batch, minimum=1)
    worst = check_integer("worst", worst, minimum=1)
    if workers is not None:
        workers = check_integer("workers", workers, minimum=1)
    if isinstance(confidence, bool) or not isinstance(confidence, (int, float)) or not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence: expected a number in (0, 1), found {confidence!r}")
    quantiles = tuple(quantiles)
    bad = [q for q in quantiles if isinstance(q, bool) or not isinstance(q, (int, float)) or not 0.0 <= q <= 1.0]
    if bad or not quantiles:
        raise ValueError(f"quantiles: expected probabilities in [0, 1], found {bad[0] if bad else 'none'!r}")
    _, uncertain = check_axes({}, dict(uncertain or {}), samples)
    spec = scenario_spec(scenario)
    columns = tuple(metric_columns(scenario))
    if metric not in numeric_metrics(scenario):
        raise ValueError(f"metric: expected one of {', '.join(numeric_metrics(scenario))}, found {metric!r}")
    crit = tuple(parse_criterion(c, scenario) for c in criteria)
    check_controller(spec, controller)
    options = {k: v for k, v in (("duration", duration), ("controller", controller)) if v is not None}
    build_scenario(scenario, dt=cfg.observer.dt, duration=duration)  # bad scenario or duration: fail now
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ValueError(f"out_dir: expected a folder, found the file {str(out)!r}")
    manifest = {"scenario": scenario, "config": cfg.to_toml(), "vary": {},
                "uncertain": {k: list(v) for k, v in uncertain.items()}, "samples": samples, "seed": seed,
                "options": options, "columns": list(columns), "mode": "monte-carlo", "batch": batch}
    n_batches = -(-samples // batch)
    with SweepLock(out):
        check_start(out, resume=resume, force=force)
        folder = out / BATCH_DIR
        if resume:
            read_manifest(out / "sweep.json", manifest)
        else:
            if folder.is_dir():
                for old in folder.glob("b*.npz"):
                    old.unlink()
            (out / "montecarlo.json").unlink(missing_ok=True)
            atomic_write(out / "sweep.json", json.dumps(manifest, indent=1))
        folder.mkdir(exist_ok=True)
        for stale in folder.glob(".b*.tmp"):  # a batch being written when the study was killed
            stale.unlink()
        found = {int(m.group(1)) for p in folder.iterdir() if (m := _BATCH_NAME.fullmatch(p.name))}
        if any(i >= n_batches for i in found):
            raise ValueError(f"resume: {str(folder)!r} holds batch files beyond the study's {n_batches}; "
                             "start again with --force")
        bounds = [(i, i * batch, min(samples, (i + 1) * batch)) for i in range(n_batches)]
        for i in sorted(found):  # checked before any run
            _read_batch(_batch_path(out, i), bounds[i][1], bounds[i][2], uncertain, samples, seed, len(columns))
        resumed = sum(stop - start for i, start, stop in bounds if i in found)
        _run_batches(_Batch(cfg, scenario, options, uncertain, samples, seed, columns),
                     [b for b in bounds if b[0] not in found], out, samples, resumed, executor, workers, progress)
        stats = _reduce(out, bounds, uncertain, samples, seed, columns, crit, metric, worst, confidence,
                        quantiles)
        result = MonteCarloResult(**stats, resumed_runs=resumed, wall_s=time.perf_counter() - t0, out_dir=out)
        atomic_write(out / "montecarlo.json", json.dumps(result.to_dict(), indent=1))
    return result


def _run_batches(runner: _Batch, todo: list, out: Path, total: int, done: int, executor, workers, progress) -> None:
    from .._progress import progress_bar

    every = 0 if isinstance(progress, bool) else check_integer("progress", progress, minimum=1)
    if not todo:
        return
    pool = Executor(executor, workers)
    bar = progress_bar(progress is True, total=total, initial=done, desc="monte carlo", unit="run", smoothing=0.1)
    t0, count, last = time.perf_counter(), done, done
    try:
        for index, arrays in pool.map_batches(runner, todo, window=2 * pool.workers):
            _write_batch(_batch_path(out, index), arrays)
            n = len(arrays["run"])
            count += n
            bar.update(n)
            if every and (count - last >= every or count == total):
                last = count
                rate = (count - done) / max(time.perf_counter() - t0, 1e-9)
                print(f"monte carlo: {count}/{total} runs, {time.perf_counter() - t0:.1f} s, "
                      f"ETA {(total - count) / rate:.0f} s", file=sys.stderr, flush=True)
    except BaseException:
        pool.abort()
        raise
    finally:
        bar.close()
    pool.close()


def _reduce(out: Path, bounds: list, uncertain: dict, samples: int, seed: int, columns: tuple, criteria: tuple,
            metric: str, keep: int, confidence: float, quantiles: tuple) -> dict[str, Any]:
    """The statistics of the batch files, read one at a time in batch order."""
    from scipy.stats import binomtest

    names = [c for c in columns if c not in ("stable", "diverged")]
    sketches = {c: QuantileSketch(ALPHA) for c in names}
    moments = {c: Moments() for c in names}
    counts = dict.fromkeys(STATUS_VALUES, 0)
    failures = 0
    heap: list = []
    col = {c: k for k, c in enumerate(columns)}
    ok_code = STATUS_VALUES.index("ok")
    for i, start, stop in bounds:
        a = _read_batch(_batch_path(out, i), start, stop, uncertain, samples, seed, len(columns))
        status, values = a["status"], a["metrics"]
        ok = status == ok_code
        for s, name in enumerate(STATUS_VALUES):
            counts[name] += int(np.count_nonzero(status == s))
        for c in names:
            sketches[c].add(values[ok, col[c]])
            moments[c].add(values[ok, col[c]])
        passed = ok.copy()
        for cr in criteria:
            passed &= cr.passes(values[:, col[cr.metric]])
        failures += int(np.count_nonzero(~passed))
        key = np.where(ok & np.isfinite(values[:, col[metric]]), values[:, col[metric]], np.inf)
        for j in np.argsort(-key, kind="stable")[:keep]:
            item = (float(key[j]), -int(a["run"][j]))
            if len(heap) < keep:
                heapq.heappush(heap, (*item, _worst_entry(a, j, uncertain, columns)))
            elif item > heap[0][:2]:
                heapq.heapreplace(heap, (*item, _worst_entry(a, j, uncertain, columns)))
    runs = bounds[-1][2] if bounds else 0
    ci = binomtest(failures, runs).proportion_ci(confidence_level=confidence, method="exact")
    stats = {}
    for c in names:
        sk, mo = sketches[c], moments[c]
        stats[c] = {"quantiles": {f"{q:g}": _json(sk.quantile(q)) for q in quantiles}, "mean": _json(mo.mean if mo.count else math.nan),
                    "std": _json(mo.std), "count": sk.count, "nonfinite": sk.nonfinite,
                    "min": _json(sk.min), "max": _json(sk.max)}
    worst = [entry for *_, entry in sorted(heap, key=lambda h: h[:2], reverse=True)]
    return {"runs": runs, "counts": counts, "criteria": tuple(str(c) for c in criteria), "failures": failures,
            "failure_probability": failures / runs, "interval": (float(ci.low), float(ci.high)),
            "confidence": confidence, "metrics": stats, "worst": worst, "metric": metric, "alpha": ALPHA}


def _json(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def _worst_entry(a: dict, j: int, uncertain: dict, columns: tuple) -> dict[str, Any]:
    entry: dict[str, Any] = {"run": int(a["run"][j]), "seed": int(a["seed"][j]),
                             "status": STATUS_VALUES[int(a["status"][j])]}
    entry.update({name: float(a["params"][j, k]) for k, name in enumerate(uncertain)})
    for k, c in enumerate(columns):
        v = float(a["metrics"][j, k])
        entry[c] = bool(v) if c in ("stable", "diverged") and math.isfinite(v) else _json(v)
    entry["error"] = str(a["error"][j])
    return entry


def replay(out_dir: str | os.PathLike, run: int) -> dict[str, Any]:
    """Simulate run ``run`` of the study in ``out_dir`` again (a worst case, say) and return its row.

    The row is that of :func:`obsdesign.sweeps.run.run_one`: the same draws, seed and metrics
    as in the study.

    Parameters
    ----------
    out_dir : path
        The study's folder (its ``sweep.json``).
    run : int
        The run index.
    """
    from ..params import Config as _Config

    path = Path(out_dir) / "sweep.json"
    try:
        manifest = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"out_dir: cannot read {str(path)!r} ({type(e).__name__}); expected the folder of a study") from None
    if not isinstance(manifest, dict) or manifest.get("mode") != "monte-carlo":
        raise ValueError(f"out_dir: {str(path)!r} is not the manifest of a Monte-Carlo study")
    samples = manifest["samples"]
    run = check_integer("run", run, minimum=0)
    if run >= samples:
        raise ValueError(f"run: expected 0 to {samples - 1}, found {run}")
    uncertain = {k: tuple(v) for k, v in manifest["uncertain"].items()}
    cfg = _Config.from_toml(manifest["config"])
    (spec,) = plan_runs({}, uncertain, samples, manifest["seed"], run, run + 1)
    row = run_one(cfg, manifest["scenario"], spec, manifest["options"])
    row.pop("_wall", None)
    return row
