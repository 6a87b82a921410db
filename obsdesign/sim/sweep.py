"""Design sweeps and Monte-Carlo robustness, locally or on a Dask cluster.

A sweep is a grid over the ``vary`` parameters (``numpy.linspace`` of each
``(low, high, n)``) times ``samples`` Monte-Carlo draws of the ``uncertain``
parameters (uniform on ``(low, high)``) per grid point. Run ``r`` gets its own
``numpy.random.SeedSequence`` (the sweep seed's ``spawn``); the draws and the
simulation's noise seed come from it, so a run's numbers do not depend on where
or in which order it is executed.

Each run is reduced to its metrics. ``DIR/results.csv`` gets one row per run as
it finishes (one complete line per ``write``, flushed); at the end the
file is rewritten in run order. ``resume=True`` reads the rows already there
(dropping a torn last line), skips those runs and finishes the rest, so an
interrupted sweep ends with the same file as an uninterrupted one.

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
import csv
import io
import itertools
import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._io import atomic_write
from ..params import _FIELD_SECTION, Config

__all__ = ["sweep", "SweepResult", "parse_vary", "parse_uncertain", "run_one"]

#: Metrics written per run (``sim_wall_s`` is left out: it differs between identical runs).
_METRIC_KEYS = ("rms_error", "max_error", "observer_rms_error_v", "observer_rms_error_f", "diverged")
_FIXED_COLUMNS = ("run", "grid_point", "sample", "seed")
_TAIL_COLUMNS = ("status", "error")


def _check_names(kind: str, spec: dict) -> dict[str, tuple]:
    if not isinstance(spec, dict):
        raise TypeError(f"{kind}: expected a dict of parameter name -> bounds, found {type(spec).__name__}")
    for name in spec:
        if name not in _FIELD_SECTION or name == "variant":
            raise ValueError(f"{kind}: unknown parameter {name!r}; expected a numeric config field such as "
                             "rho, omega_co, kappa, Cf, sigma, m")
    return spec


def _number(text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{what}: expected a number, found {text!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{what}: expected a finite number, found {text!r}")
    return value


def _split(item: str, flag: str, syntax: str, n_parts: int) -> tuple[str, list[str]]:
    name, sep, rest = item.partition("=")
    parts = rest.split(":")
    if not sep or not name or len(parts) != n_parts:
        raise ValueError(f"{flag}: expected {syntax}, found {item!r}")
    return name, parts


def parse_vary(items: list[str]) -> dict[str, tuple[float, float, int]]:
    """Parse ``NAME=LO:HI:N`` items.

    >>> parse_vary(["rho=1.5:4:6"])
    {'rho': (1.5, 4.0, 6)}
    >>> parse_vary(["rho=1.5:4"])
    Traceback (most recent call last):
    ...
    ValueError: --vary: expected NAME=LO:HI:N, found 'rho=1.5:4'
    """
    out = {}
    for item in items:
        name, parts = _split(item, "--vary", "NAME=LO:HI:N", 3)
        lo, hi = (_number(p, f"--vary {name}") for p in parts[:2])
        n = int(parts[2]) if parts[2].strip().isdigit() else 0
        if n < 1:
            raise ValueError(f"--vary {name}: expected an integer N >= 1, found {parts[2]!r}")
        out[name] = (lo, hi, n)
    return _check_names("--vary", out)


def parse_uncertain(items: list[str]) -> dict[str, tuple[float, float]]:
    """Parse ``NAME=LO:HI`` items.

    >>> parse_uncertain(["Cf=0.3:0.4"])
    {'Cf': (0.3, 0.4)}
    """
    out = {}
    for item in items:
        name, parts = _split(item, "--uncertain", "NAME=LO:HI", 2)
        lo, hi = (_number(p, f"--uncertain {name}") for p in parts)
        if hi < lo:
            raise ValueError(f"--uncertain {name}: expected LO <= HI, found {lo:g} > {hi:g}")
        out[name] = (lo, hi)
    return _check_names("--uncertain", out)


@dataclass(frozen=True)
class RunSpec:
    """One run: its index and the parameter values to apply."""

    run: int
    grid_point: int
    sample: int
    seed: int
    params: dict


def _plan(vary, uncertain, samples: int, seed: int) -> list[RunSpec]:
    axes = [np.linspace(lo, hi, n) for lo, hi, n in vary.values()]
    grid = list(itertools.product(*axes)) if axes else [()]
    n_runs = len(grid) * samples
    children = np.random.SeedSequence(seed).spawn(n_runs)
    plan = []
    for g, point in enumerate(grid):
        for j in range(samples):
            r = g * samples + j
            rng = np.random.default_rng(children[r])
            params = {name: float(v) for name, v in zip(vary, point)}
            params.update({name: float(rng.uniform(lo, hi)) for name, (lo, hi) in uncertain.items()})
            plan.append(RunSpec(r, g, j, int(children[r].generate_state(1, np.uint32)[0]), params))
    return plan


def run_one(cfg: Config, scenario: str, spec: RunSpec, options: dict) -> dict:
    """Simulate one run and reduce it to a row (never raises for a bad draw)."""
    from ..design.observer import is_stable
    from .simulate import simulate

    row: dict[str, Any] = {"run": spec.run, "grid_point": spec.grid_point, "sample": spec.sample, "seed": spec.seed,
                           **spec.params}
    try:
        cfg_r = cfg.override(**spec.params)
        row["stable"] = is_stable(cfg_r)
        res = simulate(cfg_r, scenario, seed=spec.seed, keep_trace=False, **options)
        m = res.metrics
        row.update({key: m[key] for key in _METRIC_KEYS})
        for i, value in enumerate(m["settling_time"], 1):
            row[f"settling_time_{i}"] = value
        for i, value in enumerate(m["steady_state_error"], 1):
            row[f"steady_state_error_{i}"] = value
        for band, value in m.get("rms_error_per_band", {}).items():
            row[_band_column(band)] = value
        row["status"] = "diverged" if m["diverged"] else "ok"
        row["error"] = ""
        row["_wall"] = m["sim_wall_s"]
    except (ValueError, TypeError, ArithmeticError) as e:
        row["status"] = "failed"
        row["error"] = f"{type(e).__name__}: {e}".splitlines()[0]
    return row


def _band_column(label: str) -> str:
    """Column of a chirp band's RMS error: ``'0.01-0.1 Hz'`` -> ``'rms_error_0.01_0.1Hz'``."""
    return "rms_error_" + label.replace(" ", "").replace("-", "_")


