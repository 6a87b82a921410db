"""Design parameters: plant, friction, sensor, observer and PID specifications.

Every section is a frozen, keyword-only dataclass. Each field carries its unit,
a one-line description and its admissible range in the field metadata; one
validation routine (:func:`_validate_fields`) checks them all in
``__post_init__``, so an invalid value can never be held by a config object.

Configs are read from and written to TOML. Values are only ever parsed as TOML
literals; nothing in a config is evaluated as code.

Examples
--------
>>> import obsdesign as od
>>> cfg = od.load_preset("table1")
>>> cfg.friction.kappa, cfg.observer.variant
(8000.0, 'lag')
>>> round(od.load_preset("vcm").phi, 6)  # derived as K * tau / m
0.040695
>>> od.ObserverSpec(rho=0.0)
Traceback (most recent call last):
...
ValueError: observer.rho: expected a finite number > 0, found 0.0
"""

from __future__ import annotations

import dataclasses
import math
import os
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Mapping, NamedTuple

from ._format import toml_value
from ._io import atomic_write
from ._validate import (DERIVATIVE_N, FINITE, NONNEGATIVE, POSITIVE, SAMPLE_TIME, Choice, FrozenMap,
                        Range, Text, document_fields, param_field, section_from_table, validate_fields)
from .axis import LINEAR, AxisSpec
from .compensation import CompensationSpec
from .hardware import HardwareSpec, move_legacy_delay
from .plant_spec import PlantFrictionSpec

__all__ = ["PlantParams", "FrictionParams", "SensorSpec", "ObserverSpec", "PIDSpec", "CompensationSpec", "HardwareSpec",
           "AxisSpec", "Config", "load_preset", "read_config", "preset_names", "VARIANTS", "PARAMETERS", "SECTIONS", "FieldRow"]

VARIANTS = ("lag", "static")
PID_DESIGNS = ("auto", "paper", "sampled")  #: ``[pid] design`` (:func:`obsdesign.design.pid.resolve_pid`)


@document_fields
@dataclass(frozen=True, kw_only=True)
class PlantParams:
    """Rigid-body plant of eq:2:1, ``m x'' + f = u - g`` with ``u = K u_volt``.

    Examples
    --------
    >>> PlantParams(m=0.538, K=3.28, G=5.27).m
    0.538
    """

    _section = "plant"
    m: float = param_field(POSITIVE, "kg", "moving mass")
    K: float = param_field(POSITIVE, "N/V", "actuator force constant")
    G: float = param_field(FINITE, "N", "known load force, pre-compensated", 0.0)
    u_max: float = param_field(POSITIVE, "V", "actuator voltage limit (saturation)", 10.0)

    def __post_init__(self) -> None:
        validate_fields(self)


@document_fields
@dataclass(frozen=True, kw_only=True)
class FrictionParams:
    """Coulomb friction with pre-sliding (eq:2:3:1-2:3:5) and viscous friction.

    ``beta`` is the viscous lag time constant of eq:2:2:2; ``None`` means
    static viscous friction (the paper's section 4 adjustment).

    Examples
    --------
    >>> FrictionParams(Cf=0.35, sigma=21.1, s=3000, kappa=8000).beta is None
    True
    """

    _section = "friction"
    Cf: float = param_field(POSITIVE, "N", "Coulomb friction level")
    sigma: float = param_field(POSITIVE, "N s/m", "viscous friction coefficient")
    s: float = param_field(POSITIVE, "1/m", "pre-sliding distance scaling factor")
    kappa: float = param_field(POSITIVE, "N/m", "pre-sliding stiffness bound")
    beta: float | None = param_field(
        Range(low=0.0, optional=True), "s", "viscous friction lag time constant", None
    )

    def __post_init__(self) -> None:
        validate_fields(self)


@document_fields
@dataclass(frozen=True, kw_only=True)
class SensorSpec:
    """Displacement sensor: band-limited noise and encoder quantization.

    Examples
    --------
    >>> SensorSpec(noise_rms=1e-6).quantization
    0.0
    """

    _section = "sensor"
    noise_rms: float = param_field(NONNEGATIVE, "m", "RMS of the measurement noise", 0.0)
    noise_bandwidth: float = param_field(POSITIVE, "Hz", "bandwidth of the measurement noise", 1000.0)
    quantization: float = param_field(NONNEGATIVE, "m", "encoder resolution (0: none)", 0.0)

    def __post_init__(self) -> None:
        validate_fields(self)


