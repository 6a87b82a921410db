"""``obsdesign pid``: the paper's PID and the sampled design of a config side by side, and the one it carries.

Examples
--------
>>> import obsdesign as od
>>> d = pid_designs(od.load_preset("vcm"))
>>> d.carried.design, d.paper.design, d.sampled.design   # on vcm the sampled design is the paper's gains
('paper', 'paper', 'sampled')
>>> d.sampled.kp == d.paper.kp
True
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from .._display import ResultDisplay
from ..params import Config
from .pid import PIDDesign, pid_from_config
from .pid_sampled import PIDChoice, resolve_pid

__all__ = ["PIDDesigns", "pid_designs"]


@dataclass(frozen=True, kw_only=True)
class PIDDesigns(ResultDisplay):
    """Both PID designs of a config on the sampled loop with the delay, and the one the config carries.

    Attributes
    ----------
    carried : PIDDesign
        The design the config carries (:func:`pid_from_config`), verified by python-control.
    paper, sampled : PIDChoice or None
        The paper's rule and the sampled design (``None``: no sampled design meets the target, see ``note``).
    dt : float
        Sample time [s].
    delay_samples : int
        The drive's delay [samples].
    target_deg : float
        The config's phase margin ``pid.phase_margin_deg`` [deg].
    note : str
        Why there is no sampled design ("" when there is).
    """

    _title = "Sensitivity-based PID: the paper's rule and the sampled design"
    carried: PIDDesign
    paper: PIDChoice
    sampled: PIDChoice | None
    dt: float
    delay_samples: int
    target_deg: float
    note: str = ""

    def to_dict(self) -> dict:
        """JSON-ready values: the carried design's keys of :meth:`PIDDesign.to_dict`, ``paper`` and ``sampled``."""
        def one(c: PIDChoice | None):
            if c is None:
                return None
            pm = c.sampled_pm_deg
            return {"k": c.k, "T_I": c.T_I, "T_z": c.T_z, "kp": c.kp, "ki": c.ki, "kd": c.kd, "tau_d": c.tau_d,
                    "design_phase_margin_deg": c.design_phase_margin_deg,
                    "sampled_phase_margin_deg": pm if math.isfinite(pm) else None}

        return {**self.carried.to_dict(), "setting": self.paper.setting, "dt": self.dt,
                "delay_samples": self.delay_samples, "target_phase_margin_deg": self.target_deg,
                "paper": one(self.paper), "sampled": one(self.sampled), "note": self.note}

    def _rows(self):
        rows = list(self.carried._rows())
        where = f"dt = {self.dt:g} s, delay {self.delay_samples} samples"
        for name, c in (("paper", self.paper), ("sampled", self.sampled)):
            if c is None:
                rows.append((f"{name}: no design", self.note))
                continue
            rows += [(f"{name}: kp [V/m] / ki [V/(m s)] / kd [V s/m]", f"{c.kp:.6g} / {c.ki:.6g} / {c.kd:.6g}"),
                     (f"{name}: k [V/m] / T_I [s] / T_z [s]", f"{c.k:.6g} / {c.T_I:.6g} / {c.T_z:.6g}"),
                     (f"{name}: phase margin on the sampled loop ({where}) [deg]",
                      f"{c.sampled_pm_deg:.4g} (target {self.target_deg:g})")]
        rows.append(("carried by the config", f"{self.carried.design} ([pid] design = {self.paper.setting!r})"))
        return rows


def pid_designs(cfg: Config) -> PIDDesigns:
    """The paper's and the sampled PID of ``cfg`` on its sampled loop, and the one it carries (``obsdesign pid``).

    Parameters
    ----------
    cfg : Config
        The design.

    Returns
    -------
    PIDDesigns

    Examples
    --------
    >>> import obsdesign as od
    >>> d = pid_designs(od.load_preset("vcm").override(delay_samples=1))
    >>> d.carried.design, round(d.paper.sampled_pm_deg, 2), round(d.sampled.sampled_pm_deg, 2)
    ('paper', 59.91, 60.0)
    """
    carried = pid_from_config(cfg)
    paper = resolve_pid(cfg, design="paper")
    paper = dataclasses.replace(paper, setting=cfg.pid.design)
    sampled, note = None, ""
    try:
        sampled = dataclasses.replace(resolve_pid(cfg, design="sampled"), setting=cfg.pid.design)
    except ValueError as exc:
        note = str(exc)
    return PIDDesigns(carried=carried, paper=paper, sampled=sampled, dt=cfg.observer.dt,
                      delay_samples=cfg.hardware.delay_samples, target_deg=cfg.pid.phase_margin_deg, note=note)
