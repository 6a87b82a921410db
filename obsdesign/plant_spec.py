"""The ``[plant_friction]`` section of a config: which friction model the simulated plant has.

The observer is always designed from ``[friction]`` (the paper's model). The plant the
simulator integrates may have another friction model: ``[plant_friction]`` names it
(``model``, a name of :data:`obsdesign.friction.FRICTION_MODELS`) and sets its parameters by
the names of that model's ``parameters``. Every model also takes asymmetric levels
``Cf_neg``, ``sigma_neg`` and a constant ``offset`` [N]. ``Cf`` and ``sigma`` default
to the config's ``[friction]`` values (and for ``paper`` also ``s`` and ``beta``), so a
table holding only ``model = "lugre"`` gives a LuGre plant at the design's friction levels.
Without the table the plant is the paper's model, exactly as designed. See docs/comparison.md.

Examples
--------
>>> spec = PlantFrictionSpec(model="lugre", parameters={"sigma0": 1e6, "Cf_neg": 0.3})
>>> spec.model, dict(spec.parameters)
('lugre', {'sigma0': 1000000.0, 'Cf_neg': 0.3})
>>> PlantFrictionSpec(model="coulomb")
Traceback (most recent call last):
...
ValueError: plant_friction.model: expected one of paper, lugre, dahl, gms, found 'coulomb'
>>> PlantFrictionSpec(model="dahl", parameters={"sigma0": "stiff"})
Traceback (most recent call last):
...
TypeError: dahl.sigma0: expected a real number, found str 'stiff'
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

from ._validate import FrozenMap
from .friction.registry import FRICTION_MODELS  # no NumPy, no numba: safe under ``import obsdesign``

__all__ = ["PlantFrictionSpec", "PLANT_FRICTION_MODELS", "PAPER_EXTRA", "PLANT_PARAMETER_NAMES", "split_plant",
           "with_plant_parameters"]

#: Model names, in the order of their kernel codes (those of :data:`obsdesign.friction.FRICTION_MODELS`).
PLANT_FRICTION_MODELS = tuple(FRICTION_MODELS)
#: Parameters the ``paper`` plant takes beyond those of :data:`obsdesign.friction.FRICTION_MODELS`.
PAPER_EXTRA = ("Cf_neg", "sigma_neg", "offset")


#: Parameter names of ``[plant_friction]`` tables of any model that a sweep can set (``plant.NAME``):
#: the union of the models' scalar parameters (not the element lists ``k``/``alpha`` of ``gms``).
PLANT_PARAMETER_NAMES = frozenset(name for info in FRICTION_MODELS.values() for name in info.scalar_parameters())


def split_plant(params: Mapping[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """Split sweep parameters into design ones and ``plant.``-prefixed ones (prefix removed).

    Parameters
    ----------
    params : mapping
        Parameter name -> value.

    >>> split_plant({"rho": 2.0, "plant.m": 1.0})
    ({'rho': 2.0}, {'m': 1.0})
    """
    design = {k: v for k, v in params.items() if not k.startswith("plant.")}
    plant = {k[6:]: v for k, v in params.items() if k.startswith("plant.")}
    return design, plant


def with_plant_parameters(cfg, values: Mapping[str, Any], config_fields: Mapping[str, str]):
    """``cfg`` with config fields overridden and ``[plant_friction]`` parameters set (the plant of a sweep run).

    Parameters
    ----------
    cfg : Config
        The run's design config.
    values : mapping
        Plant parameter name (no prefix) -> value.
    config_fields : mapping
        :data:`obsdesign.params.PARAMETERS` (names that are config fields; ``K`` is the actuator's).
    """
    import dataclasses

    fields = {k: v for k, v in values.items() if k in config_fields}
    friction = {k: v for k, v in values.items() if k not in config_fields}
    out = cfg.override(**fields)
    if friction:
        own = cfg.plant_friction or PlantFrictionSpec()
        out = dataclasses.replace(out, plant_friction=PlantFrictionSpec(
            model=own.model, parameters={**dict(own.parameters), **friction}))
    return out


@dataclass(frozen=True, kw_only=True)
class PlantFrictionSpec:
    """Friction model of the simulated plant (the ``[plant_friction]`` table).

    Parameters
    ----------
    model : str
        One of :data:`PLANT_FRICTION_MODELS`.
    parameters : mapping of str to number
        The model's parameters by name (unset ones: ``[friction]`` levels, else the model's defaults).
    """

    _section = "plant_friction"
    model: str = "paper"
    parameters: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        FRICTION_MODELS.check(self.model, kind="plant_friction.model")
        if not isinstance(self.parameters, Mapping):
            raise TypeError(f"plant_friction: expected a table of parameters, found {type(self.parameters).__name__}")
        params = dict(self.parameters)
        extra = {k: params.pop(k) for k in PAPER_EXTRA if self.model == "paper" and k in params}
        FRICTION_MODELS[self.model].resolve(params)  # names, types and ranges
        if extra:
            FRICTION_MODELS["lugre"].resolve(extra)
        object.__setattr__(self, "parameters", FrozenMap({k: _plain(v) for k, v in self.parameters.items()}))

    def to_dict(self) -> dict[str, Any]:
        """The TOML table: ``model`` and the parameters."""
        return {"model": self.model, **dict(self.parameters)}

    @classmethod
    def from_dict(cls, table: Mapping[str, Any]) -> "PlantFrictionSpec":
        """Build from the TOML table (``model`` plus parameters).

        Parameters
        ----------
        table : mapping
            The parsed ``[plant_friction]`` table.
        """
        if not isinstance(table, Mapping):
            raise TypeError(f"plant_friction: expected a table, found {type(table).__name__} {table!r}")
        rest = dict(table)
        model = rest.pop("model", "paper")
        return cls(model=model, parameters=rest)


def _plain(value: Any) -> Any:
    if isinstance(value, (list, tuple)):
        return [float(v) for v in value]
    if isinstance(value, int) and not isinstance(value, bool):
        return value
    return float(value)
