"""The plant the simulator runs, from a config: its friction model's kernel code and parameter array.

The mass, actuator gain and load are the config's ``[plant]`` (or those of a mismatched plant's
config, :func:`obsdesign.loop.prepare`); the friction is its ``[plant_friction]`` table, or the paper's
model at the levels of ``[friction]``. :func:`plant_friction_arrays` is the one translation of that
table into what the kernel reads (:class:`obsdesign.loop.args.PlantArgs`).
"""

from __future__ import annotations

import numpy as np

from ..friction.registry import FRICTION_MODELS
from ..params import Config

__all__ = ["plant_friction_arrays"]


def plant_friction_arrays(cfg: Config) -> tuple[int, np.ndarray]:
    """The kernel's plant friction code and parameter array for a config's ``[plant_friction]``.

    Parameters
    ----------
    cfg : Config
        The plant's config; without ``[plant_friction]`` its plant is the paper's model.

    Returns
    -------
    code : int
        ``0`` paper, ``1`` lugre, ``2`` dahl, ``3`` gms (:mod:`obsdesign.friction`).
    params : ndarray
        ``paper``: ``(Cf, Cf_neg, sigma, sigma_neg, offset, s, beta, kappa)``; the others: the
        array of :meth:`obsdesign.friction.FrictionModelInfo.pack`.

    Notes
    -----
    ``Cf`` and ``sigma`` (for ``paper`` also ``s`` and ``beta``) default to ``[friction]``; the
    stiction level ``Fs`` of ``lugre``/``gms`` defaults to ``1.5 Cf`` (the ratio of the
    published LuGre set), so the models keep their shape at any friction level.

    Examples
    --------
    >>> import obsdesign as od
    >>> code, pp = plant_friction_arrays(od.load_preset("table1"))
    >>> code, pp.tolist()
    (0, [0.35, 0.35, 21.1, 21.1, 0.0, 3000.0, 0.001, 8000.0])
    """
    fr = cfg.friction
    spec = cfg.plant_friction
    model = spec.model if spec is not None else "paper"
    given = dict(spec.parameters) if spec is not None else {}
    if model == "paper":
        q = {"Cf": fr.Cf, "sigma": fr.sigma, "s": fr.s, "beta": fr.beta or 0.0, "offset": 0.0, **given}
        if given:  # the values of [friction] are validated by the config; check only what the table sets
            FRICTION_MODELS["paper"].resolve({k: q[k] for k in ("Cf", "sigma", "s", "beta")})
        return 0, np.array([q["Cf"], q.get("Cf_neg", q["Cf"]), q["sigma"], q.get("sigma_neg", q["sigma"]),
                            q["offset"], q["s"], q["beta"], fr.kappa], dtype=np.float64)
    info = FRICTION_MODELS[model]
    q = {"Cf": fr.Cf, "sigma": fr.sigma, **given}
    if "Fs" in {spec.name for spec in info.parameters} and "Fs" not in given:
        q["Fs"] = 1.5 * q["Cf"]
    return info.code, info.pack(q)
