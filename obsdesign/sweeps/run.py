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

import json
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .._io import atomic_write
from .._validate import check_integer
from ..design.observer import is_stable
from ..loop.scenarios import CHIRP_BAND_LABELS, build_scenario, scenario_spec
from ..params import PARAMETERS, Config
from ..plant_spec import split_plant, with_plant_parameters
from ..sampled.choices import CONTROLLERS
from ..sim.simulate import simulate
from .folder import SweepLock, check_start, read_manifest
from .plan import RunSpec, check_axes, make_plan
from .pool import Executor
from .store import FIXED_COLUMNS, TAIL_COLUMNS, checksum_line, checksums_text, csv_line, csv_text, read_rows, typed_row
from .summary import best_value

__all__ = ["sweep", "SweepResult", "run_one", "metric_columns", "band_column"]

#: Metrics written per run (``sim_wall_s`` is left out: it differs between identical runs).
_METRIC_KEYS = ("rms_error", "max_error", "observer_rms_error_v", "observer_rms_error_f", "diverged")


def band_column(label: str) -> str:
    """Column of a chirp band's RMS error: ``'0.01-0.1 Hz'`` -> ``'rms_error_0.01_0.1Hz'``.

    Parameters
    ----------
    label : str
        A label of :data:`obsdesign.loop.scenarios.CHIRP_BAND_LABELS`.
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
        cols += ["settle_band", "settling_time_1", "settling_time_2", "steady_state_error_1", "steady_state_error_2",
                 "overshoot_1", "overshoot_2", "rise_time_1", "rise_time_2"]
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
        if m["settling_time"]:  # the band the settling times are measured in (obsdesign.loop.bands); empty: did not settle
            row["settle_band"] = m["settle_band"]
        for i, value in enumerate(m["settling_time"], 1):
            row[f"settling_time_{i}"] = value
        for i, value in enumerate(m["steady_state_error"], 1):
            row[f"steady_state_error_{i}"] = value
        for key in ("overshoot", "rise_time"):
            for i, value in enumerate(m.get(key, ()), 1):
                row[f"{key}_{i}"] = value
        for band, value in m.get("rms_error_per_band", {}).items():
            row[band_column(band)] = value
        row["status"] = "diverged" if m["diverged"] else "ok"
        row["error"] = f"divergence: {m['divergence']}" if m["diverged"] else ""  # e.g. 'runaway'
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


def check_controller(spec, controller: str | None) -> None:
    """Refuse a ``controller`` (None: the scenario's own) that is not one or does not fit the scenario ``spec``.

    Raises
    ------
    ValueError
        Naming ``controller``, what the scenario needs and the value found.

    Examples
    --------
    >>> from obsdesign.loop.scenarios import scenario_spec
    >>> check_controller(scenario_spec("positioning"), "open-loop")
    Traceback (most recent call last):
    ...
    ValueError: controller: scenario 'positioning' needs 'pid' or 'pid+observer', found 'open-loop'
    """
    if controller is not None:
        CONTROLLERS.check(controller)
        if spec.open_loop != (controller == "open-loop"):
            expected = "'open-loop'" if spec.open_loop else "'pid' or 'pid+observer'"
            raise ValueError(f"controller: scenario {spec.name!r} needs {expected}, found {controller!r}")


def sweep(cfg: Config, scenario: str, *, vary: dict | None = None, uncertain: dict | None = None,
          samples: int = 1, seed: int = 0, executor=None, workers: int | None = None,
          out_dir: str | os.PathLike | None = None, resume: bool = False, force: bool = False,
          progress: bool | int = False, duration: float | None = None,
          controller: str | None = None, chunk: int = 8) -> SweepResult:
    """Run a design sweep with Monte-Carlo draws.

    A sweep is a grid over the ``vary`` parameters (``numpy.linspace`` of each
    ``(low, high, n)``) times ``samples`` Monte-Carlo draws of the ``uncertain``
    parameters (uniform on ``(low, high)``) per grid point (:mod:`obsdesign.sweeps.plan`).
    Each run is reduced to its metrics, one row of ``out_dir/results.csv``
    (:mod:`obsdesign.sweeps.store`). Every argument is checked before the first run.
    The folder is locked for the whole sweep, and a folder holding results is refused
    unless ``resume`` or ``force`` is given (:mod:`obsdesign.sweeps.folder`).

    Parameters
    ----------
    cfg : Config
        The design every run starts from.
    scenario : str
        Scenario of :func:`obsdesign.simulate`.
    vary : dict, optional
        ``{name: (low, high, n)}``: grid axes over config fields (e.g. ``rho``, ``omega_co``, ``kappa``);
        ``n`` an integer >= 1.
    uncertain : dict, optional
        ``{name: (low, high)}`` with ``low <= high``: uniform draws per grid point (names not in ``vary``).
    samples : int
        Draws per grid point (at least 1).
    seed : int
        Sweep seed (integer >= 0); per-run seeds are spawned from it.
    executor : optional
        A ``dask.distributed.Client`` or a ``concurrent.futures.Executor``; default: a process
        pool with ``workers`` processes (default all cores; ``workers=1`` runs in this process).
    workers : int, optional
        Local processes when no executor is given (at least 1).
    out_dir : path, optional
        Folder for ``results.csv`` and ``sweep.json``; needed for ``resume`` and ``force``.
    resume : bool
        Continue an interrupted sweep in ``out_dir`` (same settings required; every row is checked).
    force : bool
        Replace the results in ``out_dir`` of another sweep.
    progress : bool or int
        ``True``: progress bar with ETA (tqdm); an integer N >= 1: one line on stderr every N
        runs (for logs, where a bar would not render); ``False``: quiet.
    duration : float, optional
        The run length [s] (the scenario's default).
    controller : str, optional
        The controller; it must suit the scenario (``open-loop`` for excitation/constant).
    chunk : int
        Runs per task sent to a worker (at least 1; amortizes the scheduling overhead).

    Returns
    -------
    SweepResult
    """
    samples = check_integer("samples", samples, minimum=1)
    seed = check_integer("seed", seed, minimum=0)
    chunk = check_integer("chunk", chunk, minimum=1)
    if workers is not None:
        workers = check_integer("workers", workers, minimum=1)
    vary, uncertain = check_axes(dict(vary or {}), dict(uncertain or {}), samples)
    if (resume or force) and out_dir is None:
        raise ValueError(f"{'resume' if resume else 'force'}: needs out_dir, the folder of the sweep")
    spec = scenario_spec(scenario)
    check_controller(spec, controller)
    options = {k: v for k, v in (("duration", duration), ("controller", controller)) if v is not None}
    run_cfg = cfg
    run_options = options
    build_scenario(scenario, dt=run_cfg.observer.dt, duration=duration)  # bad scenario or duration: fail now
    plan = make_plan(vary, uncertain, samples, seed)
    columns = [*FIXED_COLUMNS, *vary, *uncertain, *metric_columns(scenario), *TAIL_COLUMNS]
    if out_dir is None:
        return _execute(run_cfg, scenario, run_options, plan, columns, None, {}, executor, workers, chunk, progress)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ValueError(f"out_dir: expected a folder, found the file {str(out)!r}")
    manifest = {"scenario": scenario, "config": cfg.to_toml(), "vary": {k: list(v) for k, v in vary.items()},
                "uncertain": {k: list(v) for k, v in uncertain.items()}, "samples": samples, "seed": seed,
                "options": options, "columns": columns}
    with SweepLock(out):
        check_start(out, resume=resume, force=force)
        results_path, sums_path = out / "results.csv", out / ".checksums"
        done: dict[int, dict] = {}
        if resume and results_path.exists():
            read_manifest(out / "sweep.json", manifest)
            done = read_rows(results_path, columns, plan)
            # Rewrite the completed rows cleanly (drops a torn tail) before appending.
            ordered = [done[r] for r in sorted(done)]
            atomic_write(results_path, csv_text(columns, ordered))
            atomic_write(sums_path, checksums_text(columns, ordered))
        else:
            atomic_write(out / "sweep.json", json.dumps(manifest, indent=1))
            atomic_write(results_path, csv_text(columns, []))
            atomic_write(sums_path, "")
        return _execute(run_cfg, scenario, run_options, plan, columns, out, done, executor, workers, chunk, progress)


def _execute(run_cfg, scenario, run_options, plan, columns, out, done, executor, workers, chunk, progress):
    """Run the runs of ``plan`` not in ``done``, appending rows to ``out`` (if given)."""
    from .._progress import progress_bar

    t0 = time.perf_counter()
    todo = [spec for spec in plan if spec.run not in done]
    rows: dict[int, dict] = dict(done)
    pool = Executor(executor, workers)
    every = 0 if isinstance(progress, bool) else check_integer("progress", progress, minimum=1)
    bar = progress_bar(progress is True, total=len(plan), initial=len(done), desc="sweep", unit="run", smoothing=0.05)
    walls = []
    sink = open(out / "results.csv", "a", encoding="utf-8") if out is not None else None
    sums = open(out / ".checksums", "a", encoding="utf-8") if out is not None else None

    def record(row: dict) -> None:
        walls.append(row.pop("_wall", 0.0))
        rows[row["run"]] = row
        if sink is not None:
            sink.write(csv_line(columns, row))
            sink.flush()  # complete line handed to the OS: survives Ctrl-C or a killed process
            sums.write(checksum_line(columns, row))
            sums.flush()
        bar.update()
        if every and ((len(rows) - len(done)) % every == 0 or len(rows) == len(plan)):
            print(f"sweep: {len(rows)}/{len(plan)} runs, {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)

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
        for fh in (sink, sums):
            if fh is not None:
                fh.close()
    pool.close()
    ordered = [rows[r] for r in sorted(rows)]
    if out is not None:
        atomic_write(out / "results.csv", csv_text(columns, ordered))
        atomic_write(out / ".checksums", checksums_text(columns, ordered))
    wall = time.perf_counter() - t0
    overhead = (wall * max(1, pool.workers) - sum(walls)) / len(todo) if todo else float("nan")
    return SweepResult([typed_row(r, columns) for r in ordered], tuple(columns), out, len(done), wall, overhead)


@dataclass(frozen=True)
class _BatchRunner:
    """A picklable ``batch -> rows`` function for the workers."""

    cfg: Config
    scenario: str
    options: dict

    def __call__(self, batch: list[RunSpec]) -> list[dict]:
        return _run_batch(self.cfg, self.scenario, batch, self.options)

