"""Measured traces: displacement and actuator force on a uniform time base.

A :class:`Trace` is what the package needs from a measurement: the encoder
displacement ``x`` [m] (the paper's only measured state, eq:2:1) and the
actuator force ``u`` [N] on a uniformly sampled time base. :func:`load_trace`
reads one from a CSV file (header row, columns by name) or a MATLAB ``.mat``
file (variables by name) and refuses anything it cannot use with one clear
error naming the parameter, what was expected and what was found.

Examples
--------
>>> import numpy as np
>>> t = np.arange(200) * 1e-3
>>> tr = Trace(t=t, position=1e-3 * np.sin(2 * np.pi * 5 * t), force=np.cos(2 * np.pi * 5 * t),
...            sample_time=1e-3, source="example")
>>> tr.samples, round(tr.duration, 3), tr.reversals
(200, 0.199, 2)
"""

from __future__ import annotations

import io
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._io import atomic_write
from .._validate import SAMPLE_TIME
from .csvfile import parse_delimiter, read_csv
from .units import Units, check_plausible

__all__ = ["Trace", "load_trace", "MIN_SAMPLES", "JITTER_TOLERANCE", "MAX_MAGNITUDE", "SAMPLE_TIME_RANGE",
           "check_sample_time", "zero_phase_velocity"]

#: Fewest samples a trace may hold (the identification filters and decimates).
MIN_SAMPLES = 100
#: Largest admissible deviation of a time step from the median step, relative to the step.
JITTER_TOLERANCE = 0.01
#: Velocity threshold of :attr:`Trace.reversals`, relative to the largest |velocity|.
REVERSAL_THRESHOLD = 0.01
#: Largest admissible |value| of a column: its square (and a sum of 1e6 squares) stays finite.
MAX_MAGNITUDE = 1e150
#: Usable sample times [s], the rule of a controller's dt (:data:`obsdesign._validate.SAMPLE_TIME`):
#: outside, the time column is in the wrong unit (or not a time).
SAMPLE_TIME_RANGE = (SAMPLE_TIME.low, SAMPLE_TIME.high)
_EXTENSIONS = (".csv", ".mat")


# -- validation helpers (one per concept) ------------------------------------------------------

def _check_name(param: str, value: object, *, optional: bool = False) -> str | None:
    if value is None and optional:
        return None
    if not isinstance(value, str) or not value:
        what = "a column name (non-empty string)" + (" or None" if optional else "")
        raise TypeError(f"{param}: expected {what}, found {type(value).__name__} {value!r}")
    return value