def _metric_columns(scenario: str) -> list[str]:
    """The metric columns a run of this scenario produces (as :func:`run_one` names them)."""
    cols = ["stable", *_METRIC_KEYS]
    if scenario == "positioning":
        cols += ["settling_time_1", "settling_time_2", "steady_state_error_1", "steady_state_error_2"]
    if scenario == "tracking":
        from .scenarios import CHIRP_BAND_LABELS

        cols += [_band_column(label) for label, _, _ in CHIRP_BAND_LABELS]
    return cols


def _fmt(value) -> str:
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


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
        groups: dict[float, list[float]] = {}
        for row in self.rows:
            value = row.get(metric)
            ok = row["status"] == "ok" and value not in (None, "")
            groups.setdefault(row[parameter], []).append(float(value) if ok else math.inf)
        means = {p: float(np.mean(v)) for p, v in groups.items()}
        best = min(means, key=means.get)
        return best, means[best]


def _read_existing(path: Path, columns: list[str]) -> dict[int, dict]:
    """Completed rows of an interrupted sweep; a torn last line is dropped."""
    text = path.read_text(encoding="utf-8")
    lines = text.split("\n")
    if lines and lines[-1] != "":
        lines = lines[:-1]  # no newline at the end: torn
    if not lines or lines[0] != ",".join(columns):
        raise ValueError(f"resume: {str(path)!r} does not hold rows of this sweep (different columns)")
    done = {}
    for row in csv.DictReader(io.StringIO("\n".join(lines) + "\n")):
        if None in row or any(v is None for v in row.values()):
            continue  # wrong number of fields: torn
        done[int(row["run"])] = row
    return done


def _executor(executor, workers: int | None):
    if executor is not None:
        return executor, False
    n = workers if workers is not None else (os.cpu_count() or 1)
    if n == 1:
        return None, False
    import multiprocessing

    return concurrent.futures.ProcessPoolExecutor(max_workers=n, mp_context=multiprocessing.get_context("spawn")), True


def _as_completed(executor, futures):
    if type(executor).__module__.startswith("distributed"):
        from distributed import as_completed

        return as_completed(futures)
    return concurrent.futures.as_completed(futures)


