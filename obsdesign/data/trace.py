"""Measured traces: displacement and actuator force on a uniform time base.

A :class:`Trace` is what the package needs from a measurement: the encoder
displacement ``x`` [m] (the paper's only measured state, eq:2:1) and the
actuator force ``u`` [N] on a uniformly sampled time base. :func:`load_trace`
reads one from any log file :func:`obsdesign.data.logfile.read_log` reads (CSV, MATLAB,
TDMS, MDF4, HDF5, MCAP, Parquet; channels by name, units from the file or given) and refuses anything it cannot use with one clear
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
from .csvfile import parse_decimal, parse_delimiter
from .logfile import common_time, format_of, read_log
from .units import DEFAULT_UNITS, Units, check_plausible, column_unit, parse_unit

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


def _plausibility(units: Units, position: np.ndarray, step: float) -> tuple[str, ...]:
    speed = float(np.max(np.abs(np.diff(position)))) / step
    return check_plausible(units, sample_time=step, position_range=float(np.ptp(position)), speed=speed)


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
        position range or speed that does not fit a servo axis, naming the likely unit error; and
        a unit given that overrides another one written in the file.
    format : str
        The file's format (``'CSV'``, ``'TDMS'``, ...; ``'memory'`` for a trace built in Python).
    metadata : dict
        The file's metadata (a CSV's header block, the format's properties) and how the time
        base was found (``time base``).

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
    format: str = "memory"
    metadata: dict = field(default_factory=dict, repr=False)

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
            object.__setattr__(self, "warnings", _plausibility(self.units, self.position, step))

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


def load_trace(path: str | os.PathLike, *, position: str, input: str, time: str | None = None,
               sample_time: float | None = None, input_gain: float = 1.0, time_unit: str | None = None,
               position_unit: str | None = None, input_unit: str | None = None, resolution: float | None = None,
               rotary: bool = False, rated: str | None = None, delimiter: str | None = None,
               decimal: str | None = None) -> Trace:
    """Load a measured trace from a log file (CSV, MATLAB, TDMS, MDF4, HDF5, MCAP, Parquet).

    The file is read by :func:`obsdesign.data.logfile.read_log` (the format by its extension);
    the channels are picked by name and converted to SI by :class:`obsdesign.data.units.Units`.

    Parameters
    ----------
    path : str or path-like
        A log file: ``.csv`` (a header row of column names, then numeric rows; a header block above
        and a units row below the names are read, the delimiter and decimal mark detected), ``.mat``
        (variables), ``.tdms``, ``.mf4``, ``.h5``, ``.mcap``, ``.parquet`` (channels by name,
        ``group/channel`` where the format has groups; the optional extra of the format installed).
    position : str
        Column, variable or channel holding the displacement, in ``position_unit``.
    input : str
        Column, variable or channel holding the actuator input, in ``input_unit``; taken to the SI unit
        of its kind (A, V, N, N m), times ``input_gain`` gives the force [N] (the torque [N m] of a
        rotary axis).
    time : str, optional
        Column, variable or channel holding the time, in ``time_unit``. Without it (and without
        ``sample_time``) the time base is the file's own where it has one (TDMS ``wf_increment``, the
        MDF master channel, MCAP message stamps).
    sample_time : float, optional
        Sample time [s] (always seconds). With a time column (or the file's own time base), that is
        used if its mean step agrees within 1 %.
    input_gain : float
        Conversion of the input's SI unit to force [N/A, N/V; N m/A for a rotary axis], e.g. the
        actuator gain 35.15065188 N/V of the EMPS benchmark whose input is a voltage. Negative values
        (a sign convention) are allowed (an identification that comes out with a negative
        mass then warns to check the sign); 0, NaN and infinity are refused.
    time_unit, position_unit, input_unit : str, optional
        Units of the columns (any unit pint parses whose dimension fits, see
        :class:`obsdesign.data.units.Units`: ``'ms'``, ``'mm'``, ``'deg'``, ``'counts'``, ``'mA'``,
        ``'mN m'``, ``'%'``). Default: the unit the file writes for the column (``pos [mm]``, a units
        row, ``pos_mm``, the format's metadata), else ``s``, ``m`` and (input) ``N`` with a gain of 1,
        else ``V``. A unit given that differs from the file's is used, with a warning.
    resolution : float, optional
        Size of one encoder count [m, or rad with ``rotary``], with a position in counts.
    rotary : bool
        A rotary axis with the position in counts (an angle or a torque implies it).
    rated : str, optional
        The rated current or torque (``'2.5 A'``) that an input in ``%`` is a fraction of.
    delimiter : {',', ';', 'tab', 'space', '|'}, optional
        The CSV delimiter; default: detected.
    decimal : {'.', ','}, optional
        The CSV decimal mark; default: detected (a comma where the delimiter is not one and the
        rows hold commas but no points).

    Returns
    -------
    Trace

    Raises
    ------
    ValueError
        Unknown extension, missing file, a file that is not what its extension says (truncated, empty,
        another format), a CSV whose rows are not numbers (digit grouping named as such), a missing
        column (the message lists the available names), two columns of the same name (after stripping
        spaces, quotes and a unit in brackets), a unit of the wrong dimension (naming the column, the
        unit and the dimension expected), the same column (or the same data) for two of position,
        input and time, a scalar where a column is expected, non-finite values (column and first bad
        index), |values| above :data:`MAX_MAGNITUDE`, a sample time outside :data:`SAMPLE_TIME_RANGE`,
        not enough memory to read a ``.mat`` file, fewer than 100 samples, time not strictly
        increasing, non-uniform sampling (jitter over 1 % of the step), a time column inconsistent
        with ``sample_time``, an input gain of 0 or non-finite.
    TypeError
        Names that are not strings, gains or sample times that are not numbers.
    obsdesign.data.logfile.MissingExtra
        The format's library is not installed (an ``ImportError`` naming the ``pip install`` line).

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
    >>> tr.samples, tr.sample_time, float(tr.force[0]), tr.units.input
    (500, 0.001, 1.0, 'volt')
    >>> load_trace("run.txt", position="x", input="u")
    Traceback (most recent call last):
    ...
    ValueError: path: expected a log file (.csv, .mat, .tdms, .mf4, .mdf, .h5, .hdf5, .hdf, .mcap, .parquet, .pq), found extension '.txt'
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path: expected a file path, found {type(path).__name__} {path!r}")
    p = Path(path)
    format_of(p)
    position = _check_name("position", position)
    input = _check_name("input", input)
    time = _check_name("time", time, optional=True)
    for param, other, name in (("input", "position", input), ("time", "position", time), ("time", "input", time)):
        if name is not None and name == {"position": position, "input": input}[other]:
            raise ValueError(f"{param}: expected a column other than the {other} column, found {name!r} for both")
    gain = _check_gain(input_gain)
    for param, value in (("time_unit", time_unit), ("position_unit", position_unit), ("input_unit", input_unit)):
        if value is not None:
            parse_unit(param, value, param.split("_")[0])
    delimiter = parse_delimiter(delimiter)
    decimal = parse_decimal(decimal)
    step = None if sample_time is None else check_sample_time(
        "sample_time", _check_positive("sample_time", sample_time), "sample_time")
    log = read_log(p, delimiter=delimiter, decimal=decimal)
    kind = log.kind
    ch_x, ch_u = log.pick("position", position), log.pick("input", input)
    ch_t = None if time is None else log.pick("time", time)
    x_label, u_label = f"{kind} {position!r}", f"{kind} {input!r}"
    t_label = None if time is None else f"{kind} {time!r}"
    notes = []
    chosen = {}
    for role, given, ch, label in (("time", time_unit, ch_t, t_label), ("position", position_unit, ch_x, x_label),
                                   ("input", input_unit, ch_u, u_label)):
        if ch is None:
            chosen[role] = given or DEFAULT_UNITS[role]
            continue
        chosen[role], note = column_unit(role, given, ch.unit, ch.unit_from, label)
        if note:
            notes.append(note)
    units = Units(time=chosen["time"], position=chosen["position"], input=chosen["input"], resolution=resolution,
                  rotary=rotary, rated=rated)
    x_logged = _check_column("position", x_label, ch_x.values)
    x = x_logged * units.position_scale
    u_logged = _check_column("input", u_label, ch_u.values)
    u = u_logged * units.input_scale
    if u.size != x.size:
        raise ValueError(f"input: expected {x.size} samples like {x_label}, found {u.size} in {u_label}")
    if np.array_equal(x_logged, u_logged):
        raise ValueError(f"input: expected the actuator input, found in {u_label} the same data as in {x_label}")
    if float(np.max(np.abs(u))) * abs(gain) > MAX_MAGNITUDE:
        F = units.force_unit
        raise ValueError(f"input_gain: expected |input_gain x input| <= {MAX_MAGNITUDE:g} {F}, found "
                         f"{float(np.max(np.abs(u))) * abs(gain):g} {F} (input_gain = {gain:g}, {u_label})")
    metadata = dict(log.metadata)
    own = common_time(log, ch_x, ch_u, x_label, u_label) if ch_t is None else None
    if ch_t is not None or own is not None:
        if ch_t is not None:
            t_logged = _check_column("time", t_label, ch_t.values)
            t = t_logged * units.time_scale
            for other, label in ((x_logged, x_label), (u_logged, u_label)):
                if np.array_equal(t_logged, other):
                    raise ValueError(f"time: expected the time base, found in {t_label} the same data as in {label}")
            metadata["time base"] = t_label
        else:
            t_label = f"the file's time base of {x_label}"
            t = _check_column("time", t_label, own)
            metadata["time base"] = t_label
        if t.size != x.size:
            raise ValueError(f"time: expected {x.size} samples like {x_label}, found {t.size} in {t_label}")
        t_step = _check_time(t, t_label)
        if step is not None and abs(t_step - step) > JITTER_TOLERANCE * step:
            raise ValueError(f"time, sample_time: expected agreement within {100 * JITTER_TOLERANCE:g} %, found "
                             f"a mean step of {t_step:.6g} s in {t_label} and sample_time = {step:.6g} s")
        step = t_step
    elif step is not None:
        t = np.arange(x.size) * step
        metadata["time base"] = f"sample_time {step:.6g} s"
    else:
        raise ValueError(f"time, sample_time: expected a time column name or a sample time [s], found neither "
                         f"(and {log.name!r} gives {x_label} no time base of its own)")
    warnings = tuple(notes) + _plausibility(units, x, step) if notes else ()
    return Trace(t=t, position=x, force=gain * u, sample_time=step, source=p.name,
                 names={"position": position, "input": input, "time": time}, input_gain=gain, units=units,
                 warnings=warnings, format=log.format, metadata=metadata)
