"""Command ``config``: print a complete, commented TOML config that every command accepts.

Examples
--------
>>> from obsdesign.params import load_preset, Config
>>> text = config_toml(load_preset("vcm"))
>>> Config.from_toml(text) == load_preset("vcm")
True
>>> "# beta = " in text and "[compensation]" in text
True
"""

from __future__ import annotations

import argparse
import dataclasses

from .._format import toml_value as _toml_value
from ..params import SECTIONS
from ._common import add_config_flags, load

__all__ = ["add_commands", "config_toml"]

_HEADER = """\
# obsdesign design config ({label}).
# Every command reads it: obsdesign check|pid|noise|loop|simulate|sweep|export|report --config FILE.
# Units are SI (angles in degrees where the key says so). Lines starting with '#' are comments;
# a commented-out key is not set and takes the default described on it.
# [sensor] and [compensation] may be left out (their defaults apply)."""


def _comment(text: str) -> str:
    """Text safe inside a TOML comment (no control characters)."""
    return "".join(" " if ord(ch) < 0x20 or ord(ch) == 0x7F else ch for ch in text)


def config_toml(cfg, *, label: str | None = None) -> str:
    """The config as TOML with every key (unset optional keys commented out) and its unit and meaning.

    Parameters
    ----------
    cfg : Config
        The config to print.
    label : str, optional
        Where it comes from, for the header (default: its name).

    Returns
    -------
    str
        A TOML document with ``Config.from_toml(text) == cfg`` (sources included).
    """
    label = label or f"design {cfg.name!r}"
    lines = [_HEADER.format(label=_comment(label)), "", f"name = {_toml_value(cfg.name)}", *cfg.axis_toml()]
    for key in SECTIONS:
        section = getattr(cfg, key)
        lines += ["", f"[{key}]"]
        for f in dataclasses.fields(section):
            value = getattr(section, f.name)
            unit, doc = cfg.units.unit(f.metadata["unit"]), cfg.units.words(f.metadata["doc"])
            if value is None:
                lines.append(f"# {f.name} = ...  # [{unit}] {doc} (not set)")
            else:
                source = cfg.source_of(f"{key}.{f.name}")
                note = f"; source: {_comment(source)}" if source else ""
                lines.append(f"{f.name} = {_toml_value(value)}  # [{unit}] {doc}{note}")
    return "\n".join(lines + cfg.extra_tables_toml()) + "\n"


def _cmd_config(args: argparse.Namespace) -> int:
    cfg = load(args)
    label = f"config file {args.config}" if args.config else f"preset {cfg.name}"
    print(config_toml(cfg, label=label), end="")
    return 0


def add_commands(sub) -> None:
    """Add ``config`` to the subparsers ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subparsers of the ``obsdesign`` parser.
    """
    p = sub.add_parser("config", help="print a complete, commented TOML config (obsdesign config > my.toml)")
    add_config_flags(p, default_preset="vcm")
    p.set_defaults(run=_cmd_config)
