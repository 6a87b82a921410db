"""The plan of a sweep: a grid over the varied parameters times Monte-Carlo draws.

Run ``r`` gets its own ``numpy.random.SeedSequence`` (the sweep seed's ``spawn``);
the draws and the simulation's noise seed come from it, so a run's numbers do not
depend on where or in which order it is executed.

Examples
--------
>>> plan = make_plan({"rho": (1.0, 2.0, 2)}, {"Cf": (0.3, 0.4)}, samples=2, seed=0)
>>> [(r.run, r.grid_point, r.sample, r.params["rho"]) for r in plan]
[(0, 0, 0, 1.0), (1, 0, 1, 1.0), (2, 1, 0, 2.0), (3, 1, 1, 2.0)]
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .._validate import FINITE, Integer, check_integer
from ..params import PARAMETERS, SECTIONS

__all__ = ["RunSpec", "make_plan", "plan_runs", "count_runs", "check_names", "check_axes", "integer_fields", "MAX_RUNS"]

#: Most runs a sweep may plan (a plan holds one seed per run in memory).
MAX_RUNS = 1_000_000


@dataclass(frozen=True)
class RunSpec:
    """One run: its index, grid point, sample, seed and the parameter values to apply.

    Attributes
    ----------
    run : int
        Index of the run in the plan (its row).
    grid_point : int
        Index of its point of the design grid.
    sample : int
        Index of its uncertainty sample at that point.
    seed : int
        Seed of its noise and excitation.
    params : dict
        Parameter name (``section.field``) -> value, applied with :meth:`Config.override`.
    """

    run: int
    grid_point: int
    sample: int
    seed: int
    params: dict


def integer_fields() -> frozenset[str]:
    """Names of the config fields whose rule is an :class:`~obsdesign._validate.Integer` (e.g. ``delay_samples``).

    A swept integer field gets integer grid points (``LO``, ``HI`` whole and ``N`` such that the
    step is whole); it cannot be drawn uniformly.

    >>> sorted(integer_fields())
    ['delay_samples', 'lookahead']
    """
    return frozenset(f.name for cls in SECTIONS.values() for f in dataclasses.fields(cls)
                     if isinstance(f.metadata.get("check"), Integer))


def _integer_axis(name: str, lo: float, hi: float, n: int) -> None:
    """``ValueError`` unless ``linspace(lo, hi, n)`` holds whole numbers only."""
    points = np.linspace(lo, hi, n)
    if not np.all(points == np.round(points)):
        raise ValueError(f"vary {name}: expected whole grid points for an integer field (LO, HI whole and "
                         f"(HI - LO) / (N - 1) whole), found {lo:g}:{hi:g}:{n}")


def check_names(kind: str, spec: dict) -> dict[str, tuple]:
    """``spec`` if every key is a numeric config parameter (``ValueError`` naming ``kind`` otherwise).

    Parameters
    ----------
    kind : str
        The argument's name for messages (e.g. ``'vary'``).
    spec : dict
        Parameter name -> bounds.
    """
    if not isinstance(spec, dict):
        raise TypeError(f"{kind}: expected a dict of parameter name -> bounds, found {type(spec).__name__}")
    for name in spec:
        if name.startswith("plant."):  # the simulated plant only (model mismatch), see docs/comparison.md
            from ..plant_spec import PLANT_PARAMETER_NAMES

            if name[6:] in PLANT_PARAMETER_NAMES or (name[6:] in PARAMETERS and name[6:] != "variant"):
                continue
            raise ValueError(f"{kind}: unknown plant parameter {name!r}; expected plant.<config field> such as "
                             "plant.m, plant.Cf, or plant.<[plant_friction] parameter> such as plant.offset")
        if name not in PARAMETERS or name == "variant":
            raise ValueError(f"{kind}: unknown parameter {name!r}; expected a numeric config field such as "
                             "rho, omega_co, kappa, Cf, sigma, m (or plant.NAME for the simulated plant only)")
    return spec


def _bounds(kind: str, name: str, value, n_items: int, syntax: str) -> tuple:
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != n_items:
        raise TypeError(f"{kind} {name}: expected {syntax}, found {value!r}")
    lo = FINITE.check(f"{kind} {name} LO", value[0])
    hi = FINITE.check(f"{kind} {name} HI", value[1])
    return lo, hi


def check_axes(vary: dict, uncertain: dict, samples: int) -> tuple[dict, dict]:
    """Validated ``vary`` and ``uncertain`` (the checks of the command line, for the API too).

    Every name a numeric config field and in at most one of the two; ``vary`` values
    ``(LO, HI, N)`` with finite bounds and an integer ``N >= 1``; ``uncertain`` values
    ``(LO, HI)`` with ``LO <= HI``; at most :data:`MAX_RUNS` runs in all.

    Parameters
    ----------
    vary : dict
        ``{name: (low, high, n)}``.
    uncertain : dict
        ``{name: (low, high)}``.
    samples : int
        Draws per grid point.

    Examples
    --------
    >>> check_axes({"rho": (1, 2, 3)}, {"Cf": (0.3, 0.4)}, 2)
    ({'rho': (1.0, 2.0, 3)}, {'Cf': (0.3, 0.4)})
    >>> check_axes({"rho": (1, 2, 0)}, {}, 1)
    Traceback (most recent call last):
    ...
    ValueError: vary rho N: expected an integer >= 1, found 0
    >>> check_axes({"rho": (1, 2, 2)}, {"rho": (3, 4)}, 1)
    Traceback (most recent call last):
    ...
    ValueError: uncertain: 'rho' is varied already; expected each parameter in vary or in uncertain, not both
    """
    vary, uncertain = check_names("vary", vary), check_names("uncertain", uncertain)
    out_vary = {}
    for name, value in vary.items():
        lo, hi = _bounds("vary", name, value, 3, "(LO, HI, N)")
        out_vary[name] = (lo, hi, check_integer(f"vary {name} N", value[2], minimum=1))
        if name.removeprefix("plant.") in integer_fields():
            _integer_axis(name, *out_vary[name])
    out_unc = {}
    for name, value in uncertain.items():
        if name in vary:
            raise ValueError(f"uncertain: {name!r} is varied already; expected each parameter in vary or in "
                             "uncertain, not both")
        lo, hi = _bounds("uncertain", name, value, 2, "(LO, HI)")
        if name.removeprefix("plant.") in integer_fields():
            raise ValueError(f"uncertain {name}: an integer field cannot be drawn uniformly; vary it on a grid "
                             f"(--vary {name}=LO:HI:N) instead")
        if hi < lo:
            raise ValueError(f"uncertain {name}: expected LO <= HI, found {lo:g} > {hi:g}")
        out_unc[name] = (lo, hi)
    runs = count_runs(out_vary, samples)
    if runs > MAX_RUNS:
        raise ValueError(f"vary, samples: expected at most {MAX_RUNS} runs in all, found {runs}")
    return out_vary, out_unc


def count_runs(vary: dict, samples: int) -> int:
    """Runs of a sweep: grid points (the product of the ``n`` of ``vary``) times ``samples``.

    Parameters
    ----------
    vary : dict
        ``{name: (low, high, n)}`` grid axes.
    samples : int
        Draws per grid point.

    >>> count_runs({"rho": (1.0, 2.0, 3), "kappa": (1e5, 1e6, 2)}, 4)
    24
    """
    runs = samples
    for _, _, n in vary.values():
        runs *= n
    return runs


def plan_runs(vary: dict, uncertain: dict, samples: int, seed: int, start: int, stop: int) -> list[RunSpec]:
    """Runs ``start`` to ``stop - 1`` of the plan of :func:`make_plan`, built without the others.

    Run ``r``'s seed sequence is ``SeedSequence(seed, spawn_key=(r,))``, which is the ``r``-th
    child of ``SeedSequence(seed).spawn(n_runs)``; so a batch of a streamed Monte-Carlo study
    (:mod:`obsdesign.sweeps.montecarlo`) gets the same draws in any worker, in any order, after
    a resume, and the memory of the plan does not grow with the number of runs.

    Parameters
    ----------
    vary, uncertain, samples, seed
        As :func:`make_plan`.
    start, stop : int
        The range of run indices (``0 <= start <= stop <= count_runs(vary, samples)``).

    Examples
    --------
    >>> full = make_plan({"rho": (1.0, 2.0, 2)}, {"Cf": (0.3, 0.4)}, samples=3, seed=5)
    >>> plan_runs({"rho": (1.0, 2.0, 2)}, {"Cf": (0.3, 0.4)}, 3, 5, 2, 4) == full[2:4]
    True
    """
    n_runs = count_runs(vary, samples)
    if not 0 <= start <= stop <= n_runs:
        raise ValueError(f"start, stop: expected 0 <= start <= stop <= {n_runs}, found {start}, {stop}")
    axes = [np.linspace(lo, hi, n) for lo, hi, n in vary.values()]
    shape = tuple(len(a) for a in axes)
    ints = integer_fields()
    plan = []
    for r in range(start, stop):
        g, j = divmod(r, samples)
        index = np.unravel_index(g, shape) if shape else ()
        child = np.random.SeedSequence(seed, spawn_key=(r,))
        rng = np.random.default_rng(child)
        params = {name: int(round(v)) if name.removeprefix("plant.") in ints else float(v)
                  for name, v in zip(vary, (a[i] for a, i in zip(axes, index)))}
        params.update({name: float(rng.uniform(lo, hi)) for name, (lo, hi) in uncertain.items()})
        plan.append(RunSpec(r, g, j, int(child.generate_state(1, np.uint32)[0]), params))
    return plan


def make_plan(vary: dict, uncertain: dict, samples: int, seed: int) -> list[RunSpec]:
    """The runs of a sweep in run order: grid point by grid point, ``samples`` draws each.

    Parameters
    ----------
    vary : dict
        ``{name: (low, high, n)}`` grid axes.
    uncertain : dict
        ``{name: (low, high)}`` uniform draws.
    samples : int
        Draws per grid point.
    seed : int
        Sweep seed.
    """
    return plan_runs(vary, uncertain, samples, seed, 0, count_runs(vary, samples))
