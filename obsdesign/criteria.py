"""The design judged by stated criteria: what a user's report checks instead of the paper's claims.

Each criterion names a quantity of the design as it runs, a threshold written here once
(:data:`THRESHOLDS`) and why; :func:`judge_design` measures it from the results the report computes
anyway (the sampled loop, the positioning and tracking runs, the noise transfer, the stability check).
A criterion is a rule of thumb for a precision axis, not a proof: the report shows the number beside
the threshold so that the reader can apply their own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["THRESHOLDS", "Criterion", "judge_design"]

#: name -> (threshold, the rule in words). Margins: the usual robustness guidelines (phase margin
#: 30-60 deg, gain margin 2 or more, max |S| at most 2; Astrom & Murray, Feedback Systems, ch. 12).
THRESHOLDS = {
    "phase_margin_deg": (30.0, "phase margin of the sampled loop (with its computation delay) >= 30 deg"),
    "gain_margin_db": (6.0, "gain margin of the sampled loop >= 6 dB (a factor 2)"),
    "max_S": (2.0, "max |S| of the sampled loop <= 2 (the closest approach to -1 is at least 0.5)"),
    "pole_dt": (1.0, "fastest observer pole x dt <= 1 (the observer is not faster than the sampling)"),
    "settles": (None, "the compensated positioning step settles within each hold: into its band (max(2 x encoder "
                      "resolution, 3 x noise RMS) unless given) and stays there for at least the last 10 % of the "
                      "hold; a run that diverges or runs away fails"),
    "settling_ratio": (1.1, "compensation does not slow settling: mean settling time with the observer "
                            "<= 1.1 x the PID's alone"),
    "tracking_ratio": (1.0, "compensation improves tracking: RMS tracking error with the observer < the PID's alone"),
    "noise_fraction": (0.1, "friction-estimate noise after the low-pass <= 10 % of Cf"),
    "estimate_fraction": (0.2, "friction-estimate error in the tracking run (RMS, against the simulated plant) "
                               "<= 20 % of Cf"),
}


@dataclass(frozen=True)
class Criterion:
    """One stated criterion and what the design gives.

    Attributes
    ----------
    name : str
        A key of :data:`THRESHOLDS`.
    rule : str
        The criterion in words, with its threshold.
    measured : str
        The design's value.
    holds : bool
        Whether the design meets it.
    """

    name: str
    rule: str
    measured: str
    holds: bool


def _mean(values) -> float | None:
    if not values or any(v is None for v in values):
        return None
    return float(sum(values) / len(values))


def judge_design(cfg, *, sampled_loop, experiments, noise, stability) -> tuple[Criterion, ...]:
    """The criteria of :data:`THRESHOLDS` for a design.

    Parameters
    ----------
    cfg : Config
        The design.
    sampled_loop : SampledLoop
        :func:`obsdesign.design.sampled_loop.sampled_loop` of ``cfg`` (the loop that runs).
    experiments : ExperimentsStudy
        :func:`obsdesign.studies.experiments_study` of ``cfg`` (positioning and tracking, PID and
        PID + observer).
    noise : NoiseAnalysis
        :func:`obsdesign.noise_analysis` of ``cfg``.
    stability : StabilityReport
        :func:`obsdesign.check_stability` of ``cfg``.

    Returns
    -------
    tuple of Criterion
    """
    out = []

    def add(name, value_text, holds):
        out.append(Criterion(name, THRESHOLDS[name][1], value_text, bool(holds)))

    lp = sampled_loop
    add("phase_margin_deg", f"{lp.phase_margin_deg:.4g} deg", lp.phase_margin_deg >= THRESHOLDS["phase_margin_deg"][0])
    gm = lp.gain_margin_db
    add("gain_margin_db", "infinite" if math.isinf(gm) else f"{gm:.4g} dB", gm >= THRESHOLDS["gain_margin_db"][0])
    add("max_S", f"{lp.max_S:.4g}", lp.max_S <= THRESHOLDS["max_S"][0])
    product = abs(stability.fastest_pole) * cfg.observer.dt
    add("pole_dt", f"{abs(stability.fastest_pole):.4g} 1/s x {cfg.observer.dt:g} s = {product:.3g}",
        product <= THRESHOLDS["pole_dt"][0])
    unit = cfg.units.unit
    obs, pid = experiments.positioning["pid+observer"], experiments.positioning["pid"]
    times = obs["settling_time"]
    band = obs.get("settle_band")
    band_text = "" if band is None else f" (band {band:.4g} {unit('m')}: {obs.get('settle_band_rule')})"
    if obs.get("diverged"):
        add("settles", f"diverged ({obs['divergence']}){band_text}", False)
    else:
        add("settles", (", ".join("did not settle" if t is None else f"{t:.4g} s" for t in times) or "no step")
            + band_text, bool(times) and all(t is not None for t in times))
    with_obs, alone = _mean(obs["settling_time"]), _mean(pid["settling_time"])
    if obs.get("diverged"):
        add("settling_ratio", f"the run with the observer diverged ({obs['divergence']})", False)
    elif with_obs is None:
        add("settling_ratio", "a step with the observer did not settle", False)
    elif alone is None:
        add("settling_ratio", f"{with_obs:.4g} s; a step of the PID alone did not settle", True)
    else:
        add("settling_ratio", f"{with_obs:.4g} s against {alone:.4g} s (ratio {with_obs / alone:.3g})",
            with_obs <= THRESHOLDS["settling_ratio"][0] * alone)
    e_obs = experiments.tracking["pid+observer"]["rms_error"]
    e_pid = experiments.tracking["pid"]["rms_error"]
    trk_obs = experiments.tracking["pid+observer"]
    if e_obs is None or e_pid is None or trk_obs.get("diverged"):
        add("tracking_ratio", "a tracking run diverged" + (f" ({trk_obs['divergence']})" if trk_obs.get("diverged") else ""),
            False)
    else:
        add("tracking_ratio", f"{e_obs:.4g} {unit('m')} against {e_pid:.4g} {unit('m')} (ratio {e_obs / e_pid:.3g})",
            e_obs < THRESHOLDS["tracking_ratio"][0] * e_pid)
    cf = cfg.friction.Cf
    add("noise_fraction", f"{noise.rms_filtered:.4g} {unit('N')} = {noise.rms_filtered / cf:.3g} Cf",
        noise.rms_filtered <= THRESHOLDS["noise_fraction"][0] * cf)
    err = trk_obs.get("observer_rms_error_f")
    if err is None or trk_obs.get("diverged"):
        add("estimate_fraction", "diverged" + (f" ({trk_obs['divergence']})" if trk_obs.get("diverged") else ""), False)
    else:
        add("estimate_fraction", f"{err:.4g} {unit('N')} = {err / cf:.3g} Cf",
            err <= THRESHOLDS["estimate_fraction"][0] * cf)
    return tuple(out)
