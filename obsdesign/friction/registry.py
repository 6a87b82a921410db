"""Registry of the plant friction models: names, codes, documented parameters, packing.

Each model is a :class:`FrictionModelInfo` in :data:`FRICTION_MODELS` (a
:class:`~obsdesign._registry.Registry`), the one place where the models are listed and
their integer codes typed (:data:`PAPER`, :data:`LUGRE`, :data:`DAHL`, :data:`GMS`, read
by the numba kernels of :mod:`obsdesign.friction.kernels` and the simulator). Its
``parameters`` are ``ParameterSpec(name, unit, doc, default, low, high)`` tuples
(closed ranges); :meth:`FrictionModelInfo.pack` validates named values, fills the
defaults and returns the flat ``float64`` array the numba kernels take (layout in
:mod:`obsdesign.friction.common`). This module imports neither NumPy nor numba (NumPy
loads in :meth:`~FrictionModelInfo.pack`), so the config and the command line read it.

Ranges follow the axis. The package computes in SI for both kinds of axis (:mod:`obsdesign.axis`): on a rotary
one every N is N m and every m is rad, so a stiffness [N/m] is N m/rad there (messages name both). A bristle's
stiffness differs by orders of magnitude between a linear guide (1e5 to 1e8 N/m) and a motor's bearings (1e2 to
1e5 N m/rad), so its range is a wide ceiling, and the check that catches a wrong value is relative to the model's
own friction level: the pre-sliding travel ``Cf / sigma0`` (GMS: ``Fs / K``) of :data:`PRESLIDING_TRAVEL`, in m or
rad (a bristle that deflects 10 cm or 6 degrees before sliding, or less than an atom, is a unit or typing mistake).

Defaults. The force levels are the paper's presets (``Cf`` = 0.35 N,
``sigma`` = 21.1 N s/m, Table 1 and section 4, for the 0.538 kg axis). The
dynamic parameters are the published sets: LuGre ``sigma0`` = 1e5 N/m,
``sigma1`` = sqrt(1e5) N s/m, ``vs`` = 1e-3 m/s and ``Fs/Fc`` = 1.5 from Canudas de
Wit et al. (1995), Table 1; Dahl with the same rest stiffness and ``alpha`` = 1
(Olsson et al. 1998); GMS with the same total stiffness split over ``N`` = 4
elements (Al-Bender et al. 2005 structure). The GMS attraction parameter
``C`` = 20 N/s and its element distribution rule are this package's choice
(documented in docs/friction-models.md), not published values.

Examples
--------
>>> info = FRICTION_MODELS["lugre"]
>>> info.code, info.n_state({})
(1, 3)
>>> p = info.pack({"Cf_neg": 0.3, "offset": 0.05})
>>> p[:5].tolist()  # Cf, Cf_neg, sigma, sigma_neg, offset
[0.35, 0.3, 21.1, 21.1, 0.05]
>>> info.pack({"sigma0": -1.0})
Traceback (most recent call last):
...
ValueError: lugre.sigma0: expected a finite number in [0.01, 1e+12] N/m (N m/rad on a rotary axis), found -1.0
>>> info.pack({"sigma0": 1.0})  # 0.35 m (or rad) of pre-sliding
Traceback (most recent call last):
...
ValueError: lugre.sigma0: expected a stiffness whose pre-sliding travel Cf/sigma0 is 1e-12 to 0.1 (m, or rad on a rotary axis), found sigma0 = 1 (travel 0.35 with Cf = 0.35)
>>> FRICTION_MODELS["gms"].n_state({"N": 6})
14
>>> FRICTION_MODELS.names(), FRICTION_MODELS.code("dahl") == DAHL
(('paper', 'lugre', 'dahl', 'gms'), True)
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

from .._registry import Entry, Registry

__all__ = ["ParameterSpec", "FrictionModelInfo", "FRICTION_MODELS", "friction_code", "PAPER", "LUGRE", "DAHL", "GMS",
           "PRESLIDING_TRAVEL"]

#: The pre-sliding travel ``Cf / sigma0`` (GMS: ``Fs / K``) a bristle stiffness may give [m, or rad on a rotary
#: axis]: from below an atom to 10 cm (6 degrees). The published sets give 3.5e-6 m (LuGre, 1e5 N/m at 0.35 N); a
#: motor with 0.05 N m of Coulomb friction and 1e2 to 1e4 N m/rad, 5e-4 to 5e-6 rad.
PRESLIDING_TRAVEL = (1e-12, 0.1)

#: Integer model codes (append-only: numba caches compiled code that reads them).
#: ``PAPER`` is reserved: its kernel is :mod:`obsdesign.friction.presliding`, run by the
#: simulator's own plant step; :mod:`obsdesign.friction.kernels` dispatches the others.
PAPER, LUGRE, DAHL, GMS = 0, 1, 2, 3

if TYPE_CHECKING:
    import numpy as np


class ParameterSpec(NamedTuple):
    """One named parameter: ``(name, unit, doc, default, low, high)``; ``low <= value <= high``."""

    name: str
    unit: str
    doc: str
    default: Any
    low: float
    high: float


@dataclass(frozen=True, kw_only=True)
class FrictionModelInfo(Entry):
    """A plant friction model: code for the kernels, documented parameters, packing rule.

    Attributes
    ----------
    name, code, doc : str, int, str
        As every :class:`~obsdesign._registry.Entry`.
    parameters : tuple of ParameterSpec
        The named parameters, their units, defaults and closed ranges.
    """

    #: The kernel array of the resolved parameters; None where the array is not the model's alone
    #: (the paper plant's also holds ``[friction] kappa``: :func:`obsdesign.loop.plant.plant_friction_arrays`).
    _layout: Callable[[dict[str, Any]], list[float]] | None
    _n_state: Callable[[dict[str, Any]], int]

    def defaults(self) -> dict[str, Any]:
        """The default value of every parameter, by name."""
        return {spec.name: spec.default for spec in self.parameters}

    def resolve(self, params: Mapping[str, Any]) -> dict[str, Any]:
        """Validated parameters with the defaults filled in (``None`` asymmetry resolved)."""
        if not isinstance(params, Mapping):
            raise TypeError(f"{self.name}: expected a mapping of parameter names to values, "
                            f"found {type(params).__name__}")
        specs = {spec.name: spec for spec in self.parameters}
        unknown = sorted(set(params) - set(specs))
        if unknown:
            raise ValueError(f"{self.name}: unknown parameter {unknown[0]!r}; "
                             f"expected one of {', '.join(specs)}")
        values = self.defaults()
        values.update(params)
        out: dict[str, Any] = {}
        for name, spec in specs.items():
            out[name] = _check(f"{self.name}.{name}", spec, values[name], (self.name, name))
        if "k" in params and params["k"] is not None and "K" in params:
            raise ValueError(f"{self.name}.K: give either the total stiffness K or the element "
                             f"stiffnesses k, not both")
        if "Cf_neg" in out and out["Cf_neg"] is None:
            out["Cf_neg"] = out["Cf"]
        if "sigma_neg" in out and out["sigma_neg"] is None:
            out["sigma_neg"] = out["sigma"]
        if "Fs" in out and out["Fs"] < out["Cf"]:
            raise ValueError(f"{self.name}.Fs: expected Fs >= Cf = {out['Cf']!r} N "
                             f"(stiction at least the Coulomb level), found {out['Fs']!r}")
        _check_travel(self.name, out)
        return out

    def pack(self, params: Mapping[str, Any]) -> np.ndarray:
        """Validate ``params`` (names of :attr:`parameters`), fill defaults, return ``p``.

        Raises
        ------
        ValueError
            Unknown name, non-finite or out-of-range value, inconsistent values; the ``paper``
            model, whose array :func:`obsdesign.loop.plant.plant_friction_arrays` builds from a config.
        TypeError
            A value of the wrong type (e.g. a string, a bool, a float for ``N``).
        """
        import numpy as np  # here, not at the top: the config and the command line read the registry

        values = self.resolve(params)
        if self._layout is None:
            raise ValueError(f"{self.name}: its kernel array also holds [friction] kappa; "
                             f"build it from a Config with obsdesign.loop.plant.plant_friction_arrays")
        return np.array(self._layout(values), dtype=np.float64)

    def scalar_parameters(self) -> tuple[str, ...]:
        """Names of the parameters set by one number (not the per-element sequences)."""
        return tuple(spec.name for spec in self.parameters if (self.name, spec.name) not in _SEQUENCE)

    def n_state(self, params: Mapping[str, Any]) -> int:
        """Length of the internal state array for these parameters."""
        return self._n_state(self.resolve(params))


def friction_code(name: str) -> int:
    """Integer code of the model ``name`` (``ValueError`` naming the choices).

    Parameters
    ----------
    name : str
        A name of :data:`FRICTION_MODELS`.
    """
    if not isinstance(name, str):
        raise TypeError(f"friction model: expected a string, found {type(name).__name__} {name!r}")
    return FRICTION_MODELS.code(name)


def _fmt(a: float) -> str:
    return f"{a:g}"


def _unit(unit: str) -> str:
    """`` N/m (N m/rad on a rotary axis)``: the unit written for both kinds of axis (empty for none)."""
    if not unit:
        return ""
    from ..axis import AxisSpec  # no NumPy

    rotary = AxisSpec(kind="rotary", input="N m").unit(unit)
    return f" {unit}" + (f" ({rotary} on a rotary axis)" if rotary != unit else "")


def _check_travel(model: str, q: dict[str, Any]) -> None:
    """The pre-sliding travel of a bristle stiffness within :data:`PRESLIDING_TRAVEL` (module docstring)."""
    if "sigma0" in q:
        name, stiffness, level, label = "sigma0", q["sigma0"], q["Cf"], "Cf"
    elif "K" in q:
        name, level, label = ("k", q["Fs"], "Fs") if q.get("k") is not None else ("K", q["Fs"], "Fs")
        stiffness = sum(q["k"]) if q.get("k") is not None else q["K"]
    else:
        return
    travel = level / stiffness
    low, high = PRESLIDING_TRAVEL
    if not low <= travel <= high:
        total = f"the sum of k = {stiffness:.6g}" if name == "k" else f"{name} = {stiffness:.6g}"
        raise ValueError(f"{model}.{name}: expected a stiffness whose pre-sliding travel {label}/{'K' if name != 'sigma0' else name} "
                         f"is {_fmt(low)} to {_fmt(high)} (m, or rad on a rotary axis), found {total} (travel "
                         f"{travel:.3g} with {label} = {level:.6g})")


def _check_number(label: str, spec: ParameterSpec, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{label}: expected a real number, found {type(value).__name__} {value!r}")
    number = float(value)
    if not (math.isfinite(number) and spec.low <= number <= spec.high):
        raise ValueError(f"{label}: expected a finite number in [{_fmt(spec.low)}, {_fmt(spec.high)}]"
                         f"{_unit(spec.unit)}, found {value!r}")
    return number


#: Parameters that are integers, and parameters that are sequences (one value per element).
_INTEGER = {("gms", "N")}
_SEQUENCE = {("gms", "k"), ("gms", "alpha")}


def _check(label: str, spec: ParameterSpec, value: Any, key: tuple[str, str]) -> Any:
    """Validate one value against its spec (``None`` where the default is ``None``)."""
    if value is None:
        if spec.default is None:
            return None
        raise TypeError(f"{label}: expected a real number, found None")
    if key in _INTEGER:
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise TypeError(f"{label}: expected an integer, found {type(value).__name__} {value!r}")
        if not spec.low <= value <= spec.high:
            raise ValueError(f"{label}: expected an integer in [{spec.low}, {spec.high}], found {value!r}")
        return int(value)
    if key in _SEQUENCE:
        if isinstance(value, (str, bytes, Mapping)) or not hasattr(value, "__len__"):
            raise TypeError(f"{label}: expected a sequence of numbers, found {type(value).__name__} {value!r}")
        return [_check_number(f"{label}[{i}]", spec, item) for i, item in enumerate(value)]
    return _check_number(label, spec, value)


# --- parameter sets -------------------------------------------------------------------------

_CF = ParameterSpec("Cf", "N", "Coulomb friction level, positive direction (Fc)", 0.35, 1e-6, 1e3)
_SIGMA = ParameterSpec("sigma", "N s/m", "viscous coefficient, positive direction (sigma2)", 21.1, 0.0, 1e4)
_COMMON = (
    ParameterSpec("Cf_neg", "N", "Coulomb level for v < 0 (None: Cf)", None, 1e-6, 1e3),
    ParameterSpec("sigma_neg", "N s/m", "viscous coefficient for v < 0 (None: sigma)", None, 0.0, 1e4),
    ParameterSpec("offset", "N", "constant force added to the friction", 0.0, -1e3, 1e3),
)
_STRIBECK = (
    ParameterSpec("Fs", "N", "static (stiction) level, positive direction; Fs_neg = Fs Cf_neg / Cf",
                  0.525, 1e-6, 1e3),
    ParameterSpec("vs", "m/s", "Stribeck velocity", 1e-3, 1e-6, 1.0),
)


def _header(q: dict[str, Any]) -> list[float]:
    return [q["Cf"], q["Cf_neg"], q["sigma"], q["sigma_neg"], q["offset"]]


def _stribeck(q: dict[str, Any]) -> list[float]:
    return [q["Fs"], q["Fs"] * q["Cf_neg"] / q["Cf"], q["vs"]]


def _lugre_layout(q: dict[str, Any]) -> list[float]:
    return _header(q) + _stribeck(q) + [q["sigma0"], q["sigma1"]]


def _dahl_layout(q: dict[str, Any]) -> list[float]:
    return _header(q) + [q["sigma0"], q["alpha"]]


def gms_elements(q: dict[str, Any]) -> tuple[list[float], list[float]]:
    """Element stiffnesses and shares: explicit ``k``/``alpha`` or the default rule.

    Default rule: equal stiffness ``K / N`` and slip displacements
    ``2 i Fs / (K (N + 1))``, i = 1..N (evenly spaced up to about ``2 Fs / K``),
    which gives ``alpha_i = 2 i / (N (N + 1))``.
    """
    n = q["N"]
    k = q["k"] if q["k"] is not None else [q["K"] / n] * n
    alpha = q["alpha"] if q["alpha"] is not None else [2.0 * (i + 1) / (n * (n + 1)) for i in range(n)]
    for name, seq in (("k", k), ("alpha", alpha)):
        if len(seq) != n:
            raise ValueError(f"gms.{name}: expected {n} values (one per element, N = {n}), found {len(seq)}")
    if abs(sum(alpha) - 1.0) > 1e-9:
        raise ValueError(f"gms.alpha: expected shares summing to 1, found sum {sum(alpha)!r}")
    return list(k), list(alpha)


def _gms_layout(q: dict[str, Any]) -> list[float]:
    k, alpha = gms_elements(q)
    return _header(q) + _stribeck(q) + [q["C"], q["sigma1"], float(q["N"])] + k + alpha


#: The plant friction models, in code order: name -> :class:`FrictionModelInfo`.
FRICTION_MODELS = Registry("friction model", [
    FrictionModelInfo(
        name="paper", code=PAPER,
        doc="Coulomb with log-shaped pre-sliding memory (eq:2:3:1-2:3:5) and viscous lag; "
            "kernel in friction/presliding.py",
        parameters=(
            ParameterSpec("Cf", "N", "Coulomb friction level", 0.35, 0.0, 1e3),
            ParameterSpec("sigma", "N s/m", "viscous coefficient", 21.1, 0.0, 1e4),
            ParameterSpec("s", "1/m", "pre-sliding shape factor (z = s x)", 3000.0, 1.0, 1e7),
            ParameterSpec("beta", "s", "viscous lag time constant (0: static)", 0.001, 0.0, 1.0),
        ),
        _layout=None, _n_state=lambda q: 3,
    ),
    FrictionModelInfo(
        name="lugre", code=LUGRE,
        doc="LuGre bristle model with Stribeck curve (Canudas de Wit et al. 1995)",
        parameters=(_CF, _SIGMA) + _COMMON + _STRIBECK + (
            ParameterSpec("sigma0", "N/m", "bristle stiffness", 1e5, 1e-2, 1e12),
            ParameterSpec("sigma1", "N s/m", "bristle (micro-)damping", math.sqrt(1e5), 0.0, 1e5),
        ),
        _layout=_lugre_layout, _n_state=lambda q: 3,
    ),
    FrictionModelInfo(
        name="dahl", code=DAHL,
        doc="Dahl rate-independent pre-sliding model (Dahl 1968)",
        parameters=(_CF, _SIGMA) + _COMMON + (
            ParameterSpec("sigma0", "N/m", "rest stiffness dF/dx at F = 0", 1e5, 1e-2, 1e12),
            ParameterSpec("alpha", "", "shape exponent of the stress-strain curve", 1.0, 0.25, 4.0),
        ),
        _layout=_dahl_layout, _n_state=lambda q: 3,
    ),
    FrictionModelInfo(
        name="gms", code=GMS,
        doc="Generalized Maxwell-slip model with N elements (Al-Bender et al. 2005)",
        parameters=(_CF, _SIGMA) + _COMMON + _STRIBECK + (
            ParameterSpec("C", "N/s", "attraction parameter of the slip relaxation", 20.0, 1e-3, 1e6),
            ParameterSpec("sigma1", "N s/m", "micro-damping of the elements (sum of b_i)", 0.0, 0.0, 1e5),
            ParameterSpec("N", "", "number of elements", 4, 1, 64),
            ParameterSpec("K", "N/m", "total element stiffness (used when k is None)", 1e5, 1e-2, 1e12),
            ParameterSpec("k", "N/m", "element stiffnesses, N values (None: K / N each)", None, 1e-3, 1e12),
            ParameterSpec("alpha", "", "element shares of s(v), N values summing to 1 (None: 2 i / (N (N+1)))",
                          None, 1e-9, 1.0),
        ),
        _layout=_gms_layout, _n_state=lambda q: 2 + 2 * q["N"],
    ),
])
