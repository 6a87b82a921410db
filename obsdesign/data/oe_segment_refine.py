"""The segment fit as :func:`~obsdesign.data.output_error.refine` runs it for LuGre: its start from the static fit,
the profiled ranges, the progress bar, and the result in the axis's units (:mod:`obsdesign.data.oe_segments`).

Examples
--------
>>> from obsdesign.axis import AxisSpec
>>> AxisSpec(kind="rotary", input="A").unit(UNITS["sigma0"])
'N m/rad'
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from .choices import MAX_DELAY
from .timing import TIMING_MARGIN
from .oe_segments import (ALTERNATIVE_ITERATIONS, DAMPING_STARTS, DYNAMIC, PROFILE_ITERATIONS, PROFILE_POINTS, SEGMENT, STATIC, UNITS, SegmentFit,
                          fit_segments)

__all__ = ["SegmentRefinement", "refine_segments", "segment_start"]


def _neighbours(timing: str, delay: int) -> list[tuple[str, int]]:
    """The other readings of a log's timing the segment fit tries: either input timing, a delay at most one off.

    Examples
    --------
    >>> _neighbours("sample", 0)
    [('sample', 1), ('hold', 0), ('hold', 1)]
    """
    return [(t, k) for t in ("sample", "hold") for k in (delay - 1, delay, delay + 1)
            if 0 <= k <= MAX_DELAY and (t, k) != (timing, delay)]


@dataclass(frozen=True, kw_only=True)
class SegmentRefinement:
    """Result of :func:`refine_segments`: the :class:`SegmentFit` in the axis's units, and its start.

    Attributes
    ----------
    fit : SegmentFit
    initial : dict
        The starting values by name (IDIM-LS's estimate; the bristle parameters from the noise level).
    units : dict
        Unit of each parameter on this axis (``kg m^2``, ``N m``, ``N m/rad`` on a rotary one).
    length_unit : str
        ``'m'`` or ``'rad'``.
    timing : str
        How the input timing and the delay were modelled.
    segment_time : float
        ``L`` in seconds.
    wall_time : float
        Seconds.
    model : str
        ``'lugre'``.
    warning : str
        One line when the fit as a whole is not to be trusted (another reading of the log's timing fits better).
    """

    fit: SegmentFit
    initial: dict
    units: dict
    length_unit: str
    timing: str
    segment_time: float
    wall_time: float
    model: str = "lugre"
    warning: str = ""

    def __getitem__(self, name: str) -> dict:
        f = self.fit
        if name not in f.values:
            raise KeyError(f"{name!r} was not refined; refined: {', '.join(f.names)}")
        lo, hi = f.intervals[name]
        return {"value": f.values[name], "initial": self.initial[name], "std": f.std[name], "low": lo, "high": hi,
                "unit": self.units[name], "identifiable": f.identifiable[name], "note": f.notes[name]}

    def to_dict(self) -> dict:
        """JSON-ready: ``model, method, segment_samples, segment_time, segments, timing, rms, noise, evaluations,
        wall_time, stopped, substeps`` and ``parameters`` (name -> ``value, initial, std, low, high, unit, identifiable,
        note``), ``profiles`` (name -> ``{grid, cost}``)."""
        f = self.fit
        return {"model": self.model, "method": "segment output error", "segment_samples": f.segment_samples,
                "segment_time": self.segment_time, "segments": f.segments, "timing": self.timing, "rms": f.rms,
                "noise": f.noise, "length_unit": self.length_unit, "evaluations": f.evaluations,
                "wall_time": self.wall_time, "stopped": f.stopped, "substeps": f.substeps, "timing_alternatives": dict(f.alternatives),
                "warning": self.warning,
                "parameters": {n: self[n] for n in f.names},
                "profiles": {n: {"grid": g.tolist(), "cost": c.tolist()} for n, (g, c) in f.profiles.items()}}

    def apply(self, ident):
        """``ident`` unchanged (the segment fit is reported beside the static one, not written into it)."""
        return ident

    def __str__(self) -> str:
        f = self.fit
        lines = [f"Output-error refinement ({self.model}, segments): {f.segments} segments of L = {f.segment_samples} "
                 f"samples ({self.segment_time:.4g} s), each with its own initial position, velocity and bristle "
                 f"force; {self.timing}; RMS position residual {f.rms:.3g} {self.length_unit} "
                 f"({f.rms / f.noise:.3g} x the noise level); {f.evaluations} simulations, {f.substeps} Heun sub-steps "
                 "a sample"]
        if f.stopped:
            lines.append(f"  {f.stopped}")
        if self.warning:
            lines.append(f"  {self.warning}")
        if f.alternatives:
            lines.append("  the log's timing, other readings refitted (BIC against this one; negative fits better): "
                         + "; ".join(f"{k} {v:+.1f}" for k, v in f.alternatives.items()))
        for n in f.names:
            p = self[n]
            verdict = "identifiable" if p["identifiable"] else f"NOT identifiable: {p['note']}"
            lines.append(f"  {n:<7} {p['value']:.6g} {p['unit']}  95 % [{p['low']:.6g}, {p['high']:.6g}]  "
                         f"(start {p['initial']:.4g})  {verdict}")
        return "\n".join(lines)


def segment_start(ident, dt: float) -> tuple[float, dict, dict]:
    """The segment fit's noise level, start and profile ranges from ``identify``'s result.

    The start is the static fit with a bristle stiffness ``Cf / (10 noise)`` (the Coulomb level over ten times the
    noise, at most a tenth of the stiffest bristle the sampling resolves, ``16 m / dt^2``: a resonance at
    ``4 / dt``) and a damping ratio 0.3; ``sigma0`` is profiled from ``Cf / (1e3 noise)`` to ``Cf / (1e-3 noise)``
    (within that stiffest bristle), ``sigma1`` from 0.001 to 30 times the critical damping of the start.

    Parameters
    ----------
    ident : Identification
        ``identify``'s result (``noise_rms, quantization, m, sigma, Cf, offset, Fs, vs``).
    dt : float
        Sample time [s].

    Returns
    -------
    noise : float
        The position noise RMS the residual is weighted by (with the encoder's ``q / sqrt(12)`` as its floor).
    start, ranges : dict
        Name -> value of ``m, sigma, Cf, offset, Fs, vs, sigma0, sigma1``; name -> ``(low, high)`` of
        ``sigma0`` and ``sigma1``.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> ident = SimpleNamespace(noise_rms=1e-6, quantization=0.0, m=2.0, sigma=10.0, Cf=1.0, offset=0.0, Fs=None,
    ...                         vs=None)
    >>> noise, start, ranges = segment_start(ident, 1e-3)
    >>> round(start["sigma0"]), ranges["sigma0"]      # Cf / (10 noise); Cf / (1e3 noise) up to 16 m / dt^2
    (100000, (1000.0, 32000000.0))
    """
    noise = max(ident.noise_rms, ident.quantization / math.sqrt(12.0), 1e-15)
    sigma0_max = 16.0 * ident.m / dt**2  # a bristle resonance 4 / dt (0.64 x the rate): beyond, a rigid stick
    start = {"m": ident.m, "sigma": ident.sigma, "Cf": ident.Cf, "offset": ident.offset,
             "Fs": ident.Fs if ident.Fs is not None else ident.Cf,
             "vs": ident.vs if ident.vs is not None else 1.0,
             "sigma0": min(ident.Cf / (10.0 * noise), sigma0_max / 10.0)}
    start["sigma1"] = 0.6 * math.sqrt(start["sigma0"] * ident.m)  # damping ratio 0.3 (the stage-1 starts vary it)
    crit = 2.0 * math.sqrt(start["sigma0"] * ident.m)
    ranges = {"sigma0": (min(ident.Cf / (1e3 * noise), sigma0_max / 1e4), min(ident.Cf / (1e-3 * noise), sigma0_max)),
              "sigma1": (1e-3 * crit, 30.0 * crit)}
    return noise, start, ranges


def refine_segments(trace, ident, *, parameters: tuple, segment: float = SEGMENT, time_budget: float | None = None,
                    progress: bool = False) -> SegmentRefinement:
    """LuGre and the rigid body refined by segment output error (:func:`fit_segments`) from ``ident``.

    Parameters
    ----------
    trace : Trace
        The record.
    ident : Identification
        Its static fit: the start, the input timing and the delay, the noise level.
    parameters : tuple of str
        The parameters asked for; the bristle ones among them are profiled. ``m, sigma, Cf, offset``,
        ``sigma0, sigma1`` (and ``Fs, vs`` when the static fit kept a Stribeck term, or asked) are always
        fitted: holding any of them at a biased value biases the rest.
    segment : float
        Segment length [s] of the final stage.
    time_budget : float, optional
        Seconds.
    progress : bool
        Show a progress bar with an ETA on stderr.
    """
    import sys

    from ..axis import AxisSpec

    t0 = time.perf_counter()
    if ident.model != "coulomb-viscous":
        raise ValueError(f"ident: expected a coulomb-viscous identification for the segment fit, found {ident.model!r}")
    d = int(ident.delay_samples)
    x = np.asarray(trace.position, dtype=np.float64)[d:]
    u = np.asarray(trace.force, dtype=np.float64)[:trace.force.size - d]
    dt = trace.sample_time
    noise, start, ranges = segment_start(ident, dt)
    stribeck = ident.Fs is not None or "Fs" in parameters or "vs" in parameters
    free = STATIC + (("Fs", "vs") if stribeck else ()) + DYNAMIC
    profile = tuple(n for n in DYNAMIC if n in parameters)
    per_fit = len(free) + 5
    total = int(len(DAMPING_STARTS) * (12 + 12 + 30) * per_fit
                + len(_neighbours(ident.input_timing, d)) * ALTERNATIVE_ITERATIONS * per_fit
                + len(profile) * (PROFILE_POINTS * PROFILE_ITERATIONS * (per_fit - 1) + 30 * per_fit))
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=total, unit="sim", desc="refine (segment output error)", file=sys.stderr, leave=False,
                   mininterval=0.5, dynamic_ncols=True)
    alternatives, warning = {}, ""
    for timing, delay in _neighbours(ident.input_timing, d):
        label = f"--input-timing {timing} --delay-samples {delay}"
        alternatives[label] = (np.asarray(trace.position, dtype=np.float64)[delay:],
                               np.asarray(trace.force, dtype=np.float64)[:trace.force.size - delay], timing == "hold")
    try:
        fit = fit_segments(x, u, dt=dt, hold=ident.input_timing == "hold", noise=noise, start=start, free=free,
                           profile=profile, segment=segment, time_budget=time_budget, bar=bar, ranges=ranges,
                           alternatives=alternatives)
    finally:
        if bar is not None:
            bar.close()
    better = {k: v for k, v in fit.alternatives.items() if v < -TIMING_MARGIN}
    if better:
        label = min(better, key=better.get)
        warning = (f"NOT identified: the segments fit better with another reading of the log's timing "
                   f"({label}: BIC {better[label]:+.1f}); rerun with {label}")
        fit = replace(fit, identifiable={n: False for n in fit.names},
                      notes={n: "another reading of the log's timing fits better (above)" for n in fit.names})
    axis = AxisSpec(kind="rotary" if trace.units.rotary else "linear", input="A")
    timing = (f"input {'held over a sample' if ident.input_timing == 'hold' else 'as logged (interpolated)'}, "
              f"position {d} sample{'s' if d != 1 else ''} late (as identify found)")
    return SegmentRefinement(fit=fit, initial={n: start[n] for n in free},
                             units={n: axis.unit(UNITS[n]) for n in free}, length_unit=axis.unit("m"),
                             timing=timing, segment_time=fit.segment_samples * dt, warning=warning,
                             wall_time=time.perf_counter() - t0)