@document_fields
@dataclass(frozen=True, kw_only=True)
class ObserverSpec:
    """Observer design: gain parameter rho (Proposition 2), filter and sampling.

    Examples
    --------
    >>> ObserverSpec(rho=4.0, variant="static").dt
    0.0001
    """

    _section = "observer"
    rho: float = param_field(POSITIVE, "-", "gain design parameter (stable for rho > 1)")
    omega_co: float = param_field(POSITIVE, "rad/s", "cutoff of the low-pass filter eq:3:4:5", 2 * math.pi * 40)
    variant: str = param_field(Choice(VARIANTS), "-", "model variant the observer is derived from", "lag")
    dt: float = param_field(POSITIVE, "s", "controller sample time (1e-12 to 1 s)", 1e-4)

    def __post_init__(self) -> None:
        validate_fields(self)
        if not SAMPLE_TIME.contains(self.dt):  # one rule for dt: simulate, check, every export
            raise ValueError(f"observer.dt: expected a sample time in [1e-12, 1] s, found {self.dt!r}")


@document_fields
@dataclass(frozen=True, kw_only=True)
class PIDSpec:
    """Sensitivity-based PID specification of section 4.1.

    The plant approximation is ``H = phi / (lambda (tau lambda + 1))``
    (eq:linplant); ``phi`` defaults to ``K tau / m``.

    Examples
    --------
    >>> PIDSpec(max_S=1/400, phase_margin_deg=60.0, tau=0.006675).phase_margin
    1.0471975511965976
    """

    _section = "pid"
    max_S: float = param_field(POSITIVE, "m/V", "upper bound of |S| (eq:pidGain)")
    phase_margin_deg: float = param_field(Range(low=0.0, high=90.0), "deg", "phase margin Phi at crossover (eq:L_omegas)")
    tau: float = param_field(POSITIVE, "s", "plant time constant of eq:linplant")
    phi: float | None = param_field(
        Range(low=0.0, optional=True), "m/(V s)", "plant gain of eq:linplant (default K tau / m)", None
    )
    derivative_N: float = param_field(DERIVATIVE_N, "-", "derivative filter: time constant (kd/kp)/N in simulations "
                                      "(0.1 to 1e4)", 10.0)
    design: str = param_field(Choice(PID_DESIGNS), "-", "gains: paper (section 4.1), sampled (the phase margin on the "
                              "sampled loop with the delay) or auto (docs/delay.md)", "auto")

    def __post_init__(self) -> None:
        validate_fields(self)

    @property
    def phase_margin(self) -> float:
        """Phase margin in radians."""
        return math.radians(self.phase_margin_deg)


class FieldRow(NamedTuple):
    """A parameter of a config: qualified name, value, unit, description, and whether it is the default."""

    name: str
    value: Any
    unit: str
    doc: str
    is_default: bool


#: Section name -> its dataclass, in the order of a TOML file.
SECTIONS: Mapping[str, type] = FrozenMap({
    "plant": PlantParams,
    "friction": FrictionParams,
    "sensor": SensorSpec,
    "observer": ObserverSpec,
    "pid": PIDSpec,
    "compensation": CompensationSpec, "hardware": HardwareSpec,
})
#: Sections that may be left out of a TOML file (their defaults apply).
_OPTIONAL_SECTIONS = ("sensor", "compensation", "hardware")


