"""Running a sweep: one run per plan entry, in this process, a process pool or on Dask.

Examples
--------
>>> import obsdesign as od, tempfile
>>> with tempfile.TemporaryDirectory() as tmp:
...     res = od.sweep(od.load_preset("vcm"), "positioning", vary={"rho": (2.0, 4.0, 2)},
...                    uncertain={"Cf": (0.3, 0.4)}, samples=2, out_dir=tmp, workers=1)
...     [row["status"] for row in res.rows], sorted({row["rho"] for row in res.rows})
(['ok', 'ok', 'ok', 'ok'], [2.0, 4.0])
"""

from __future__ import annotations

import concurrent.futures
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._io import atomic_write
from .._validate import check_integer
from ..design.observer import is_stable
from ..params import PARAMETERS, Config
from ..plant_spec import split_plant, with_plant_parameters
from ..sim.scenarios import CHIRP_BAND_LABELS, build_scenario
from ..sim.simulate import simulate
from .plan import RunSpec, check_names, make_plan
from .store import FIXED_COLUMNS, TAIL_COLUMNS, csv_line, csv_text, read_rows, typed_row
from .summary import best_value

__all__ = ["sweep", "SweepResult", "run_one", "metric_columns", "band_column"]

#: Metrics written per run (``sim_wall_s`` is left out: it differs between identical runs).
_METRIC_KEYS = ("rms_error", "max_error", "observer_rms_error_v", "observer_rms_error_f", "diverged")


def band_column(label: str) -> str:
    """Column of a chirp band's RMS error: ``'0.01-0.1 Hz'`` -> ``'rms_error_0.01_0.1Hz'``.

    Parameters
    ----------
    label : str
        A label of :data:`obsdesign.sim.scenarios.CHIRP_BAND_LABELS`.
    """
    return "rms_error_" + label.replace(" ", "").replace("-", "_")


def metric_columns(scenario: str) -> list[str]:
    """The metric columns a run of this scenario produces (as :func:`run_one` names them).

    Parameters
    ----------
    scenario : str
        Scenario name.
    """
    cols = ["stable", *_METRIC_KEYS]
    if scenario == "positioning":
        cols += ["settling_time_1", "settling_time_2", "steady_state_error_1", "steady_state_error_2"]
    if scenario == "tracking":
        cols += [band_column(label) for label, _, _ in CHIRP_BAND_LABELS]
    return cols


def run_one(cfg: Config, scenario: str, spec: RunSpec, options: dict) -> dict:
    """Simulate one run and reduce it to a row (never raises for a bad draw).

    Parameters
    ----------
    cfg : Config
        The sweep's config.
    scenario : str
        Scenario name.
    spec : RunSpec
        The run.
    options : dict
        Keyword options of :func:`obsdesign.simulate`.
    """
    row: dict[str, Any] = {"run": spec.run, "grid_point": spec.grid_point, "sample": spec.sample, "seed": spec.seed,
                           **spec.params}
    try:
        design, plant = split_plant(spec.params)  # "plant.NAME": the simulated plant only (model mismatch)
        cfg_r = cfg.override(**design)
        row["stable"] = is_stable(cfg_r)
        if plant:
            options = dict(options, plant=with_plant_parameters(cfg_r, plant, PARAMETERS))
        res = simulate(cfg_r, scenario, seed=spec.seed, keep_trace=False, **options)
        m = res.metrics
        row.update({key: m[key] for key in _METRIC_KEYS})
        for i, value in enumerate(m["settling_time"], 1):
            row[f"settling_time_{i}"] = value
        for i, value in enumerate(m["steady_state_error"], 1):
            row[f"steady_state_error_{i}"] = value
        for band, value in m.get("rms_error_per_band", {}).items():
            row[band_column(band)] = value
        row["status"] = "diverged" if m["diverged"] else "ok"
        row["error"] = ""
        row["_wall"] = m["sim_wall_s"]
    except (ValueError, TypeError, ArithmeticError) as e:
        row["status"] = "failed"
        row["error"] = f"{type(e).__name__}: {e}".splitlines()[0]
    return row


def _run_batch(cfg, scenario, batch, options):
    return [run_one(cfg, scenario, spec, options) for spec in batch]


