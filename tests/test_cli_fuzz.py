"""Random argument vectors never crash the command line.

Hypothesis builds argument vectors from pools of good, bad and hostile values (numbers out
of range, huge and tiny, NaN, unicode, empty strings, paths that are folders, unwritable or
too long) and runs ``obsdesign.cli.main`` in process. Whatever the vector: no traceback,
an exit status of 0, 1 or 2, and at most one line on stderr for status 2. The pools keep
each run short (tiny durations; ``report`` always gets an output path that is refused
before the work).
"""

import contextlib
import io
import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from obsdesign.cli import main

NUMBERS = ["4", "1.02", "0.98", "0", "-1", "1e308", "1e-300", "nan", "inf", "-inf", "", "abc", "0x10", "1_000",
           " 4 ", "٤", "1e400", "9" * 400, "60deg", "²", "-0", "1e-9"]
DURATIONS = ["0.01", "0.02", "1e-4", "0", "-1", "1e9", "nan", "x"]
TEXTS = ["", "lag", "static", "dynamic", "LAG", "pid", "pid+observer", "open-loop", "estimated", "true", "model",
         "physical", "bogus", "é", "\u2028", "a" * 300, "--", "-", "table1", "vcm", "../presets/vcm"]


@pytest.fixture(scope="module")
def paths(tmp_path_factory):
    root = tmp_path_factory.mktemp("fuzz")
    (root / "folder.csv").mkdir()
    (root / "folder.html").mkdir()
    (root / "file").write_text("x")
    (root / "bad.toml").write_bytes(b"\xff\xfe not toml")
    return {
        "out": [str(root / "t.csv"), str(root / "t.npz"), str(root / "t.txt"), str(root / "folder.csv"), "",
                "/proc/x.csv", str(root / ("a" * 5000)) + ".csv", str(root / "missing" / "t.csv")],
        "plot": [str(root / "p.svg"), str(root / "p.pdf"), "/proc/p.svg", str(root / "folder.csv"), ""],
        "dir": [str(root / "ex"), str(root / "file"), "/proc/ex", "", str(root / ("b" * 5000))],
        "report_out": [str(root / "folder.html"), "/proc/r.html", "", str(root / "missing" / "r.html"),
                       str(root / ("c" * 5000)) + ".html"],
        "config": ["", str(root / "bad.toml"), str(root / "missing.toml"), str(root), "/dev/null", "a" * 5000],
        "sweep": [str(root), str(root / "missing"), ""],
    }


def _flags(paths):
    number = st.sampled_from(NUMBERS)
    text = st.sampled_from(TEXTS)
    common = {"--preset": text, "--config": st.sampled_from(paths["config"]), "--rho": number, "--kappa": number,
              "--variant": text, "--json": st.none()}
    return {
        "derive": {"--variant": text, "--format": st.sampled_from(["text", "json", "latex", "yaml", ""])},
        "check": common,
        "pid": {**common, "--phi": number, "--tau": number, "--max-s": number, "--phase-margin": number},
        "noise": {**common, "--noise-rms": number, "--noise-bandwidth": number, "--stiffness": number},
        "simulate": {**common, "--controller": text, "--stiffness": text, "--plant": text, "--noise-rms": number,
                     "--dt": number, "--seed": number, "--step-size": number, "--step-up": number,
                     "--step-down": number, "--input-force": number, "--settle-tol": number,
                     "--out": st.sampled_from(paths["out"]), "--plot": st.sampled_from(paths["plot"])},
        "export": {**common, "--format": st.sampled_from(["c", "python", "js", "octave", "latex", "pdf", ""]),
                   "--dt": number, "-o": st.sampled_from(paths["dir"])},
        "report": {"--preset": text, "--config": st.sampled_from(paths["config"]),
                   "--sweep": st.sampled_from(paths["sweep"]), "--quiet": st.none()},
    }


@st.composite
def argv(draw, paths):
    flags = _flags(paths)
    command = draw(st.sampled_from(sorted(flags)))
    out = [command]
    if command == "simulate":
        out += [draw(st.sampled_from(["positioning", "constant", "excitation", "tracking", "bogus", ""])),
                "--duration", draw(st.sampled_from(DURATIONS))]
    if command == "report":  # always refused before the (long) work
        out += ["-o", draw(st.sampled_from(paths["report_out"]))]
    if command == "export" and draw(st.booleans()):
        out += ["--format", "c"]
    for flag in draw(st.lists(st.sampled_from(sorted(flags[command])), max_size=4)):
        value = flags[command][flag]
        out += [flag] if value is None or value.is_empty else [flag, draw(value)]
    if draw(st.integers(0, 9)) == 0:
        out.insert(draw(st.integers(0, len(out))), draw(st.sampled_from(["--bogus", "-x", "--help"])))
    return out


def test_random_argument_vectors_never_crash(paths):
    @settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
    @given(argv(paths))
    def run(args):
        out, err = io.StringIO(), io.StringIO()
        env_debug = os.environ.pop("OBSDESIGN_DEBUG", None)
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                status = main(args)
        finally:
            if env_debug is not None:
                os.environ["OBSDESIGN_DEBUG"] = env_debug
        lines = err.getvalue().strip().splitlines()
        assert "Traceback" not in err.getvalue(), (args, err.getvalue())
        assert status in (0, 1, 2), (args, status, lines)
        if status == 2:
            assert len(lines) <= 1, (args, lines)
        if status == 1:
            assert args[0] == "check", (args, lines)

    run()
