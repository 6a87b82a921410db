"""The result of a simulated run: traces (SI units), summary metrics, exports and displays."""

from __future__ import annotations

import io
import os
from dataclasses import dataclass, field

import numpy as np

from .._display import ResultDisplay
from .._format import short, with_unit
from .._io import atomic_write
from ..params import Config

__all__ = ["SimResult", "COLUMNS"]

#: Trace columns of CSV/NPZ exports, in order (SI units).
COLUMNS = ("t", "x", "x_meas", "v", "f", "v_hat", "f_hat", "f_hat_filtered", "u", "x_ref", "e")


@dataclass(frozen=True, eq=False)
class SimResult(ResultDisplay):
    """A simulated run: traces (SI units) and summary metrics.

    Attributes
    ----------
    t, x, x_meas, v, f, v_hat, f_hat, f_hat_filtered, u, x_ref, e : ndarray or None
        Per sample ``k``: the plant at ``t[k]``, the measurement, the estimates after
        processing it and the force ``u`` computed at ``k``; ``f`` is the plant's value of
        the estimated friction state; ``e = x_ref - x``. ``None`` when the trace was not kept.
    stiffness : ndarray or None
        Stiffness the observer used for the interval after each sample [N/m].
    metrics : dict
        ``rms_error``, ``max_error``, ``settling_time``, ``steady_state_error``,
        ``observer_rms_error_v``, ``observer_rms_error_f``, ``diverged``, ``sim_wall_s``
        and more (see ``docs/simulation.md``).
    scenario, controller, plant, stiffness_schedule, estimator : str
    config : Config
        The config of the run.
    """

    scenario: str
    controller: str
    plant: str
    stiffness_schedule: str
    config: Config
    metrics: dict
    t: np.ndarray | None = field(default=None, repr=False)
    x: np.ndarray | None = field(default=None, repr=False)
    x_meas: np.ndarray | None = field(default=None, repr=False)
    v: np.ndarray | None = field(default=None, repr=False)
    f: np.ndarray | None = field(default=None, repr=False)
    v_hat: np.ndarray | None = field(default=None, repr=False)
    f_hat: np.ndarray | None = field(default=None, repr=False)
    f_hat_filtered: np.ndarray | None = field(default=None, repr=False)
    u: np.ndarray | None = field(default=None, repr=False)
    x_ref: np.ndarray | None = field(default=None, repr=False)
    e: np.ndarray | None = field(default=None, repr=False)
    stiffness: np.ndarray | None = field(default=None, repr=False)
    estimator: str = "paper"

    def columns(self) -> dict[str, np.ndarray]:
        """The trace columns of :data:`COLUMNS` as a dict."""
        if self.t is None:
            raise ValueError("trace: this result holds metrics only (simulate(..., keep_trace=False))")
        return {name: getattr(self, name) for name in COLUMNS}

    def to_csv(self, path: str | os.PathLike) -> None:
        """Write the trace as CSV (header: :data:`COLUMNS`), atomically."""
        data = np.column_stack(list(self.columns().values()))
        buf = io.StringIO()
        np.savetxt(buf, data, delimiter=",", header=",".join(COLUMNS), comments="", fmt="%.17g")
        atomic_write(path, buf.getvalue().encode())

    def to_npz(self, path: str | os.PathLike) -> None:
        """Write the trace as a NumPy ``.npz`` archive, atomically."""
        buf = io.BytesIO()
        np.savez(buf, **self.columns())
        atomic_write(path, buf.getvalue())

    @property
    def _title(self) -> str:
        return f"simulation: {self.scenario}, {self.controller}"

    def _rows(self) -> list[tuple[str, str]]:
        from .metrics import METRIC_UNITS

        def unit_of(key: str) -> str:
            unit = self.config.units.unit(METRIC_UNITS.get(key, ""))
            return "" if unit == "-" else unit

        m, rows = self.metrics, []
        for key, value in m.items():
            unit = unit_of(key)
            if key == "settle_band_rule":
                continue  # stated beside the band
            if key == "settling_time" and isinstance(value, list):
                value = "[" + ", ".join("did not settle" if v is None else with_unit(v, unit, 4) for v in value) + "]"
            elif key == "settle_band" and value is not None:
                value = f"{with_unit(value, unit, 4)} ({m.get('settle_band_rule')})"
            elif key == "divergence" and value in ("runaway", "estimate"):
                what, bound = (("|e|", "error_bound"), m.get("max_error")) if value == "runaway" else \
                    (("|f_hat_filtered|", "estimate_bound"), None)
                b_unit = unit_of(what[1])
                reached = f" {with_unit(bound, b_unit, 4)}" if bound is not None else ""
                value = f"{value} ({what[0]}{reached} beyond {what[1]} {with_unit(m.get(what[1]), b_unit, 4)})"
            elif isinstance(value, list):
                value = "[" + ", ".join(short(v) for v in value) + "]" + (f" {unit}" if unit else "")
            elif isinstance(value, dict):
                value = ", ".join(f"{k}: {with_unit(v, unit, 4)}" for k, v in value.items())
            else:
                value = with_unit(value, unit, 4) if isinstance(value, float) else short(value)
            rows.append((key, value))
        return rows

    def text(self, units=None) -> str:
        """The metrics, one per line, in the units of the run's config (``units`` is ignored: it is that)."""
        lines = [f"Simulation: {self.scenario} ({self.controller}, plant {self.plant}, "
                 f"stiffness {self.stiffness_schedule}, variant {self.config.observer.variant})"]
        lines += [f"  {key}: {value}" for key, value in self._rows()]
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.text()