@dataclass(frozen=True, kw_only=True)
class Config:
    """A complete design: plant, friction, sensor, observer, PID, compensation and hardware sections.

    Attributes
    ----------
    name : str
        Name of the design.
    plant, friction, sensor, observer, pid, compensation, hardware : dataclass
        The sections of :data:`SECTIONS`; ``sensor``, ``compensation`` and ``hardware`` may be left out.
    sources : Mapping[str, str]
        Where values come from (``"plant.m"`` -> text); not compared.
    plant_friction : PlantFrictionSpec or None
        ``[plant_friction]``: the simulated plant's friction model (None: the paper's).
    axis : AxisSpec or None
        ``[axis]``: linear or rotary and the command's unit (None: linear, in V, as the presets);
        :attr:`units` resolves it. Every printed unit comes from it (:meth:`AxisSpec.unit`).

    Examples
    --------
    >>> cfg = load_preset("vcm")
    >>> Config.from_toml(cfg.to_toml()) == cfg
    True
    """

    _section = "config"
    name: str = param_field(Text(), "-", "name of the design", "custom")
    plant: PlantParams
    friction: FrictionParams
    observer: ObserverSpec
    pid: PIDSpec
    sensor: SensorSpec = field(default_factory=SensorSpec)
    compensation: CompensationSpec = field(default_factory=CompensationSpec)
    hardware: HardwareSpec = field(default_factory=HardwareSpec)
    sources: Mapping[str, str] = field(default_factory=dict, compare=False, repr=False)
    plant_friction: PlantFrictionSpec | None = None  # [plant_friction]: the simulated plant's model
    axis: AxisSpec | None = None  # [axis]: linear or rotary, the command's unit (None: linear, V)

    def __post_init__(self) -> None:
        validate_fields(self)
        if not isinstance(self.plant_friction, (PlantFrictionSpec, type(None))):
            raise TypeError(f"config.plant_friction: expected PlantFrictionSpec or None, found {self.plant_friction!r}")
        if not isinstance(self.axis, (AxisSpec, type(None))):
            raise TypeError(f"config.axis: expected AxisSpec or None, found {self.axis!r}")
        object.__setattr__(self, "sources", FrozenMap(_check_sources(self.sources)))
        for key, cls in SECTIONS.items():
            value = getattr(self, key)
            if not isinstance(value, cls):
                raise TypeError(f"config.{key}: expected {cls.__name__}, found {type(value).__name__}")
        if self.observer.variant == "lag" and self.friction.beta is None:
            raise ValueError(
                "friction.beta: expected a finite number > 0 for observer.variant 'lag', found None "
                "(use variant 'static' for friction without lag)"
            )

    @property
    def units(self) -> AxisSpec:
        """The axis's units: :attr:`axis`, or :data:`obsdesign.axis.LINEAR` (in V) without ``[axis]``."""
        return self.axis if self.axis is not None else LINEAR

    @property
    def phi(self) -> float:
        """PID plant gain phi of eq:linplant: ``pid.phi`` if set, else ``K tau / m``."""
        return self.pid.phi if self.pid.phi is not None else self.plant.K * self.pid.tau / self.plant.m

    def override(self, **values: Any) -> "Config":
        """A copy with some fields replaced, addressed by their (unique) field names.

        ``None`` values are ignored, so optional command-line flags can be passed
        straight through. Validation is that of the sections' constructors.

        Examples
        --------
        >>> cfg = load_preset("table1").override(rho=0.98, kappa=None)
        >>> cfg.observer.rho, cfg.friction.kappa
        (0.98, 8000.0)
        >>> load_preset("table1").override(mass=1.0)
        Traceback (most recent call last):
        ...
        ValueError: override: unknown parameter 'mass'; expected one of Cf, G, K, beta, buildup, deadzone, delay_samples, derivative_N, design, dt, ff_offset, ff_presliding, ff_stribeck, ff_stribeck_velocity, gain, kappa, lookahead, m, max_S, mode, noise_bandwidth, noise_rms, omega_co, phase_margin_deg, phi, quantization, rho, s, sigma, tau, u_max, variant, viscous
        """
        changes: dict[str, dict[str, Any]] = {}
        for name, value in values.items():
            if name not in _FIELD_SECTION:
                raise ValueError(
                    f"override: unknown parameter {name!r}; expected one of {', '.join(sorted(_FIELD_SECTION))}"
                )
            if value is not None:
                changes.setdefault(_FIELD_SECTION[name], {})[name] = value
        sections = {key: dataclasses.replace(getattr(self, key), **kw) for key, kw in changes.items()}
        changed = {f"{key}.{name}" for key, kw in changes.items() for name in kw}
        sources = {k: v for k, v in self.sources.items() if k not in changed}
        return dataclasses.replace(self, **sections, sources=sources)

    # -- TOML ---------------------------------------------------------------
    @classmethod
    def from_dict(cls, data: dict[str, Any], *, source: str = "config") -> "Config":
        """Build a config from a nested mapping (as parsed from TOML).

        Raises
        ------
        ValueError
            On unknown or missing sections and keys, and on out-of-range values.
        TypeError
            On values of the wrong type.
        """
        if not isinstance(data, dict):
            raise TypeError(f"{source}: expected a table, found {type(data).__name__}")
        data = move_legacy_delay(data, source=source)
        allowed = set(SECTIONS) | {"name", "sources", "plant_friction", "axis"}
        unknown = sorted(set(data) - allowed)
        if unknown:
            raise ValueError(
                f"{source}: unknown key {unknown[0]!r}; expected one of {', '.join(sorted(allowed))}"
            )
        kwargs: dict[str, Any] = {}
        if "name" in data:
            kwargs["name"] = data["name"]
        if "sources" in data:
            kwargs["sources"] = data["sources"]
        if "plant_friction" in data:
            kwargs["plant_friction"] = PlantFrictionSpec.from_dict(data["plant_friction"])
        if "axis" in data:
            kwargs["axis"] = AxisSpec.from_dict(data["axis"])
        for key, section in SECTIONS.items():
            table = data.get(key)
            if table is None:
                if key in _OPTIONAL_SECTIONS:
                    continue
                raise ValueError(f"{source}: missing section [{key}]")
            kwargs[key] = section_from_table(section, table)
        return cls(**kwargs)

    @classmethod
    def from_toml(cls, text: str, *, source: str = "config") -> "Config":
        """Parse a TOML document (see :meth:`to_toml` for the layout)."""
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise ValueError(f"{source}: not valid TOML ({e})") from e
        return cls.from_dict(data, source=source)

    def to_dict(self) -> dict[str, Any]:
        """Nested mapping of all set values (``None`` fields are left out)."""
        out: dict[str, Any] = {"name": self.name}
        if self.axis is not None:
            out["axis"] = self.axis.to_dict()
        if self.sources:
            out["sources"] = dict(self.sources)
        for key in SECTIONS:
            section = getattr(self, key)
            out[key] = {
                f.name: getattr(section, f.name)
                for f in dataclasses.fields(section)
                if getattr(section, f.name) is not None
            }
        if self.plant_friction is not None:
            out["plant_friction"] = self.plant_friction.to_dict()
        return out

    def to_toml(self) -> str:
        """Serialise to TOML; ``Config.from_toml(c.to_toml()) == c``."""
        lines, unit, words = [f"name = {toml_value(self.name)}"] + self.axis_toml(), self.units.unit, self.units.words
        for key, table in self.to_dict().items():
            if key in ("name", "sources", "plant_friction", "axis"):
                continue
            section = getattr(self, key)
            meta = {f.name: f.metadata for f in dataclasses.fields(section)}
            lines += ["", f"[{key}]"]
            for name, value in table.items():
                lines.append(f"{name} = {toml_value(value)}  # [{unit(meta[name]['unit'])}] {words(meta[name]['doc'])}")
        return "\n".join(lines + self.extra_tables_toml()) + "\n"

    def axis_toml(self) -> list[str]:
        """TOML lines of the ``[axis]`` table (empty when unset): first, as the units below follow it."""
        return self.axis.toml_lines() if self.axis is not None else []

    def extra_tables_toml(self) -> list[str]:
        """TOML lines of the ``[plant_friction]`` and ``[sources]`` tables (empty when unset)."""
        lines = []
        if self.plant_friction is not None:
            lines += ["", "[plant_friction]  # the simulated plant's friction model (docs/friction-models.md)"]
            lines += [f"{k} = {toml_value(v)}" for k, v in self.plant_friction.to_dict().items()]
        if self.sources:
            lines += ["", "[sources]  # where each value comes from (dropped for a value that is overridden)"]
            lines += [f"{toml_value(k)} = {toml_value(v)}" for k, v in self.sources.items()]
        return lines

    def save(self, path: str | os.PathLike) -> None:
        """Write :meth:`to_toml` atomically (temporary file, then rename)."""
        atomic_write(path, self.to_toml())

    def source_of(self, name: str) -> str | None:
        """Where the value of parameter ``name`` (``'section.field'``) comes from, if recorded.

        >>> load_preset("vcm").source_of("plant.m")
        'paper section 4'
        >>> load_preset("vcm").override(m=1.0).source_of("plant.m") is None
        True
        """
        return self.sources.get(name)

    def describe_fields(self) -> list[FieldRow]:
        """One :class:`FieldRow` per parameter, in section order, for tables (units of :attr:`units`).

        >>> load_preset("vcm").describe_fields()[0]
        FieldRow(name='plant.m', value=0.538, unit='kg', doc='moving mass', is_default=False)
        """
        rows = []
        for key in SECTIONS:
            section = getattr(self, key)
            for f in dataclasses.fields(section):
                value = getattr(section, f.name)
                default = f.default is not dataclasses.MISSING and value == f.default
                rows.append(FieldRow(f"{key}.{f.name}", value, self.units.unit(f.metadata["unit"]),
                                     self.units.words(f.metadata["doc"]), default))
        return rows


