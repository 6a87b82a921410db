"""Offline observation: the designed observer run over a measured trace.

:func:`observe` runs the reduced-order observer of a config (and the low-pass filter
eq:3:4:5 of its friction estimate) over a :class:`~obsdesign.data.Trace` at the trace's
own sample time. There is no second implementation: the config becomes the one sampled
controller (:func:`obsdesign.sampled.sampled_controller`) and the samples go through
:func:`obsdesign.sampled.kernel.observe_loop`, the estimator step of the closed-loop
simulator's controller. Run on a simulator's own ``x_meas`` and force, it reproduces the
simulator's ``v_hat``, ``f_hat``, ``f_hat_filtered`` and ``stiffness`` bit for bit, for every
schedule (``estimated`` with the same reversal hysteresis) and every estimator.

Conventions
-----------
* **Input.** The observer's model is ``m a = u - G - sigma v - w3`` (static variant) with
  ``G`` the known constant load force of the config (``plant.G``; ``to_config`` puts the
  identified offset there). The force fed to the observer is therefore ``u - G``: the
  load is fed forward and the estimate ``f_hat`` does **not** include it. Against a model
  with an offset, compare ``f_hat + G`` with ``Cf sign(v) + offset``, or ``f_hat`` with
  ``Cf sign(v)``.
* **Timing.** ``u[n]`` is the force applied from sample ``n`` to ``n + 1`` (held); the
  estimate at sample ``n`` uses the forces up to ``u[n - 1]``, as in the simulator.
* **Sample time.** The trace's sample time wins: the observer can only run at the rate
  the data were sampled. A config whose ``observer.dt`` differs from it by more than
  :data:`DT_TOLERANCE` (relative) is refused, with the value to put in the config; within
  that tolerance the two are one clock and the config's value is used.
* **Stiffness** ``estimated`` (default, as in the simulator: branch driven by the
  measured position, a reversal accepted once the position has come back from its extreme by
  4 ``sensor.noise_rms``), ``estimated-raw`` (a reversal at every sign change of ``v_hat``),
  ``constant`` (``kappa``), or ``true``:
  measured data have no plant, so ``true`` means the paper's pre-sliding stiffness
  (eq:2:3:5, bounded by ``kappa``) driven by the measured position and the zero-phase
  velocity (:func:`~obsdesign.data.trace.zero_phase_velocity`, samples with ``|v|`` at most
  1 % of its peak keep the branch) with the config's ``Cf``, ``s``, ``kappa``: the best
  knowledge of the stiffness the data allow, available offline only (it looks ahead).

Examples
--------
>>> import numpy as np
>>> import obsdesign as od
>>> from obsdesign.data import Trace, observe
>>> cfg = od.load_preset("table1")
>>> t = np.arange(2000) * cfg.observer.dt
>>> tr = Trace(t=t, position=1e-4 * np.sin(2 * np.pi * 5 * t), force=np.zeros(2000), sample_time=cfg.observer.dt)
>>> obs = observe(cfg, tr)
>>> obs.samples, round(obs.sample_time, 6), obs.columns()["v_hat"].shape
(2000, 0.0001, (2000,))
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass, field

import numpy as np
from numba import njit

from .._display import ResultDisplay
from .._io import atomic_write
from ..friction.presliding import stiffness as _branch_stiffness
from ..friction.presliding import track_reversal
from ..params import Config
from ..sampled.controller import SampledController, sampled_controller
from ..sampled.kernel import observe_loop
from .trace import REVERSAL_THRESHOLD, Trace, zero_phase_velocity

__all__ = ["Observation", "observe", "model_friction_state", "OBSERVATION_COLUMNS", "DT_TOLERANCE",
           "presliding_stiffness_along"]

#: Columns of :meth:`Observation.columns` (CSV/NPZ exports), in order (SI units).
OBSERVATION_COLUMNS = ("t", "x_meas", "u", "v_hat", "f_hat", "f_hat_filtered", "stiffness")
#: Largest relative difference between the config's ``observer.dt`` and the trace's sample time.
DT_TOLERANCE = 1e-6


@njit(cache=True, error_model="numpy")
def presliding_stiffness_along(x, v, Cf, s, kappa):
    """Pre-sliding stiffness [N/m] along position and velocity traces (the ``true`` schedule offline).

    Parameters
    ----------
    x : ndarray
        Position [m].
    v : ndarray
        Velocity [m/s]; a sign change starts a new branch, ``v == 0`` keeps it.
    Cf : float
        Coulomb level [N].
    s : float
        Pre-sliding scale [1/m].
    kappa : float
        Stiffness bound [N/m].

    Examples
    --------
    >>> import numpy as np
    >>> k = presliding_stiffness_along(np.array([0.0, 0.0, 1e-5, 1.0]), np.array([0.0, 1.0, 1.0, 1.0]),
    ...                                1.0, 1e3, 5e3)
    >>> [round(float(x), 2) for x in k]    # at rest: kappa; start: kappa; s Cf ln(1/z), z = 0.01; sliding
    [5000.0, 5000.0, 4605.17, 0.0]
    """
    out = np.empty(x.shape[0])
    direction, x_r, f_r = 0.0, x[0], 0.0
    for i in range(x.shape[0]):
        direction, x_r, f_r = track_reversal(v[i], x[i], direction, x_r, f_r, s)
        out[i] = _branch_stiffness(x[i], direction, x_r, f_r, Cf, s, kappa)
    return out


@dataclass(frozen=True, eq=False)
class Observation(ResultDisplay):
    """The observer's estimates over a measured trace (SI units).

    Attributes
    ----------
    t, x_meas, u : ndarray
        Time [s], measured displacement [m] and actuator force [N] of the trace (``u`` as
        logged times the input gain; the observer was fed ``u - G``).
    v_hat, f_hat, f_hat_filtered : ndarray
        Velocity [m/s] and friction [N] estimates after processing each sample, and the
        friction estimate after the low-pass eq:3:4:5. ``f_hat`` excludes the load ``G``.
    stiffness : ndarray
        Stiffness the observer used for the interval after each sample [N/m].
    config : Config
        The design that ran (its ``observer.dt`` is the trace's sample time).
    stiffness_schedule : str
        The schedule that ran (:data:`obsdesign.sampled.choices.SCHEDULES`).
    source : str
        Where the trace came from.
    reversals : int
        Motion reversals of the trace (:attr:`Trace.reversals`).
    """

    t: np.ndarray = field(repr=False)
    x_meas: np.ndarray = field(repr=False)
    u: np.ndarray = field(repr=False)
    v_hat: np.ndarray = field(repr=False)
    f_hat: np.ndarray = field(repr=False)
    f_hat_filtered: np.ndarray = field(repr=False)
    stiffness: np.ndarray = field(repr=False)
    config: Config
    stiffness_schedule: str
    source: str
    reversals: int

    @property
    def samples(self) -> int:
        """Number of samples."""
        return int(self.t.size)

    @property
    def sample_time(self) -> float:
        """The observer's sample time [s]."""
        return float(self.config.observer.dt)

    @property
    def duration(self) -> float:
        """Length ``t[-1] - t[0]`` [s]."""
        return float(self.t[-1] - self.t[0])

    def summary(self) -> dict:
        """The JSON summary: ``samples``, ``sample_time``, ``duration``, ``reversals``,
        ``rms_v_hat``, ``rms_f_hat``, ``rms_f_hat_filtered`` (SI units)."""

        def rms(a: np.ndarray) -> float:
            return float(np.sqrt(np.mean(np.square(a))))

        return {"samples": self.samples, "sample_time": self.sample_time, "duration": self.duration,
                "reversals": self.reversals, "rms_v_hat": rms(self.v_hat), "rms_f_hat": rms(self.f_hat),
                "rms_f_hat_filtered": rms(self.f_hat_filtered)}

    def columns(self) -> dict[str, np.ndarray]:
        """The columns of :data:`OBSERVATION_COLUMNS` as a dict."""
        return {name: getattr(self, name) for name in OBSERVATION_COLUMNS}

    def to_csv(self, path: str | os.PathLike) -> None:
        """Write the columns as CSV (header: :data:`OBSERVATION_COLUMNS`), atomically.

        Parameters
        ----------
        path : str or os.PathLike
            Output file.
        """
        buf = io.StringIO()
        np.savetxt(buf, np.column_stack(list(self.columns().values())), delimiter=",",
                   header=",".join(OBSERVATION_COLUMNS), comments="", fmt="%.17g")
        atomic_write(path, buf.getvalue())

    def to_npz(self, path: str | os.PathLike) -> None:
        """Write the columns as a NumPy ``.npz`` archive, atomically.

        Parameters
        ----------
        path : str or os.PathLike
            Output file.
        """
        buf = io.BytesIO()
        np.savez(buf, **self.columns())
        atomic_write(path, buf.getvalue())

    @property
    def _title(self) -> str:
        return f"observation: {self.source}"

    def _rows(self) -> list[tuple[str, object]]:
        s, label = self.summary(), self.config.units.label  # the units of the config's axis
        rows = [("config", self.config.name), ("variant", self.config.observer.variant),
                ("stiffness schedule", self.stiffness_schedule), ("samples", s["samples"]),
                ("sample time [s]", s["sample_time"]), ("duration [s]", s["duration"]),
                ("reversals", s["reversals"]), ("load G fed forward [N]", float(self.config.plant.G)),
                ("rms v_hat [m/s]", s["rms_v_hat"]), ("rms f_hat [N]", s["rms_f_hat"]),
                ("rms f_hat filtered [N]", s["rms_f_hat_filtered"])]
        return [(label(name), value) for name, value in rows]


def _matching_config(cfg: Config, trace: Trace) -> Config:
    dt = cfg.observer.dt
    if abs(dt - trace.sample_time) > DT_TOLERANCE * trace.sample_time:
        raise ValueError(
            f"cfg: expected observer.dt equal to the trace's sample time {trace.sample_time:.9g} s "
            f"(within {DT_TOLERANCE:g} relative), found {dt:.9g} s; the trace's sample time wins (the observer "
            f"runs at the rate the data were sampled): set dt = {trace.sample_time:.9g} in the config's "
            f"[observer] table (cfg.override(dt={trace.sample_time:.9g}))")
    log, axis = ("rotary" if trace.units.rotary else "linear"), ("rotary" if cfg.units.rotary else "linear")
    if log != axis:  # the same numbers in other units (kg and kg m^2, N and N m): a wrong config, not a design
        raise ValueError(f"cfg: expected a {log} axis as the trace's units say ({trace.units.position}), found a "
                         f"{axis} config; give a config with [axis] kind = {log!r} (identify ... -o FILE.toml "
                         "writes one)")
    return cfg


def observe(cfg: "Config | SampledController", trace: Trace, *, stiffness: str | None = None) -> Observation:
    """Run the designed observer and its low-pass filter over a measured trace.

    Parameters
    ----------
    cfg : Config or SampledController
        The design (e.g. ``identify(trace).to_config()``), or the sampled controller whose estimator
        and schedule run (:func:`obsdesign.sampled.sampled_controller`); its ``observer.dt`` must be
        the trace's sample time (the trace's wins; see the module notes).
    trace : Trace
        Measured displacement [m] and actuator force [N].
    stiffness : str, optional
        A name of :data:`obsdesign.sampled.choices.SCHEDULES`: the stiffness schedule of a Config's
        observer (default ``estimated``, with the reversal
        hysteresis of the simulator); ``true`` is the pre-sliding stiffness along the measured
        position and the zero-phase velocity (module notes). Not with a SampledController, which
        has its own.

    Returns
    -------
    Observation

    Raises
    ------
    TypeError
        If ``cfg`` is not a Config or SampledController, or ``trace`` not a Trace.
    ValueError
        If the sample times differ, the trace's axis (linear or rotary) is not the config's, or the
        schedule is unknown.

    Notes
    -----
    The observer (eq:3:1:3 back transformation, exact per-interval recursion) is fed
    ``u - G``; its friction estimate ``f_hat`` is the state ``w3`` of the variant
    (``static``: Coulomb friction with pre-sliding, viscous friction ``sigma v`` modelled;
    ``lag``: Coulomb plus viscous), without the load ``G``.

    Examples
    --------
    >>> import numpy as np
    >>> import obsdesign as od
    >>> cfg = od.load_preset("table1")
    >>> t = np.arange(500) * 1e-3
    >>> tr = Trace(t=t, position=np.zeros(500), force=np.zeros(500), sample_time=1e-3)
    >>> observe(cfg, tr)
    Traceback (most recent call last):
    ...
    ValueError: cfg: expected observer.dt equal to the trace's sample time 0.001 s (within 1e-06 relative), found 0.0001 s; the trace's sample time wins (the observer runs at the rate the data were sampled): set dt = 0.001 in the config's [observer] table (cfg.override(dt=0.001))
    >>> obs = observe(cfg.override(dt=1e-3), tr, stiffness="constant")
    >>> float(np.max(np.abs(obs.v_hat))), float(obs.stiffness[0])
    (0.0, 8000.0)
    """
    if isinstance(cfg, SampledController):
        if stiffness is not None:
            raise ValueError(f"stiffness: a SampledController has its schedule ({cfg.schedule!r}); "
                             f"expected None, found {stiffness!r}")
        ctrl = cfg
    elif isinstance(cfg, Config):
        ctrl = None
    else:
        raise TypeError(f"cfg: expected a Config or a SampledController, found {type(cfg).__name__}")
    if not isinstance(trace, Trace):
        raise TypeError(f"trace: expected a Trace (from obsdesign.data.load_trace), found {type(trace).__name__}")
    _matching_config(ctrl.config if ctrl is not None else cfg, trace)
    if ctrl is None:
        ctrl = sampled_controller(cfg, schedule="estimated" if stiffness is None else stiffness)
    cfg = ctrl.config
    fr = cfg.friction
    x_meas = np.ascontiguousarray(trace.position, dtype=float)
    u_net = np.ascontiguousarray(trace.force - cfg.plant.G, dtype=float)
    n = trace.samples
    if ctrl.schedule == "true":
        v = zero_phase_velocity(trace.position, trace.sample_time)
        v = np.where(np.abs(v) > REVERSAL_THRESHOLD * float(np.max(np.abs(v))), v, 0.0)
        k_true = presliding_stiffness_along(x_meas, v, fr.Cf, fr.s, fr.kappa)
    else:
        k_true = np.zeros(n)
    out = {name: np.empty(n) for name in ("v_hat", "f_hat", "f_hat_filtered", "stiffness")}
    obs_args, est_args, _ = ctrl.kernel_args()
    observe_loop(obs_args, est_args, x_meas, u_net, k_true, *out.values())
    bad = np.flatnonzero(~np.isfinite(out["f_hat"]) | ~np.isfinite(out["v_hat"]))
    if bad.size:
        raise ValueError(f"cfg: expected a finite observer run, found a non-finite estimate at sample {bad[0]} "
                         f"(check the design with 'obsdesign check')")
    for arr in out.values():
        arr.setflags(write=False)
    return Observation(t=trace.t, x_meas=trace.position, u=trace.force, config=cfg, stiffness_schedule=ctrl.schedule,
                       source=trace.source, reversals=trace.reversals, **out)


def model_friction_state(ident, trace: Trace, cfg: Config) -> np.ndarray:
    """What an identified model says the observer's friction state ``w3`` is along a trace [N].

    Parameters
    ----------
    ident : Identification
        The identified model (``m a + Cf sign(v) + sigma v + offset``, per direction for
        ``asymmetric``).
    trace : Trace
        The trace; ``v`` is its zero-phase velocity at the identification's cut-off.
    cfg : Config
        The observer's config: its load ``G`` is fed forward and, for the ``static``
        variant, its viscous term ``sigma v`` is modelled, so neither is in ``w3``.

    Returns
    -------
    ndarray
        ``ident.friction(v) + offset - G`` minus ``cfg.friction.sigma v`` for ``static``.
        With ``cfg = ident.to_config()`` (``G = offset``, same ``sigma``) and the
        ``coulomb-viscous`` model this is ``Cf sign(v)``: the Coulomb friction without offset.

    Examples
    --------
    >>> import numpy as np
    >>> from obsdesign.data import Identification
    >>> ident = Identification(model="coulomb-viscous", m=2.0, sigma=20.0, Cf=1.0, offset=0.5, m_std=0.0,
    ...                        sigma_std=0.0, Cf_std=0.0, offset_std=0.0, nrmse_percent=1.0,
    ...                        condition_number=2.0, samples=1000, sample_time=1e-3, force_peak=5.0)
    >>> t = np.arange(1000) * 1e-3
    >>> tr = Trace(t=t, position=0.01 * np.sin(2 * np.pi * t), force=np.zeros(1000), sample_time=1e-3)
    >>> w3 = model_friction_state(ident, tr, ident.to_config())
    >>> sorted(set(np.round(w3[100:900], 9).tolist()))      # Cf sign(v)
    [-1.0, 1.0]
    """
    v = zero_phase_velocity(trace.position, trace.sample_time, ident.filter_hz)
    w3 = ident.friction(v) + ident.offset - cfg.plant.G
    if cfg.observer.variant == "static":
        w3 = w3 - cfg.friction.sigma * v
    return np.asarray(w3, dtype=float)