@dataclass(frozen=True, eq=False)
class SweepResult:
    """The rows of a finished sweep and where they were written.

    Attributes
    ----------
    rows : list of dict
        One per run, in run order (as in ``results.csv``).
    columns : tuple of str
    out_dir : Path or None
    skipped : int
        Runs taken from an earlier, interrupted sweep (``resume``).
    wall_s : float
        Wall time of this call.
    run_overhead_s : float
        Wall time per run beyond the simulation kernels (times the number of workers),
        including pool start-up; the benchmark measures it in steady state.
    """

    rows: list
    columns: tuple
    out_dir: Path | None
    skipped: int
    wall_s: float
    run_overhead_s: float = field(default=float("nan"))

    def best(self, parameter: str, metric: str = "rms_error") -> tuple[float, float]:
        """The value of a varied ``parameter`` with the lowest mean ``metric`` over its runs
        (runs that failed or diverged count as infinitely bad)."""
        return best_value(self.rows, parameter, metric)


class _Executor:
    """One adapter over the ways to run batches: in this process, a process pool of our own,
    a ``concurrent.futures.Executor`` or a ``dask.distributed.Client`` given by the caller."""

    def __init__(self, executor, workers: int | None) -> None:
        self.owned = executor is None
        if executor is None:
            n = workers if workers is not None else (os.cpu_count() or 1)
            if n > 1:
                import multiprocessing

                executor = concurrent.futures.ProcessPoolExecutor(
                    max_workers=n, mp_context=multiprocessing.get_context("spawn"))
            self.workers = n
        else:
            self.workers = self._count_workers(executor)
        self.pool = executor
        self.dask = executor is not None and hasattr(executor, "scheduler_info") and hasattr(executor, "gather")
        self.futures: list = []

    @staticmethod
    def _count_workers(executor) -> int:
        if hasattr(executor, "nthreads"):  # dask.distributed.Client
            return max(1, sum(executor.nthreads().values()))
        return max(1, getattr(executor, "_max_workers", 1))

    def map_batches(self, fn, batches):
        """Results of ``fn(batch)`` as they complete (in this process: in order)."""
        if self.pool is None:
            for batch in batches:
                yield fn(batch)
            return
        self.futures = [self.pool.submit(fn, batch) for batch in batches]
        if self.dask:
            from distributed import as_completed
        else:
            as_completed = concurrent.futures.as_completed
        for fut in as_completed(self.futures):
            yield fut.result()

    def abort(self) -> None:
        if self.pool is None:
            return
        if self.owned:
            self.pool.shutdown(wait=False, cancel_futures=True)
        elif self.dask:
            self.pool.cancel(self.futures)
        else:
            for fut in self.futures:
                fut.cancel()

    def close(self) -> None:
        if self.owned and self.pool is not None:
            self.pool.shutdown()


