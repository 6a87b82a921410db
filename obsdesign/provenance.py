"""Where each parameter of a design comes from: a preset, a config file, a command-line flag, an identification.

A preset's ``[sources]`` table says where its values come from (``"paper section 4"``). A config file
written from a preset keeps that table; once a value is edited the paper no longer backs it, so
:func:`verified_sources` drops every entry that cites what a
preset cites for a value that is not that preset's. ``identify -o`` (:func:`obsdesign.data.rules.config_from`)
writes each rule with the value it gave (``"... [kg]; written as 0.8"``, :data:`WRITTEN_AS`): such an entry
is dropped once the value differs. :func:`obsdesign.load_config`, every command's ``--config`` and the
report read a file through this one rule. :func:`parameter_sources` gives the source column of
the report; :func:`matching_preset` says whether a config is one of the paper's presets (the report shows
the paper's reproduction studies for those).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping

from .params import Config, load_preset, preset_names, read_config

__all__ = ["load_config", "verified_sources", "parameter_sources", "matching_preset", "WRITTEN_AS"]

#: Separator of a ``[sources]`` entry and the value it was written for (``repr`` of the value).
WRITTEN_AS = "; written as "


def _value(cfg: Config, key: str):
    section, name = key.split(".")
    return getattr(getattr(cfg, section), name)


def verified_sources(cfg: Config) -> Config:
    """``cfg`` without the ``[sources]`` entries that credit a preset's source to a value the preset does not have.

    An entry whose text is the one a shipped preset gives for that parameter is kept only when the
    value equals that preset's value; an entry ending in ``"; written as V"`` (:data:`WRITTEN_AS`,
    ``identify -o``) only when the value's ``repr`` is ``V``; every other entry (the file's own words)
    is kept.

    Parameters
    ----------
    cfg : Config
        A design, typically read from a file.

    Returns
    -------
    Config
        ``cfg`` itself when nothing is dropped.

    Examples
    --------
    >>> import dataclasses
    >>> vcm = load_preset("vcm")
    >>> edited = dataclasses.replace(vcm, plant=dataclasses.replace(vcm.plant, m=1.733))  # sources kept as copied
    >>> edited.source_of("plant.m"), verified_sources(edited).source_of("plant.m")
    ('paper section 4', None)
    >>> verified_sources(edited).source_of("plant.K")       # unchanged: still the paper's value
    'paper section 4'
    >>> written = dataclasses.replace(vcm, sources={"plant.m": "identified [kg]; written as 0.538",
    ...                                             "plant.K": "identified [N/V]; written as 1.0"})
    >>> dict(verified_sources(written).sources)             # K is 3.28, not the 1.0 written
    {'plant.m': 'identified [kg]; written as 0.538'}
    """
    if not isinstance(cfg, Config):
        raise TypeError(f"cfg: expected a Config, found {type(cfg).__name__}")
    presets = [load_preset(name) for name in preset_names()]
    stale = set()
    for key, text in cfg.sources.items():
        cited = [pre for pre in presets if pre.sources.get(key) == text]
        if cited and all(_value(pre, key) != _value(cfg, key) for pre in cited):
            stale.add(key)
        elif WRITTEN_AS in text and text.rsplit(WRITTEN_AS, 1)[1] != repr(_value(cfg, key)):
            stale.add(key)
    if not stale:
        return cfg
    return dataclasses.replace(cfg, sources={k: v for k, v in cfg.sources.items() if k not in stale})


def load_config(path: str | os.PathLike) -> Config:
    """Load a config from a TOML file, its ``[sources]`` through :func:`verified_sources`.

    The one reading of a config file: ``obsdesign.load_config``, every command's ``--config`` and the
    report. An entry that credits a preset's source, or the value ``identify`` wrote, to a value
    edited since is dropped.

    Parameters
    ----------
    path : str or os.PathLike
        A TOML file (see :meth:`obsdesign.Config.to_toml`).

    Raises
    ------
    ValueError
        If the file does not exist, cannot be read, is not UTF-8 TOML, or holds invalid values.
    """
    return verified_sources(read_config(path))


def matching_preset(cfg: Config) -> str | None:
    """The name of the shipped preset ``cfg`` equals (every value; sources aside), or None.

    Parameters
    ----------
    cfg : Config
        The design.

    >>> matching_preset(load_preset("vcm")), matching_preset(load_preset("vcm").override(rho=3.0))
    ('vcm', None)
    """
    for name in preset_names():
        if load_preset(name) == cfg:
            return name
    return None


def parameter_sources(cfg: Config, origin: str, *, flags: Mapping[str, str] | None = None) -> dict[str, str]:
    """Parameter (``'section.field'``) -> where its value comes from, for the report's parameter table.

    In this order: a command-line flag (``flags``: parameter -> flag, e.g. ``{"observer.rho": "--rho"}``);
    the config's ``[sources]`` entry, after ``origin`` (a preset's entry survives in a file only for the
    preset's value, :func:`verified_sources`); ``obsdesign default`` for a default value; else ``origin``.

    Parameters
    ----------
    cfg : Config
        The design.
    origin : str
        Where the config came from: ``"preset vcm"``, ``"config file axis.toml"``.
    flags : mapping, optional
        The parameters set by command-line flags.

    Examples
    --------
    >>> src = parameter_sources(load_preset("vcm").override(rho=3.0), "preset vcm", flags={"observer.rho": "--rho"})
    >>> src["plant.m"], src["observer.rho"], src["pid.derivative_N"]
    ('preset vcm: paper section 4', 'flag --rho', 'obsdesign default')
    """
    flags = dict(flags or {})
    cfg = verified_sources(cfg)
    out = {}
    for row in cfg.describe_fields():
        known = cfg.source_of(row.name)
        if row.name in flags:
            out[row.name] = f"flag {flags[row.name]}"
        elif known is not None:
            out[row.name] = f"{origin}: {known}"
        else:
            out[row.name] = "obsdesign default" if row.is_default else origin
    return out
