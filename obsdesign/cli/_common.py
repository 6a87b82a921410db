"""Shared pieces of the command line: the parser class, argument types, config flags, output."""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import tempfile
from pathlib import Path

from .._validate import FINITE, NONNEGATIVE, POSITIVE, Range, parse_number
from ..params import VARIANTS, load_preset, preset_names
from ..provenance import load_config

__all__ = ["print_warnings", "UsageError", "Parser", "number", "POSITIVE_ARG", "NONNEGATIVE_ARG", "FINITE_ARG", "PHASE_ARG",
           "integer", "workers_arg", "nonempty", "INPUT_FILE", "INPUT_DIR", "add_config_flags", "add_design_flags",
           "load", "emit", "check_output_file", "check_output_dir", "check_samples", "MAX_SAMPLES", "check_runs", "finite_design", "warn_unstable",
           "add_encoder_flags", "encoder_resolution", "MAX_COUNTS_PER_REV"]

#: Most samples one ``simulate`` run may hold (about 13 GB of trace arrays at 16 doubles per sample).
MAX_SAMPLES = 10**8


class UsageError(Exception):
    """Bad command-line input: reported as one line with exit status 2."""


class Parser(argparse.ArgumentParser):
    """``argparse`` that reports errors as one line (no usage block) through :class:`UsageError`."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # Let "-1e-6" reach the flag's validator instead of being taken for an option.
        self._negative_number_matcher = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|nan)$")

    def error(self, message: str):  # one line, no usage block
        raise UsageError(f"{self.prog}: {message}")


def number(rule: Range, unit: str = ""):
    """An argparse type: a finite number in the rule's range (the flag name is added by argparse)."""

    def parse(text: str) -> float:
        try:
            return parse_number(text, "value", rule, unit)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {rule.describe()}{unit}, found {text!r}") from None

    return parse


POSITIVE_ARG = number(POSITIVE)
NONNEGATIVE_ARG = number(NONNEGATIVE)
FINITE_ARG = number(FINITE)
PHASE_ARG = number(Range(low=0.0, high=90.0), " deg")