_FIELD_SECTION: dict[str, str] = {
    f.name: key for key, cls in SECTIONS.items() for f in dataclasses.fields(cls)
}
#: Every parameter :meth:`Config.override` accepts, mapped to its section.
PARAMETERS: Mapping[str, str] = FrozenMap(dict(sorted(_FIELD_SECTION.items())))


_PARAMETER_NAMES = frozenset(f"{key}.{f.name}" for key, cls in SECTIONS.items() for f in dataclasses.fields(cls))


def _check_sources(sources: Any) -> dict[str, str]:
    """The ``[sources]`` table: parameter name (``'section.field'``) -> where its value comes from."""
    if not isinstance(sources, Mapping):
        raise TypeError(f"sources: expected a table of 'section.field' = \"text\", found {type(sources).__name__}")
    for key, value in sources.items():
        if key not in _PARAMETER_NAMES:
            raise ValueError(f"sources: unknown parameter {key!r}; expected 'section.field' such as 'plant.m'")
        if not isinstance(value, str):
            raise TypeError(f"sources.{key}: expected a string, found {type(value).__name__} {value!r}")
    return dict(sources)


def preset_names() -> tuple[str, ...]:
    """Names of the presets shipped with the package.

    >>> preset_names()
    ('table1', 'vcm')
    """
    files = resources.files("obsdesign.presets").iterdir()
    return tuple(sorted(p.name[:-5] for p in files if p.name.endswith(".toml")))


