"""The display rows of :class:`~obsdesign.data.Identification` (its ``str`` and HTML)."""

from __future__ import annotations

from .timing import describe

__all__ = ["rows"]

#: Order of the zero-phase Butterworth low-pass of :func:`obsdesign.data.identify` (the benchmark's choice).
FILTER_ORDER = 4
#: The per-direction parameters of the ``asymmetric`` model.
ASYM = ("sigma_pos", "sigma_neg", "Cf_pos", "Cf_neg")


def rows(self) -> list[tuple[str, str]]:
    """The ``(label, text)`` rows of :class:`~obsdesign.data.Identification`'s text and HTML.

    Parameters
    ----------
    self : Identification
    """
    u = self.units
    words = u.axis_spec(self.input_gain).words  # the sentences below in the axis's words (torque, inertia)

    def pm(name, digits=5):
        value, std = getattr(self, name), getattr(self, name + "_std")
        unit = u.si(name.split("_")[0])
        text = f"{value:.{digits}g} ± {std:.2g} {unit}"
        if name in self.intervals:
            lo, hi = self.intervals[name]
            text += f"  [95 %: {lo:.{digits}g} to {hi:.{digits}g}]"
        if name in self.fixed:
            text += "  (fixed)"
        if name in self.at_bound:
            text += f"  (at its {self.at_bound[name]} bound)"
        return text

    names = ["m", "sigma", "Cf", "offset"] + (list(ASYM) if self.model == "asymmetric" else [])
    names += ["Fs", "vs"] if self.stribeck else []
    rows = [("model", self.model + (" + Stribeck" if self.stribeck else "")), ("source", self.source or "-"),
            ("units", u.describe(self.input_gain) + f"; input gain {self.input_gain:g} "
             f"{u.force_unit}/{u.input_unit(self.input_gain)}")]
    rows += [(n, pm(n)) for n in names]
    rows += [("s", "-" if self.s is None else f"{self.s:.5g} 1/{u.length_unit}"), ("s note", words(self.s_note)),
             ("timing", words(self.timing_note or describe(self.input_timing, self.delay_samples))),
             ("selection", words(self.selection or "-")), ("intervals", self.interval_method or "-"),
             ("NRMSE", f"{self.nrmse_percent:.3g} %"), ("condition number", f"{self.condition_number:.4g}"),
             ("rows in the fit", f"{self.samples} (|v| > {self.min_speed:.3g} {u.si('speed')}"
              + (f", past {self.travel_floor:.3g} {u.length_unit} of travel after each reversal (1/s: pre-sliding)"
                 if self.travel_floor else "")
              + (f", {self.window}" if self.window else "") + ")"),
             ("filter", f"Butterworth {FILTER_ORDER}th order {self.filter_hz:.4g} Hz, zero phase ({words(self.filter_rule)})"),
             ("decimation", f"{self.decimation} (sample time {self.sample_time:g} s)")]
    rows += [("WARNING", w) for w in self.warnings] + [("caution", w) for w in self.notices]
    return rows