def sweep(cfg: Config, scenario: str, *, vary: dict | None = None, uncertain: dict | None = None,
          samples: int = 1, seed: int = 0, executor=None, workers: int | None = None,
          out_dir: str | os.PathLike | None = None, resume: bool = False, progress: bool = False,
          duration: float | None = None, variant: str | None = None, controller: str | None = None,
          chunk: int = 8) -> SweepResult:
    """Run a design sweep with Monte-Carlo draws.

    A sweep is a grid over the ``vary`` parameters (``numpy.linspace`` of each
    ``(low, high, n)``) times ``samples`` Monte-Carlo draws of the ``uncertain``
    parameters (uniform on ``(low, high)``) per grid point (:mod:`obsdesign.sweeps.plan`).
    Each run is reduced to its metrics, one row of ``out_dir/results.csv``
    (:mod:`obsdesign.sweeps.store`).

    Parameters
    ----------
    cfg : Config
    scenario : str
        Scenario of :func:`obsdesign.simulate`.
    vary : dict, optional
        ``{name: (low, high, n)}``: grid axes over config fields (e.g. ``rho``, ``omega_co``, ``kappa``).
    uncertain : dict, optional
        ``{name: (low, high)}``: uniform draws per grid point.
    samples : int
        Draws per grid point (at least 1).
    seed : int
        Sweep seed; per-run seeds are spawned from it.
    executor : optional
        A ``dask.distributed.Client`` or a ``concurrent.futures.Executor``; default: a process
        pool with ``workers`` processes (default all cores; ``workers=1`` runs in this process).
    workers : int, optional
        Local processes when no executor is given.
    out_dir : path, optional
        Folder for ``results.csv`` and ``sweep.json``; needed for ``resume``.
    resume : bool
        Continue an interrupted sweep in ``out_dir`` (same settings required).
    progress : bool
        Progress bar with ETA (tqdm).
    duration, variant, controller : optional
        The run length [s], the model variant (applied to the config) and the controller.
    chunk : int
        Runs per task sent to a worker (amortizes the scheduling overhead).

    Returns
    -------
    SweepResult
    """
    from tqdm import tqdm

    vary = check_names("vary", dict(vary or {}))
    uncertain = check_names("uncertain", dict(uncertain or {}))
    samples = check_integer("samples", samples, minimum=1)
    seed = check_integer("seed", seed, minimum=0)
    if resume and out_dir is None:
        raise ValueError("resume: needs out_dir, the folder of the interrupted sweep")
    options = {k: v for k, v in (("duration", duration), ("variant", variant), ("controller", controller))
               if v is not None}
    run_cfg = cfg.override(variant=variant)
    run_options = {k: v for k, v in options.items() if k != "variant"}
    build_scenario(scenario, dt=run_cfg.observer.dt, duration=duration)  # bad scenario or duration: fail now
    plan = make_plan(vary, uncertain, samples, seed)
    columns = [*FIXED_COLUMNS, *vary, *uncertain, *metric_columns(scenario), *TAIL_COLUMNS]
    t0 = time.perf_counter()

    done: dict[int, dict] = {}
    results_path = None
    if out_dir is not None:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        results_path = out / "results.csv"
        manifest = {"scenario": scenario, "config": cfg.to_toml(), "vary": {k: list(v) for k, v in vary.items()},
                    "uncertain": {k: list(v) for k, v in uncertain.items()}, "samples": samples, "seed": seed,
                    "options": options, "columns": columns}
        manifest_path = out / "sweep.json"
        if resume and results_path.exists():
            old = json.loads(manifest_path.read_text()) if manifest_path.exists() else None
            if old != manifest:
                raise ValueError(f"resume: the sweep in {str(out)!r} was started with different settings")
            done = read_rows(results_path, columns)
            # Rewrite the completed rows cleanly (drops a torn tail) before appending.
            atomic_write(results_path, csv_text(columns, [done[r] for r in sorted(done)]))
        else:
            atomic_write(manifest_path, json.dumps(manifest, indent=1))
            atomic_write(results_path, csv_text(columns, []))
    todo = [spec for spec in plan if spec.run not in done]
    rows: dict[int, dict] = dict(done)
    pool = _Executor(executor, workers)
    bar = tqdm(total=len(plan), initial=len(done), desc="sweep", unit="run", disable=not progress, smoothing=0.05)
    walls = []
    sink = open(results_path, "a", encoding="utf-8") if results_path is not None else None

    def record(row: dict) -> None:
        walls.append(row.pop("_wall", 0.0))
        rows[row["run"]] = row
        if sink is not None:
            sink.write(csv_line(columns, row))
            sink.flush()  # complete line handed to the OS: survives Ctrl-C or a killed process
        bar.update()

    try:
        batches = [todo[i:i + chunk] for i in range(0, len(todo), chunk)] if pool.pool is not None else \
            [[spec] for spec in todo]
        for batch_rows in pool.map_batches(_BatchRunner(run_cfg, scenario, run_options), batches):
            for row in batch_rows:
                record(row)
    except BaseException:
        pool.abort()
        raise
    finally:
        bar.close()
        if sink is not None:
            sink.close()
    pool.close()
    ordered = [rows[r] for r in sorted(rows)]
    if results_path is not None:
        atomic_write(results_path, csv_text(columns, ordered))
    wall = time.perf_counter() - t0
    overhead = (wall * max(1, pool.workers) - sum(walls)) / len(todo) if todo else float("nan")
    return SweepResult([typed_row(r, columns) for r in ordered], tuple(columns),
                       Path(out_dir) if out_dir is not None else None, len(done), wall, overhead)


@dataclass(frozen=True)
class _BatchRunner:
    """A picklable ``batch -> rows`` function for the workers."""

    cfg: Config
    scenario: str
    options: dict

    def __call__(self, batch: list[RunSpec]) -> list[dict]:
        return _run_batch(self.cfg, self.scenario, batch, self.options)