def load_preset(name: str) -> Config:
    """Load a shipped preset by name (``table1`` or ``vcm``).

    Parameters
    ----------
    name : str
        One of :func:`preset_names`.

    Raises
    ------
    ValueError
        If no preset of that name exists.
    """
    if not isinstance(name, str):
        raise TypeError(f"preset: expected a string, found {type(name).__name__} {name!r}")
    names = preset_names()
    if name not in names:
        raise ValueError(f"preset: expected one of {', '.join(names)}, found {name!r}")
    text = resources.files("obsdesign.presets").joinpath(f"{name}.toml").read_text(encoding="utf-8")
    return Config.from_toml(text, source=f"preset {name}")


def read_config(path: str | os.PathLike) -> Config:
    """A config from a TOML file, its ``[sources]`` as written (:func:`obsdesign.load_config` verifies them).

    Parameters
    ----------
    path : str or os.PathLike
        A TOML file (see :meth:`Config.to_toml`).

    Raises
    ------
    ValueError
        If the file does not exist, cannot be read, is not UTF-8 TOML, or holds invalid values.
    """
    p = Path(path)
    try:
        data = p.read_bytes() if p.is_file() else None
    except OSError as e:
        raise ValueError(f"config: cannot read {str(p)!r} ({e.strerror or type(e).__name__})") from None
    if data is None:
        raise ValueError(f"config: expected an existing TOML file, found {str(p)!r}")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ValueError(f"{p}: expected UTF-8 text (TOML), found the byte 0x{data[e.start]:02x} at offset "
                         f"{e.start}") from None
    return Config.from_toml(text, source=str(p))