def _check_gain(value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise TypeError(f"input_gain: expected a finite nonzero number, found {type(value).__name__} {value!r}")
    gain = float(value)
    if not math.isfinite(gain) or gain == 0.0:
        raise ValueError(f"input_gain: expected a finite nonzero number, found {gain!r}")
    return gain


def _check_positive(param: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise TypeError(f"{param}: expected a finite number > 0, found {type(value).__name__} {value!r}")
    number = float(value)
    if not (math.isfinite(number) and number > 0.0):
        raise ValueError(f"{param}: expected a finite number > 0, found {number!r}")
    return number


def _check_column(param: str, label: str, values: object) -> np.ndarray:
    """A finite 1-D float column of at least :data:`MIN_SAMPLES` samples, |values| <= :data:`MAX_MAGNITUDE`."""
    if type(values).__module__.startswith("scipy.sparse") and hasattr(values, "toarray"):
        shape = getattr(values, "shape", ())
        if len(shape) > 1 and sum(d > 1 for d in shape) > 1:
            raise ValueError(f"{param}: expected a vector (n x 1 or 1 x n), found {label}, a sparse matrix of shape "
                             f"{' x '.join(map(str, shape))}")
        values = values.toarray()  # a sparse vector (MATLAB's sparse()): its samples are the dense values
    arr = np.asarray(values)
    if arr.dtype.kind not in "biuf":
        raise TypeError(f"{param}: expected a numeric column, found {label} of dtype {arr.dtype}")
    if arr.size == 1:
        raise ValueError(f"{param}: expected a column of samples, found a scalar {label} "
                         f"({' x '.join(map(str, arr.shape)) or 'scalar'})")
    if arr.ndim > 1 and sum(d > 1 for d in arr.shape) > 1:
        raise ValueError(f"{param}: expected a vector (n x 1 or 1 x n), found {label} of shape "
                         f"{' x '.join(map(str, arr.shape))}")
    arr = arr.astype(float).ravel()
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise ValueError(f"{param}: expected finite values, found {float(arr[bad[0]])!r} in {label} at index {bad[0]}")
    if arr.size < MIN_SAMPLES:
        raise ValueError(f"{param}: expected at least {MIN_SAMPLES} samples, found {arr.size} in {label}")
    big = np.flatnonzero(np.abs(arr) > MAX_MAGNITUDE) if param not in ("t", "time") else ()  # time: its step
    if len(big):
        raise ValueError(f"{param}: expected |values| <= {MAX_MAGNITUDE:g} (larger ones overflow when squared), "
                         f"found {float(arr[big[0]]):g} in {label} at index {big[0]}; check the unit")
    return arr


def _check_time(t: np.ndarray, label: str) -> float:
    """Strictly increasing, uniform within :data:`JITTER_TOLERANCE`; returns the mean step."""
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0.0)
    if bad.size:
        i = bad[0] + 1
        raise ValueError(f"time: expected strictly increasing values, found {float(t[i])!r} after "
                         f"{float(t[i - 1])!r} in {label} at index {i}")
    median = float(np.median(steps))
    jitter = np.abs(steps - median) / median
    worst = int(np.argmax(jitter))
    if jitter[worst] > JITTER_TOLERANCE:
        raise ValueError(f"time: expected uniform sampling (jitter <= {100 * JITTER_TOLERANCE:g} % of the step "
                         f"{median:.6g} s), found {100 * jitter[worst]:.3g} % in {label} at index {worst + 1}")
    return check_sample_time("time", float((t[-1] - t[0]) / (t.size - 1)), f"the mean step of {label}")


def check_sample_time(param: str, step: float, label: str) -> float:
    """``step`` if it lies in :data:`SAMPLE_TIME_RANGE`, else ``ValueError`` naming ``param`` and ``label``.

    Parameters
    ----------
    param : str
        The parameter for the message (``time``, ``sample_time``).
    step : float
        The sample time [s].
    label : str
        Where it came from, for the message.
    """
    low, high = SAMPLE_TIME_RANGE
    if not low <= step <= high:
        raise ValueError(f"{param}: expected a sample time in [{low:g}, {high:g}] s, found {step:.6g} s "
                         f"({label}); check the time unit (s, not ms or us) or the column")
    return step


def zero_phase_velocity(position: np.ndarray, sample_time: float, cutoff_hz: float | None = None) -> np.ndarray:
    """Velocity [m/s] by a zero-phase Butterworth low-pass and central differences.

    Parameters
    ----------
    position : ndarray
        Position samples [m].
    sample_time : float
        Sample time [s].
    cutoff_hz : float, optional
        Cut-off of the zero-phase filter [Hz].

    The filter is 4th order, run forwards and backwards (``sosfiltfilt``), with
    cut-off ``cutoff_hz`` (default a tenth of the sampling rate, the rule of
    :func:`obsdesign.data.identify`); central differences are exact for a
    parabola and add no phase.

    Examples
    --------
    >>> t = np.arange(1000) * 1e-3
    >>> v = zero_phase_velocity(0.5 * t**2, 1e-3)   # x = t^2 / 2, v = t
    >>> bool(np.allclose(v[100:900], t[100:900], atol=1e-9))
    True
    """
    from scipy import signal

    fs = 1.0 / sample_time
    cutoff = 0.1 * fs if cutoff_hz is None else cutoff_hz
    sos = signal.butter(4, cutoff, fs=fs, output="sos")
    return np.gradient(signal.sosfiltfilt(sos, position), sample_time)


# -- the trace -----------------------------------------------------------------------------------

@dataclass(frozen=True, kw_only=True, eq=False)
class Trace:
    """A uniformly sampled measurement: displacement and actuator force.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time [s], strictly increasing and uniform.
    position : ndarray, shape (n,)
        Measured displacement ``x`` [m].
    force : ndarray, shape (n,)
        Actuator force ``u`` [N] (the logged input times ``input_gain``).
    sample_time : float
        Mean time step [s].
    source : str
        Where the data came from (file name).
    names : dict
        The column or variable names used: keys ``position``, ``input`` and ``time``
        (``None`` when the time base came from ``sample_time``).
    input_gain : float
        Factor [N per logged unit] applied to the input column (1.0: logged in N).
    units : Units
        The logged columns' units (:class:`obsdesign.data.units.Units`); the arrays here are SI
        (m or rad, s, N or N m).
    warnings : tuple of str
        Plausibility warnings (:func:`obsdesign.data.units.check_plausible`): a sample time,
        position range or speed that does not fit a servo axis, naming the likely unit error.

    Notes
    -----
    Constructed directly, a trace is validated like a loaded one: equal lengths,
    finite values, at least :data:`MIN_SAMPLES` samples, uniform time.
    """

    t: np.ndarray = field(repr=False)
    position: np.ndarray = field(repr=False)
    force: np.ndarray = field(repr=False)
    sample_time: float
    source: str = "memory"
    names: dict = field(default_factory=lambda: {"position": "position", "input": "force", "time": "t"})
    input_gain: float = 1.0
    units: Units = field(default_factory=Units)
    warnings: tuple[str, ...] = field(default=(), repr=False)

    def __post_init__(self) -> None:
        cols = {name: _check_column(name, name, getattr(self, name)) for name in ("t", "position", "force")}
        lengths = {name: arr.size for name, arr in cols.items()}
        if len(set(lengths.values())) > 1:
            raise ValueError(f"force: expected columns of equal length, found {lengths}")
        _check_time(cols["t"], "t")
        step = check_sample_time("sample_time", _check_positive("sample_time", self.sample_time), "sample_time")
        for name, arr in cols.items():
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "sample_time", step)
        object.__setattr__(self, "input_gain", _check_gain(self.input_gain))
        if not isinstance(self.source, str):
            raise TypeError(f"source: expected a string, found {type(self.source).__name__}")
        if not isinstance(self.units, Units):
            raise TypeError(f"units: expected a Units, found {type(self.units).__name__}")
        if not self.warnings:
            speed = float(np.max(np.abs(np.diff(self.position)))) / step
            object.__setattr__(self, "warnings", check_plausible(
                self.units, sample_time=step, position_range=float(np.ptp(self.position)), speed=speed))

    @property
    def samples(self) -> int:
        """Number of samples."""
        return int(self.t.size)

    @property
    def duration(self) -> float:
        """Length ``t[-1] - t[0]`` [s]."""
        return float(self.t[-1] - self.t[0])

    @property
    def reversals(self) -> int:
        """Number of motion reversals.

        Rule: the velocity is the zero-phase differentiated position
        (:func:`zero_phase_velocity`, cut-off a tenth of the sampling rate);
        samples with ``|v|`` at or below 1 % of the largest ``|v|`` are ignored, and
        the sign changes between the remaining consecutive samples are counted.
        Encoder noise at standstill therefore does not count as motion.
        """
        v = zero_phase_velocity(self.position, self.sample_time)
        peak = float(np.max(np.abs(v)))
        if peak == 0.0:
            return 0
        signs = np.sign(v[np.abs(v) > REVERSAL_THRESHOLD * peak])
        return int(np.count_nonzero(signs[1:] != signs[:-1]))

    def __repr__(self) -> str:
        return (f"Trace(source={self.source!r}, samples={self.samples}, sample_time={self.sample_time:.6g}, "
                f"duration={self.duration:.6g})")

    def to_csv(self, path: str | os.PathLike) -> None:
        """Write ``t,position,force`` (SI units) as CSV, atomically (temporary file, then rename).

        The file loads back with ``load_trace(path, position="position", input="force", time="t")``.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> t = np.arange(100) * 1e-3
        >>> tr = Trace(t=t, position=t**2, force=np.ones(100), sample_time=1e-3)
        >>> with tempfile.TemporaryDirectory() as d:
        ...     tr.to_csv(pathlib.Path(d) / "trace.csv")
        ...     back = load_trace(pathlib.Path(d) / "trace.csv", position="position", input="force", time="t")
        >>> bool(np.array_equal(back.position, tr.position))
        True
        """
        buf = io.StringIO()
        np.savetxt(buf, np.column_stack([self.t, self.position, self.force]), delimiter=",",
                   header="t,position,force", comments="", fmt="%.17g")
        atomic_write(path, buf.getvalue())