def integer(minimum: int, maximum: int | None = None):
    """An argparse type: an integer >= minimum (and <= maximum, a documented ceiling)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = minimum - 1
        if value < minimum or (maximum is not None and value > maximum):
            bound = f" and <= {maximum}" if maximum is not None else ""
            raise argparse.ArgumentTypeError(f"expected an integer >= {minimum}{bound}, found {text!r}")
        return value

    return parse


def nonempty(kind: str):
    """An argparse type: a path or address that is not empty (the one rule for empty paths of every command).

    Parameters
    ----------
    kind : str
        What the text names, for the message (``"file name"``, ``"folder name"``).

    Examples
    --------
    >>> nonempty("folder name")(" ")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: expected a folder name, found ' '
    """

    def parse(text: str) -> str:
        if not text.strip():
            raise argparse.ArgumentTypeError(f"expected a {kind}, found {text!r}")
        return text

    return parse


INPUT_FILE, INPUT_DIR = nonempty("file name"), nonempty("folder name")


def workers_arg(text: str) -> int:
    """An argparse type: local worker processes, from 1 to 4 per core of this machine (bounded before any work).

    Examples
    --------
    >>> workers_arg("1")
    1
    """
    limit = 4 * max(1, os.cpu_count() or 1)
    value = integer(1)(text)
    if value > limit:
        raise argparse.ArgumentTypeError(f"expected an integer from 1 to {limit} (4 per core of this machine), "
                                         f"found {text!r}")
    return value


def add_config_flags(p: argparse.ArgumentParser, *, default_preset: str) -> None:
    """``--preset NAME | --config FILE``."""
    group = p.add_mutually_exclusive_group()
    group.add_argument("--preset", choices=preset_names(), help=f"shipped preset (default: {default_preset})")
    group.add_argument("--config", metavar="FILE", help="TOML config file")
    p.set_defaults(default_preset=default_preset)


def add_design_flags(p: argparse.ArgumentParser, *, json_flag: str | None = "print one JSON object") -> None:
    """The observer overrides shared by check, noise and simulate (and --json)."""
    p.add_argument("--variant", choices=VARIANTS, help="override the config's model variant")
    p.add_argument("--rho", type=POSITIVE_ARG, help="override the gain parameter rho (> 0)")
    p.add_argument("--kappa", type=POSITIVE_ARG, help="override the stiffness bound kappa [N/m] (> 0)")
    if json_flag:
        p.add_argument("--json", action="store_true", help=json_flag)


def shown(path: str, limit: int = 120) -> str:
    """A path for a message: quoted, and shortened in the middle if very long."""
    text = str(path)
    return repr(text if len(text) <= limit else text[:limit // 2] + "..." + text[-limit // 2:])


#: Design flags that override the config once, at the door (:func:`load`).
DESIGN_FLAGS = ("rho", "kappa", "variant")


def load(args: argparse.Namespace):
    """The config of ``--config`` or ``--preset`` (or the command's default preset), with the command's
    design flags (``--rho``, ``--kappa``, ``--variant`` where it has them) applied once by
    :meth:`obsdesign.Config.override`."""
    config = getattr(args, "config", None)
    if config is not None:
        if not config.strip():
            raise UsageError(f"obsdesign {args.command}: argument --config: expected the path of a TOML file, "
                             f"found {config!r}")
        cfg = load_config(config)  # its sources verified: an edited value is never credited to its old source
    else:
        cfg = load_preset(args.preset or args.default_preset)
    return cfg.override(**{flag: getattr(args, flag, None) for flag in DESIGN_FLAGS})


@contextlib.contextmanager
def finite_design(args: argparse.Namespace, flags: tuple[str, ...]):
    """Turn a numerical library's "infs or NaNs" error (values that overflow) into a message naming the flags.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments.
    flags : tuple of str
        Attribute names of the numeric flags of the command (``max_s`` is shown as ``--max-s``).
    """
    try:
        yield
    except (ValueError, OverflowError, FloatingPointError) as e:
        if not (isinstance(e, (OverflowError, FloatingPointError)) or "infs or NaNs" in str(e)):
            raise
        given = ", ".join(f"--{f.replace('_', '-')} {getattr(args, f):g}" for f in flags
                          if getattr(args, f, None) is not None)
        raise ValueError(f"the design overflows to non-finite numbers with {given or 'this config'}; "
                         "use values of a physically meaningful size") from None


def warn_unstable(cfg, what: str) -> None:
    """One ``obsdesign: warning:`` line on stderr if the observer design fails ``check``.

    Parameters
    ----------
    cfg : Config
        The design.
    what : str
        What the result means for an unstable design (ends the message).
    """
    from ..design import design_warnings

    print_warnings(design_warnings(cfg), what)


def print_warnings(notes, what: str = "") -> None:
    """Each note as one ``obsdesign: warning:`` line on stderr; ``what`` (what the result means for
    a design that fails check) follows the note of the failed conditions.

    Parameters
    ----------
    notes : iterable of str
        Notes of :func:`obsdesign.design.design_warnings` (or any one-line notes).
    what : str
        Appended to the note of a failed check.
    """
    import sys

    for note in notes:
        if what and note.startswith("the observer design fails check"):
            note = f"{note}; {what}"
        print(f"obsdesign: warning: {note}", file=sys.stderr)


def emit(args: argparse.Namespace, result, payload: dict, *, units=None) -> None:
    """Print the result as text, or its payload as one strict JSON object with ``--json``.

    ``units`` (the config's :class:`~obsdesign.axis.AxisSpec`) writes the text's units for its axis.
    """
    if args.json:
        from .._format import jsonable  # numpy: loaded only when a command prints

        print(json.dumps(jsonable(payload), allow_nan=False))
    else:
        print(result.text(units) if units is not None and hasattr(result, "text") else result)


def _probe(folder: Path, name: str, command: str, flag: str, path: str) -> None:
    """Create and remove a file named like the output's temporary file in ``folder``."""
    try:
        fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{name}.", suffix=Path(name).suffix + ".tmp")
        os.close(fd)
        os.unlink(tmp)
    except OSError as e:
        raise UsageError(f"obsdesign {command}: argument {flag}: cannot write {shown(path)} "
                         f"({e.strerror or type(e).__name__})") from None


def check_output_file(command: str, flag: str, path: str | None, exts: tuple[str, ...] | None) -> None:
    """An output file can be written: not empty, suffix in ``exts``, its folder exists and is
    writable, and it is not a folder. Called before any work.

    Parameters
    ----------
    command : str
        The subcommand (for the message).
    flag : str
        The flag of the path (for the message).
    path : str or None
        The output file (None: nothing to check).
    exts : tuple of str or None
        Admissible suffixes (lower case), or None for any.
    """
    if path is None:
        return
    if not path.strip():
        raise UsageError(f"obsdesign {command}: argument {flag}: expected a file name, found {path!r}")
    p = Path(path)
    if exts is not None and p.suffix.lower() not in exts:
        raise UsageError(f"obsdesign {command}: argument {flag}: expected a file ending in "
                         f"{' or '.join(exts)}, found {shown(path)}")
    try:
        parent_ok, is_dir = p.parent.is_dir(), p.is_dir()
    except OSError as e:
        raise UsageError(f"obsdesign {command}: argument {flag}: cannot use {shown(path)} "
                         f"({e.strerror or type(e).__name__})") from None
    if not parent_ok:
        raise UsageError(f"obsdesign {command}: argument {flag}: directory {shown(str(p.parent))} does not exist")
    if is_dir:
        raise UsageError(f"obsdesign {command}: argument {flag}: expected a file, found the folder {shown(path)}")
    _probe(p.parent, p.name, command, flag, path)


def check_output_dir(command: str, flag: str, path: str) -> None:
    """An output folder can be used: not empty, not a file, and it (or the nearest existing
    folder above it, if it is to be created) is writable. Called before any work.

    Parameters
    ----------
    command : str
        The subcommand (for the message).
    flag : str
        The flag of the path (for the message).
    path : str
        The output folder.
    """
    if not path.strip():
        raise UsageError(f"obsdesign {command}: argument {flag}: expected a folder name, found {path!r}")
    p = Path(path)
    try:
        exists, is_dir = p.exists(), p.is_dir()
        base = p
        while not base.exists() and base != base.parent:
            base = base.parent
    except OSError as e:
        raise UsageError(f"obsdesign {command}: argument {flag}: cannot use {shown(path)} "
                         f"({e.strerror or type(e).__name__})") from None
    if exists and not is_dir:
        raise UsageError(f"obsdesign {command}: argument {flag}: expected a directory, found the file {shown(path)}")
    if not base.is_dir():
        raise UsageError(f"obsdesign {command}: argument {flag}: expected a directory, found the file "
                         f"{shown(str(base))} in {shown(path)}")
    _probe(base, "obsdesign_probe", command, flag, path)


def check_samples(duration: float, dt: float, *, limit: int = MAX_SAMPLES) -> int:
    """The samples of a run, refused before any allocation if above ``limit`` or the available memory.

    Parameters
    ----------
    duration : float
        Simulated time [s].
    dt : float
        Sample time [s].
    limit : int
        Most samples allowed.

    Returns
    -------
    int
        ``round(duration / dt)``.

    Examples
    --------
    >>> check_samples(6.0, 1e-4)
    60000
    >>> check_samples(1e9, 1e-4)
    Traceback (most recent call last):
    ...
    ValueError: --duration/--dt: expected at most 1e+08 samples (duration / dt), found 1e+13 (duration 1e+09 s, dt 0.0001 s)
    """
    ratio = duration / dt
    available = _available_memory()
    need = ratio * 16 * 8  # about 16 float64 arrays per sample (trace, scenario, noise)
    if not ratio <= limit:
        raise ValueError(f"--duration/--dt: expected at most {limit:.0e} samples (duration / dt), found {ratio:.3g} "
                         f"(duration {duration:g} s, dt {dt:g} s)")
    if available is not None and need > available:
        raise ValueError(f"--duration/--dt: {ratio:.3g} samples need about {need / 1e9:.2g} GB, "
                         f"{available / 1e9:.2g} GB available")
    return int(round(ratio))


def check_runs(vary: dict, samples: int, *, limit: int | None = None) -> int:
    """The runs of a sweep (grid points times samples), refused before the plan is built if above ``limit``.

    Parameters
    ----------
    vary : dict
        ``{name: (lo, hi, n)}`` grid axes.
    samples : int
        Draws per grid point.
    limit : int, optional
        Most runs allowed (default: :data:`obsdesign.sweeps.plan.MAX_RUNS`, the API's own bound).

    Examples
    --------
    >>> check_runs({"rho": (1.0, 2.0, 10)}, 4)
    40
    >>> check_runs({"rho": (1.0, 2.0, 10**8)}, 1)
    Traceback (most recent call last):
    ...
    ValueError: --vary/--samples: expected at most 1e+06 runs (grid points x samples), found 1e+08
    """
    from ..sweeps.plan import MAX_RUNS

    limit = MAX_RUNS if limit is None else limit
    runs = samples
    for _, _, n in vary.values():
        runs *= n
    if runs > limit:
        raise ValueError(f"--vary/--samples: expected at most {limit:.0e} runs (grid points x samples), "
                         f"found {float(runs):.3g}")
    return runs


def _available_memory() -> float | None:
    """Bytes the kernel could give (``MemAvailable`` of Linux), or None if unknown."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except (OSError, ValueError, IndexError):
        pass
    return None


#: Largest ``--counts-per-rev`` (2^40: beyond any encoder; a documented ceiling).
MAX_COUNTS_PER_REV = 2**40


def add_encoder_flags(p: argparse.ArgumentParser, resolution_help: str, counts_help: str, **kwargs) -> None:
    """``--resolution R`` or ``--counts-per-rev N`` (one of them; read by :func:`encoder_resolution`)."""
    group = p.add_mutually_exclusive_group()
    group.add_argument("--resolution", type=POSITIVE_ARG, metavar="R", help=resolution_help, **kwargs)
    group.add_argument("--counts-per-rev", type=integer(1, MAX_COUNTS_PER_REV), metavar="N", help=counts_help)


def encoder_resolution(args: argparse.Namespace) -> float | None:
    """The size of one count [m or rad]: ``--resolution``, or ``2 pi / --counts-per-rev`` rad."""
    import math

    return 2.0 * math.pi / args.counts_per_rev if args.counts_per_rev is not None else args.resolution
