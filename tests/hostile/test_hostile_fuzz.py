"""Property-based fuzz of the two readers of user files (issue 36): the config loader and the CSV reader.

Every example ends in one of: a result, or one line of error (exit 2 on the command line, ``ValueError`` or
``TypeError`` in the API); never a traceback, an internal error (exit 3), a hang (each example runs under a
deadline) or a file written beside the input. On the code before issue 36 the CSV fuzz failed at once on a
field over 131,072 characters (``_csv.Error``, exit 3 on the command line).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import obsdesign as od

PRESET_LINES = (Path(od.__file__).parent / "presets" / "vcm.toml").read_text().splitlines()
_VALUE_LINES = [i for i, line in enumerate(PRESET_LINES) if " = " in line and not line.startswith("#")]

#: Values a hostile user (or a damaged file) puts where a number belongs.
HOSTILE_VALUES = st.sampled_from([
    "1e309", "-1e309", "nan", "inf", "-inf", "1" + "0" * 400, "0", "-0.0", "1e-320", "-1", "1e300", "1e-300",
    "1000000000", "2.5", "true", '"x"', '""', "[]", "[1, 2]", "{}", "{ a = 1 }", "'''\n'''", '"\\u0000"', "0x10",
    "1_000", "+inf", "2026-12-04", "\"<script>alert(1)</script>\"", '"' + "a" * 10_000 + '"'])
_TEXT = st.text(alphabet=st.characters(blacklist_categories=("Cs",)), max_size=40)


@st.composite
def configs(draw) -> bytes:
    lines = list(PRESET_LINES)
    for _ in range(draw(st.integers(1, 4))):
        i = draw(st.sampled_from(_VALUE_LINES))
        key = lines[i].split(" = ", 1)[0]
        how = draw(st.sampled_from(["value", "value", "text", "drop", "duplicate", "unknown"]))
        if how == "value":
            lines[i] = f"{key} = {draw(HOSTILE_VALUES)}"
        elif how == "text":
            lines[i] = draw(_TEXT)
        elif how == "drop":
            lines[i] = ""
        elif how == "duplicate":
            lines.insert(i, lines[i])
        else:
            lines.insert(i, f"{draw(st.from_regex(r'[a-z_]{1,12}', fullmatch=True))} = 1.0")
    text = "\n".join(lines).encode("utf-8")
    if draw(st.booleans()) and draw(st.booleans()):
        cut = draw(st.integers(0, len(text)))
        text = text[:cut] + draw(st.binary(max_size=8)) + text[cut:]
    return text


_FIELD = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-10**30, 10**30).map(str),
    st.sampled_from(["", " ", "nan", "1,5", '"1"', "1e999", "--1", "\0", "١", "1" * 200_000, "x" * 140_000]),
    _TEXT)


@st.composite
def csv_files(draw) -> bytes:
    sep = draw(st.sampled_from([",", ";", "\t", " ", "|"]))
    header = draw(st.sampled_from([["t", "x", "u"], ["t", "x", "u", "x"], ["t", "x"], ["", "x", "u"], ["t x", "u"]]))
    rows = []
    t = 0.0
    for _ in range(draw(st.integers(0, 30))):
        t += 1e-3
        row = [repr(t), repr(draw(st.floats(-1, 1))), repr(draw(st.floats(-5, 5)))]
        if draw(st.integers(0, 4)) == 0:
            row[draw(st.integers(0, 2))] = draw(_FIELD)
        rows.append(sep.join(row[:len(header)] if draw(st.integers(0, 9)) else row + ["1"]))
    text = sep.join(header) + "\n" + "\n".join(rows) + "\n"
    if draw(st.integers(0, 9)) == 0:
        text = "\ufeff" + text
    if draw(st.integers(0, 9)) == 0:
        text = text.replace("\n", "\r\n")
    return text.encode("utf-8")


def _one_error(e: BaseException) -> None:
    assert isinstance(e, (ValueError, TypeError)), f"{type(e).__name__}: {e}"
    assert str(e) and "\n" not in str(e).strip() and "Traceback" not in str(e)


SETTINGS = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                           HealthCheck.too_slow,
                                                                           HealthCheck.large_base_example])


@SETTINGS
@given(data=configs())
def test_the_config_loader_gives_a_config_or_one_line(data, tmp_path_factory, cli):
    folder = tmp_path_factory.mktemp("cfg")
    path = folder / "fuzz.toml"
    path.write_bytes(data)
    status, out, err = cli("config", "--config", path, seconds=30)
    assert status in (0, 2), (status, err)
    assert not any("Traceback" in line or "internal error" in line for line in err), err
    if status == 2:
        assert len(err) == 1, err
    else:  # what it printed reads back as the same config
        again = folder / "again.toml"
        again.write_text(out)
        assert od.load_config(again) == od.load_config(path)
        again.unlink()
    assert sorted(p.name for p in folder.iterdir()) == ["fuzz.toml"]  # nothing written beside it


@SETTINGS
@given(data=csv_files())
def test_the_csv_reader_gives_columns_or_one_line(data, tmp_path_factory, within):
    from obsdesign.data import load_trace

    folder = tmp_path_factory.mktemp("csv")
    path = folder / "fuzz.csv"
    path.write_bytes(data)
    try:
        with within(30):
            trace = load_trace(path, position="x", input="u", time="t")
    except Exception as e:  # noqa: BLE001 (the property: which exceptions)
        _one_error(e)
    else:
        assert np.all(np.isfinite(trace.position)) and np.all(np.isfinite(trace.force))
        assert trace.position.size == trace.force.size >= 2
    assert sorted(p.name for p in folder.iterdir()) == ["fuzz.csv"]


def test_a_long_field_is_one_line_on_the_command_line(tmp_path, cli):
    """The review's case end to end (5 MB in one field): exit 2, one line, not an internal error."""
    path = tmp_path / "field.csv"
    path.write_text("t,x,u\n0," + "1" * 5_000_000 + ",0\n1e-3,0,0\n")
    status, _, err = cli("observe", path, "--preset", "vcm", "--position", "x", "--input", "u", "--time", "t")
    assert status == 2 and len(err) == 1 and "at most 100000 characters" in err[0], err