def sweep(cfg: Config, scenario: str, *, vary: dict | None = None, uncertain: dict | None = None,
          samples: int = 1, seed: int = 0, executor=None, workers: int | None = None,
          out_dir: str | os.PathLike | None = None, resume: bool = False, progress: bool = False,
          duration: float | None = None, variant: str | None = None, controller: str | None = None,
          chunk: int = 8) -> SweepResult:
    """Run a design sweep with Monte-Carlo draws.

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
    out_dir : path, optional
        Folder for ``results.csv`` and ``sweep.json``; needed for ``resume``.
    resume : bool
        Continue an interrupted sweep in ``out_dir`` (same settings required).
    progress : bool
        Progress bar with ETA (tqdm).
    duration, variant, controller : optional
        Passed to :func:`obsdesign.simulate`.
    chunk : int
        Runs per task sent to a worker (amortizes the scheduling overhead).

    Returns
    -------
    SweepResult
    """
    from tqdm import tqdm

    vary = _check_names("vary", dict(vary or {}))
    uncertain = _check_names("uncertain", dict(uncertain or {}))
    if isinstance(samples, bool) or not isinstance(samples, int) or samples < 1:
        raise ValueError(f"samples: expected an integer >= 1, found {samples!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"seed: expected an integer >= 0, found {seed!r}")
    if resume and out_dir is None:
        raise ValueError("resume: needs out_dir, the folder of the interrupted sweep")
    options = {k: v for k, v in (("duration", duration), ("variant", variant), ("controller", controller))
               if v is not None}
    from .scenarios import build_scenario

    build_scenario(scenario, dt=cfg.observer.dt, duration=duration)  # bad scenario or duration: fail now
    plan = _plan(vary, uncertain, samples, seed)
    columns = [*_FIXED_COLUMNS, *vary, *uncertain, *_metric_columns(scenario), *_TAIL_COLUMNS]
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
            done = _read_existing(results_path, columns)
            # Rewrite the completed rows cleanly (drops a torn tail) before appending.
            atomic_write(results_path, _csv_text(columns, [done[r] for r in sorted(done)]))
        else:
            atomic_write(manifest_path, json.dumps(manifest, indent=1))
            atomic_write(results_path, _csv_text(columns, []))
    todo = [spec for spec in plan if spec.run not in done]
    futures: list = []
    rows: dict[int, dict] = dict(done)
    pool, own = _executor(executor, workers)
    bar = tqdm(total=len(plan), initial=len(done), desc="sweep", unit="run", disable=not progress, smoothing=0.05)
    walls = []
    sink = open(results_path, "a", encoding="utf-8") if results_path is not None else None

    def record(row: dict) -> None:
        walls.append(row.pop("_wall", 0.0))
        rows[row["run"]] = row
        if sink is not None:
            sink.write(_csv_line(columns, row))
            sink.flush()  # complete line handed to the OS: survives Ctrl-C or a killed process
        bar.update()

    try:
        if pool is None:
            for spec in todo:
                record(run_one(cfg, scenario, spec, options))
        else:
            batches = [todo[i:i + chunk] for i in range(0, len(todo), chunk)]
            futures = [pool.submit(_run_batch, cfg, scenario, batch, options) for batch in batches]
            for fut in _as_completed(pool, futures):
                for row in fut.result():
                    record(row)
    except BaseException:
        if pool is not None and own:
            pool.shutdown(wait=False, cancel_futures=True)
        elif pool is not None and hasattr(pool, "cancel"):
            pool.cancel(futures)
        raise
    finally:
        bar.close()
        if sink is not None:
            sink.close()
    if own:
        pool.shutdown()
    ordered = [rows[r] for r in sorted(rows)]
    if results_path is not None:
        atomic_write(results_path, _csv_text(columns, ordered))
    wall = time.perf_counter() - t0
    overhead = (wall * max(1, _n_workers(pool)) - sum(walls)) / len(todo) if todo else float("nan")
    return SweepResult([_typed(r, columns) for r in ordered], tuple(columns),
                       Path(out_dir) if out_dir is not None else None, len(done), wall, overhead)


def _n_workers(pool) -> int:
    if pool is None:
        return 1
    if hasattr(pool, "_max_workers"):
        return pool._max_workers
    if hasattr(pool, "nthreads"):
        return max(1, sum(pool.nthreads().values()))
    return 1


def _run_batch(cfg, scenario, batch, options):
    return [run_one(cfg, scenario, spec, options) for spec in batch]


def _csv_line(columns: list[str], row: dict) -> str:
    """One complete CSV line (quoted where needed), so a single write never tears a row."""
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([_fmt(row.get(c)) for c in columns])
    return buf.getvalue()


def _csv_text(columns: list[str], rows: list[dict]) -> str:
    return ",".join(columns) + "\n" + "".join(_csv_line(columns, row) for row in rows)


def _typed(row: dict, columns) -> dict:
    """Rows read back from CSV hold strings; convert numbers and booleans."""
    out = {}
    for c in columns:
        v = row.get(c)
        if isinstance(v, str) and c not in ("status", "error"):
            if v == "":
                v = None
            elif v in ("true", "false"):
                v = v == "true"
            else:
                try:
                    v = int(v) if c in _FIXED_COLUMNS else float(v)
                except ValueError:
                    pass
        out[c] = v
    return out