# -- loading -------------------------------------------------------------------------------------

def _read_mat(path: Path) -> dict[str, np.ndarray]:
    from scipy import io as sio

    try:
        raw = sio.loadmat(str(path))
    except MemoryError:
        raise ValueError(f"path: not enough memory to read {path.name!r} (a MATLAB file whose variables "
                         "decompress to more than the memory available)") from None
    except Exception as e:  # scipy raises several types for a file that is not MATLAB
        raise ValueError(f"path: expected a MATLAB .mat file (v5 or older), found one scipy cannot read: "
                         f"{path.name!r} ({e})") from e
    return {k: v for k, v in raw.items() if not k.startswith("__")}


def _pick(param: str, name: str, table: dict[str, np.ndarray], kind: str) -> tuple[np.ndarray, str]:
    if name not in table:
        raise ValueError(f"{param}: expected the name of a {kind}, found {name!r}; available: "
                         f"{', '.join(sorted(table)) or 'none'}")
    return table[name], f"{kind} {name!r}"


def load_trace(path: str | os.PathLike, *, position: str, input: str, time: str | None = None,
               sample_time: float | None = None, input_gain: float = 1.0, time_unit: str = "s",
               position_unit: str = "m", input_unit: str | None = None, resolution: float | None = None,
               rotary: bool = False, delimiter: str | None = None) -> Trace:
    """Load a measured trace from a CSV or MATLAB ``.mat`` file.

    Parameters
    ----------
    path : str or path-like
        A ``.csv`` file (UTF-8; ``#`` comment lines anywhere; a header row of column names, then
        numeric rows, split by ``delimiter``) or a ``.mat`` file (read with ``scipy.io.loadmat``;
        variables are columns).
    position : str
        Column or variable holding the displacement, in ``position_unit``.
    input : str
        Column or variable holding the actuator input, in ``input_unit``; times ``input_gain``
        gives the force [N] (the torque [N m] of a rotary axis).
    time : str, optional
        Column or variable holding the time, in ``time_unit``.
    sample_time : float, optional
        Sample time [s] (always seconds). At least one of ``time`` and ``sample_time`` is required;
        with both, the time column is used if its mean step agrees within 1 %.
    input_gain : float
        Conversion of the logged input to force [N/unit], e.g. the actuator gain
        35.15065188 N/V of the EMPS benchmark whose input is a voltage. Negative values
        (a sign convention) are allowed (an identification that comes out with a negative
        mass then warns to check the sign); 0, NaN and infinity are refused.
    time_unit : {'s', 'ms', 'us'}
    position_unit : {'m', 'mm', 'um', 'counts', 'rad'}
        ``rad``: a rotary axis (inertia kg m^2, torque N m); ``counts`` needs ``resolution``.
    input_unit : {'V', 'A', 'N', 'N m'}, optional
        The logged input's unit, named in the identification and the config (default: the force
        unit when ``input_gain`` is 1, else ``V``).
    resolution : float, optional
        Size of one encoder count [m, or rad with ``rotary``], with ``position_unit='counts'``.
    rotary : bool
        A rotary axis with the position in counts (``rad`` implies it).
    delimiter : {',', ';', 'tab', 'space', '|'}, optional
        The CSV delimiter; default: detected from the header and the first row.

    Returns
    -------
    Trace

    Raises
    ------
    ValueError
        Wrong extension, missing file, unreadable or non-UTF-8 CSV, a missing column
        (the message lists the available names), two columns of the same name (after stripping
        spaces and quotes), the same column (or the same data) for two of position, input and time,
        a scalar where a column is expected, non-finite values (column and first bad index),
        |values| above :data:`MAX_MAGNITUDE`, a sample time outside :data:`SAMPLE_TIME_RANGE`,
        not enough memory to read a ``.mat`` file, fewer than 100 samples, time not
        strictly increasing, non-uniform sampling (jitter over 1 % of the step), a time
        column inconsistent with ``sample_time``, an input gain of 0 or non-finite.
    TypeError
        Names that are not strings, gains or sample times that are not numbers.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import numpy as np
    >>> with tempfile.TemporaryDirectory() as d:
    ...     p = pathlib.Path(d) / "run.csv"
    ...     t = np.arange(500) * 1e-3
    ...     rows = np.column_stack([t, np.sin(t), 0.1 * np.cos(t)])
    ...     np.savetxt(p, rows, delimiter=",", header="time,x,u_volt", comments="")
    ...     tr = load_trace(p, position="x", input="u_volt", time="time", input_gain=10.0)
    >>> tr.samples, tr.sample_time, float(tr.force[0])
    (500, 0.001, 1.0)
    >>> load_trace("run.txt", position="x", input="u")
    Traceback (most recent call last):
    ...
    ValueError: path: expected a .csv or .mat file, found extension '.txt'
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path: expected a file path, found {type(path).__name__} {path!r}")
    p = Path(path)
    ext = p.suffix.lower()
    if ext not in _EXTENSIONS:
        raise ValueError(f"path: expected a .csv or .mat file, found extension {p.suffix or '(none)'!r}")
    position = _check_name("position", position)
    input = _check_name("input", input)
    time = _check_name("time", time, optional=True)
    for param, other, name in (("input", "position", input), ("time", "position", time), ("time", "input", time)):
        if name is not None and name == {"position": position, "input": input}[other]:
            raise ValueError(f"{param}: expected a column other than the {other} column, found {name!r} for both")
    gain = _check_gain(input_gain)
    units = Units(time=time_unit, position=position_unit, input=input_unit, resolution=resolution, rotary=rotary)
    delimiter = parse_delimiter(delimiter)
    if ext == ".mat" and delimiter is not None:
        raise ValueError(f"delimiter: expected None for a .mat file (it has no delimiter), found {delimiter!r}")
    step = None if sample_time is None else check_sample_time(
        "sample_time", _check_positive("sample_time", sample_time), "sample_time")
    if time is None and step is None:
        raise ValueError("time, sample_time: expected a time column name or a sample time [s], found neither")
    if not p.is_file():
        raise ValueError(f"path: expected an existing file, found {str(p)!r}")
    table = read_csv(p, delimiter) if ext == ".csv" else _read_mat(p)
    kind = "column" if ext == ".csv" else "variable"

    x_raw, x_label = _pick("position", position, table, kind)
    u_raw, u_label = _pick("input", input, table, kind)
    x_logged = _check_column("position", x_label, x_raw)
    x = x_logged * units.position_scale
    u = _check_column("input", u_label, u_raw)
    if u.size != x.size:
        raise ValueError(f"input: expected {x.size} samples like {x_label}, found {u.size} in {u_label}")
    if np.array_equal(x_logged, u):
        raise ValueError(f"input: expected the actuator input, found in {u_label} the same data as in {x_label}")
    if float(np.max(np.abs(u))) * abs(gain) > MAX_MAGNITUDE:
        raise ValueError(f"input_gain: expected |input_gain x input| <= {MAX_MAGNITUDE:g} N, found "
                         f"{float(np.max(np.abs(u))) * abs(gain):g} N (input_gain = {gain:g}, {u_label})")
    if time is not None:
        t_raw, t_label = _pick("time", time, table, kind)
        t_logged = _check_column("time", t_label, t_raw)
        t = t_logged * units.time_scale
        if t.size != x.size:
            raise ValueError(f"time: expected {x.size} samples like {x_label}, found {t.size} in {t_label}")
        for other, label in ((x_logged, x_label), (u, u_label)):
            if np.array_equal(t_logged, other):
                raise ValueError(f"time: expected the time base, found in {t_label} the same data as in {label}")
        t_step = _check_time(t, t_label)
        if step is not None and abs(t_step - step) > JITTER_TOLERANCE * step:
            raise ValueError(f"time, sample_time: expected agreement within {100 * JITTER_TOLERANCE:g} %, found "
                             f"a mean step of {t_step:.6g} s in {t_label} and sample_time = {step:.6g} s")
        step = t_step
    else:
        t = np.arange(x.size) * step
    return Trace(t=t, position=x, force=gain * u, sample_time=step, source=p.name,
                 names={"position": position, "input": input, "time": time}, input_gain=gain, units=units)
