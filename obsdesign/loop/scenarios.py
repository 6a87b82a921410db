"""Scenarios: reference trajectories, open-loop inputs and band-limited noise.

A scenario is chosen by name (its default options) or by a small frozen spec
holding its options:

=============  ===========  ========================  ==============================================
scenario       loop         spec                      signal
=============  ===========  ========================  ==============================================
excitation     open loop    :class:`Excitation`       band-limited random force, RMS ``force_rms``
                                                      (default 1 N), bandwidth ``bandwidth`` (default
                                                      5 Hz): the paper's numerical illustration
constant       open loop    :class:`ConstantForce`    constant force ``force`` (default 1 N)
positioning    closed loop  :class:`Positioning`      steps ``0 -> step_size`` at ``step_up``, back to
                                                      0 at ``step_down`` (defaults 1 mm, 0.5 s, 3.0 s,
                                                      end 6.0 s), like Fig. expref(a)
tracking       closed loop  :class:`Chirp`            linear up-chirp 0.01 -> 3 Hz over the run
                                                      (default 60 s), amplitude so that the peak
                                                      reference velocity is 0.1 m/s, Fig. expref(b)
=============  ===========  ========================  ==============================================

Examples
--------
>>> sc = build_scenario("positioning", dt=1e-3)
>>> sc.duration, sc.steps, sc.holds
(6.0, (0.5, 3.0), ((0.5, 3.0), (3.0, 6.0)))
>>> float(sc.x_ref[1000])  # 1 mm after the first step
0.001
>>> build_scenario(Positioning(step_size=2e-3, step_down=1.0), dt=1e-3, duration=2.0).holds
((0.5, 1.0), (1.0, 2.0))
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Union

from .._validate import FINITE, NONNEGATIVE, POSITIVE, check_choice

if TYPE_CHECKING:  # numpy loads on first use: the command line reads SCENARIOS without it
    import numpy as np

__all__ = ["hold_samples", "SCENARIOS", "Scenario", "ScenarioSpec", "Excitation", "ConstantForce", "Positioning", "Chirp",
           "scenario_spec", "build_scenario", "band_limited_noise", "chirp_frequency", "CHIRP_BANDS",
           "CHIRP_BAND_LABELS"]

CHIRP_F0, CHIRP_F1, CHIRP_PEAK_VELOCITY = 0.01, 3.0, 0.1
#: Edges [Hz] of the chirp-frequency bands in which tracking errors are reported.
CHIRP_BANDS = (0.01, 0.1, 0.3, 1.0, 3.0)
#: ``(label, low, high)`` of each band, e.g. ``("0.01-0.1 Hz", 0.01, 0.1)``.
CHIRP_BAND_LABELS = tuple((f"{lo:g}-{hi:g} Hz", lo, hi) for lo, hi in zip(CHIRP_BANDS[:-1], CHIRP_BANDS[1:]))


@dataclass(frozen=True, kw_only=True)
class Excitation:
    """Open loop: band-limited white force of RMS ``force_rms`` [N] over ``[0, bandwidth]`` Hz.

    Attributes
    ----------
    force_rms : float
        RMS of the force [N].
    bandwidth : float
        Its bandwidth [Hz].
    """

    name: ClassVar[str] = "excitation"
    open_loop: ClassVar[bool] = True
    default_duration: ClassVar[float] = 10.0
    force_rms: float = 1.0
    bandwidth: float = 5.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "force_rms", NONNEGATIVE.check("input_force", self.force_rms))
        object.__setattr__(self, "bandwidth", POSITIVE.check("excitation_bandwidth", self.bandwidth))


@dataclass(frozen=True, kw_only=True)
class ConstantForce:
    """Open loop: a constant force ``force`` [N].

    Attributes
    ----------
    force : float
        The force [N].
    """

    name: ClassVar[str] = "constant"
    open_loop: ClassVar[bool] = True
    default_duration: ClassVar[float] = 5.0
    force: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "force", FINITE.check("input_force", self.force))


@dataclass(frozen=True, kw_only=True)
class Positioning:
    """Closed loop: a step of ``step_size`` [m] at ``step_up`` [s], back to 0 at ``step_down`` [s].

    Attributes
    ----------
    step_size : float
        Step height [m].
    step_up, step_down : float
        Times of the step and of the return to 0 [s].
    """

    name: ClassVar[str] = "positioning"
    open_loop: ClassVar[bool] = False
    default_duration: ClassVar[float] = 6.0
    step_size: float = 1e-3
    step_up: float = 0.5
    step_down: float = 3.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "step_size", FINITE.check("step_size", self.step_size))
        object.__setattr__(self, "step_up", NONNEGATIVE.check("step_up", self.step_up))
        object.__setattr__(self, "step_down", NONNEGATIVE.check("step_down", self.step_down))


@dataclass(frozen=True, kw_only=True)
class Chirp:
    """Closed loop: a linear up-chirp reference from ``f0`` to ``f1`` [Hz] over the run, with the
    amplitude that makes its peak velocity ``peak_velocity`` [m/s].

    Attributes
    ----------
    f0, f1 : float
        Start and end frequency [Hz].
    peak_velocity : float
        Peak velocity of the reference [m/s].
    """

    name: ClassVar[str] = "tracking"
    open_loop: ClassVar[bool] = False
    default_duration: ClassVar[float] = 60.0
    f0: float = CHIRP_F0
    f1: float = CHIRP_F1
    peak_velocity: float = CHIRP_PEAK_VELOCITY

    def __post_init__(self) -> None:
        for name in ("f0", "f1", "peak_velocity"):
            object.__setattr__(self, name, POSITIVE.check(name, getattr(self, name)))


ScenarioSpec = Union[Excitation, ConstantForce, Positioning, Chirp]
_SPECS: dict[str, Any] = {cls.name: cls for cls in (Excitation, ConstantForce, Positioning, Chirp)}
#: Scenario names, in documentation order.
SCENARIOS = tuple(_SPECS)
OPEN_LOOP = tuple(name for name, cls in _SPECS.items() if cls.open_loop)
DEFAULT_DURATION = {name: cls.default_duration for name, cls in _SPECS.items()}


def scenario_spec(scenario: Any) -> ScenarioSpec:
    """The spec of a scenario given by name (its defaults) or as a spec.

    Parameters
    ----------
    scenario : str or scenario spec
        A name of :data:`SCENARIOS` or a spec.

    >>> scenario_spec("constant")
    ConstantForce(force=1.0)
    """
    if isinstance(scenario, tuple(_SPECS.values())):
        return scenario
    return _SPECS[check_choice("scenario", scenario, SCENARIOS)]()


@dataclass(frozen=True)
class Scenario:
    """Sampled signals of one scenario.

    Attributes
    ----------
    spec : ScenarioSpec
    dt, duration : float
        Sample time and length [s].
    x_ref : ndarray
        Reference displacement [m] per sample (zeros for open loop).
    u_open : ndarray
        Open-loop force [N] per sample (zeros for closed loop).
    steps : tuple of float
        Step times [s] (positioning).
    holds : tuple of (float, float)
        Hold intervals [s] after each step (positioning).
    """

    spec: Any
    dt: float
    duration: float
    x_ref: np.ndarray = field(repr=False)
    u_open: np.ndarray = field(repr=False)
    steps: tuple = ()
    holds: tuple = ()

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def open_loop(self) -> bool:
        return self.spec.open_loop


def band_limited_noise(n: int, dt: float, rms: float, bandwidth: float, seed) -> np.ndarray:
    """White Gaussian noise limited to ``[0, bandwidth]`` Hz by an ideal filter (FFT mask).

    Parameters
    ----------
    n : int
        Number of samples.
    dt : float
        Sample time [s].
    rms : float
        Expected RMS.
    bandwidth : float
        Bandwidth [Hz].
    seed : int or numpy.random.SeedSequence
        Seed of the draw.

    The result has expected RMS ``rms`` (one-sided flat spectrum up to ``bandwidth``,
    or up to the Nyquist frequency if that is lower).

    Examples
    --------
    >>> import numpy as np
    >>> x = band_limited_noise(200_000, 1e-4, 2.0, 50.0, seed=1)
    >>> round(float(np.sqrt(np.mean(x * x))), 1)
    2.0
    """
    import numpy as np
    if rms == 0.0:
        return np.zeros(n)
    rng = np.random.default_rng(seed)
    white = rng.standard_normal(n)
    nyquist = 0.5 / dt
    if bandwidth >= nyquist:
        return rms * white
    spec = np.fft.rfft(white)
    spec[np.fft.rfftfreq(n, dt) > bandwidth] = 0.0
    return np.fft.irfft(spec, n) * (rms / math.sqrt(bandwidth / nyquist))


def chirp_frequency(t: np.ndarray, duration: float, spec: Chirp | None = None) -> np.ndarray:
    """Instantaneous frequency [Hz] of the tracking chirp.

    Parameters
    ----------
    t : ndarray
        Times [s].
    duration : float
        Length of the chirp [s].
    spec : Chirp, optional
        The chirp (default :class:`Chirp`).
    """
    spec = spec or Chirp()
    return spec.f0 + (spec.f1 - spec.f0) * t / duration


def hold_samples(start: float, end: float, dt: float, n: int) -> tuple[int, int]:
    """The sample range ``range(i0, i1)`` of a run of ``n`` samples that belongs to a hold [s].

    A sample belongs to the hold from ``start`` to ``end`` when its time is nearest to a time in
    ``[start, end)``.

    Parameters
    ----------
    start, end : float
        The hold [s].
    dt : float
        Sample period [s].
    n : int
        Samples of the run.

    Returns
    -------
    tuple of int
        ``(i0, i1)``, clipped to the run.

    Examples
    --------
    >>> hold_samples(0.5, 3.0, 1e-3, 4000), hold_samples(3.0, 4.0, 1e-3, 4000)
    ((500, 3000), (3000, 4000))
    """
    i0, i1 = int(math.ceil(start / dt - 0.5)), int(math.ceil(end / dt - 0.5))
    return max(i0, 0), min(i1, n)


def build_scenario(scenario: Any, *, dt: float, duration: float | None = None, seed=0) -> Scenario:
    """Sample the signals of a scenario (a name or a spec) at ``dt`` over ``duration`` [s].

    Parameters
    ----------
    scenario : str or scenario spec
        A name of :data:`SCENARIOS` or a spec.
    dt : float
        Sample time [s].
    duration : float, optional
        Length [s] (the scenario's default).
    seed : int or numpy.random.SeedSequence
        Seed of the excitation.

    Raises
    ------
    ValueError
        Unknown name, a duration shorter than two samples, or inconsistent step times.
    """
    spec = scenario_spec(scenario)
    duration = spec.default_duration if duration is None else POSITIVE.check("duration", duration)
    n = int(round(duration / dt))
    if n < 2:
        raise ValueError(f"duration: expected at least 2 samples of dt = {dt:g} s, found {duration!r} s")
    if isinstance(spec, Excitation):
        return Scenario(spec, dt, duration, _zeros(n), band_limited_noise(n, dt, spec.force_rms, spec.bandwidth, seed))
    if isinstance(spec, Positioning):
        up, down = spec.step_up, spec.step_down
        if not up < down < duration:
            raise ValueError(
                f"step_down: expected step_up < step_down < duration, found {up:g} < {down:g} < {duration:g} s"
            )
        holds = ((up, down), (down, duration))
        for name, (start, end) in zip(("step_down", "duration"), holds):
            i0, i1 = hold_samples(start, end, dt, n)
            if i1 - i0 < 2:  # the step metrics of a hold need two samples of it
                raise ValueError(f"{name}: expected a hold of at least 2 samples of dt = {dt:g} s from {start:g} s, "
                                 f"found {max(i1 - i0, 0)} up to {end:g} s")
        x_ref, u_open = _deterministic_signals(spec, dt, duration, n)
        return Scenario(spec, dt, duration, x_ref, u_open, (up, down), holds)
    x_ref, u_open = _deterministic_signals(spec, dt, duration, n)
    return Scenario(spec, dt, duration, x_ref, u_open)


def _zeros(n: int) -> np.ndarray:
    import numpy as np
    out = np.zeros(n)
    out.flags.writeable = False
    return out


@functools.lru_cache(maxsize=8)
def _deterministic_signals(spec, dt: float, duration: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``(x_ref, u_open)`` of a scenario without random parts, read-only and cached (sweeps and
    repeated runs of one scenario share them)."""
    x_ref, u_open = _signals(spec, dt, duration, n)
    x_ref.flags.writeable = False
    u_open.flags.writeable = False
    return x_ref, u_open


def _signals(spec, dt: float, duration: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    import numpy as np
    zeros = np.zeros(n)
    if isinstance(spec, ConstantForce):
        return zeros, np.full(n, spec.force)
    t = np.arange(n) * dt
    if isinstance(spec, Positioning):
        up, down = spec.step_up, spec.step_down
        return np.where((t >= up - 0.5 * dt) & (t < down - 0.5 * dt), spec.step_size, 0.0), zeros
    amplitude = spec.peak_velocity / (2 * math.pi * spec.f1)
    # 2 pi (f0 t + 0.5 (f1 - f0) t^2 / duration), evaluated in place in that order of operations
    quadratic = t * (0.5 * (spec.f1 - spec.f0))
    quadratic *= t
    quadratic /= duration
    phase = spec.f0 * t
    phase += quadratic
    phase *= 2 * math.pi
    np.sin(phase, out=phase)
    phase *= amplitude
    return phase, zeros
