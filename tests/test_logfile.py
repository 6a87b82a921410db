"""Logs as drives and lab systems write them (issue 40): every format, any unit, CSV as the tools export it.

Each format's file is written here by the field's own library (npTDMS, asammdf, h5py, mcap-ros2, pyarrow)
from the same samples as a CSV reference; ``identify`` must give the same result from each, bit for bit
(the samples are stored as doubles). The unit cases compare against a CSV in SI units: a German
TwinCAT-style export, a rotary log in deg with the current in mA, a current in % of the rated one.
"""

import contextlib
import io
import json
import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from obsdesign.cli import main
from obsdesign.data import load_trace
from obsdesign.data.logfile import FORMATS, MissingExtra, read_log

sys.path.insert(0, str(Path(__file__).parent))
from _axis_logs import DT, GAIN, axis_log  # noqa: E402

RAD_PER_M = 50.0  # the rotary log is the linear motion read as an angle
RATED = 2.5  # A, the rated current of the % log
#: sensor_msgs/msg/JointState with its dependencies, as ROS 2 writes a schema into an MCAP file.
JOINT_STATE = """std_msgs/Header header
string[] name
float64[] position
float64[] velocity
float64[] effort
================================================================================
MSG: std_msgs/Header
builtin_interfaces/Time stamp
string frame_id
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""
STAMP0 = 1_700_000_000 * 10**9  # ns, the first message's stamp (a UNIX time, as ROS writes it)
STEP_NS = int(round(DT * 1e9))


def run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, out.getvalue(), err.getvalue()


def identified(path, *flags) -> dict:
    code, out, err = run("identify", path, *flags, "--input-unit", "A", "--input-gain", GAIN, "--bootstrap", "0",
                         "--json")
    assert code == 0, err
    result = json.loads(out)
    result.pop("units")
    result["config"] = {key: row["value"] for key, row in result["config"].items()}  # its rules name the file
    return result


def write_csv(path, columns: dict, delimiter=","):
    np.savetxt(path, np.column_stack(list(columns.values())), delimiter=delimiter, header=delimiter.join(columns),
               comments="", fmt="%.17g")


@pytest.fixture(scope="module")
def samples(tmp_path_factory):
    """The fast synthetic axis (12 s at 2 kHz) and its CSV reference, ``t,x,i`` in s, m, A."""
    d = tmp_path_factory.mktemp("formats")
    log = axis_log("fast", duration=12.0)
    write_csv(d / "reference.csv", {"t": log["t"], "x": log["x"], "i": log["i"]})
    return d, log


@pytest.fixture(scope="module")
def reference(samples):
    d, _ = samples
    return identified(d / "reference.csv", "--position", "x", "--input", "i", "--time", "t")


# -- every format, bit for bit -------------------------------------------------------------------

def write_tdms(path, log):
    from nptdms import ChannelObject, TdmsWriter

    wave = {"wf_increment": DT, "wf_start_offset": 0.0, "wf_xunit_string": "s"}
    with TdmsWriter(path) as w:
        w.write_segment([ChannelObject("axis", "t", log["t"], properties={"unit_string": "s"}),
                         ChannelObject("axis", "x", log["x"], properties={"unit_string": "m", **wave}),
                         ChannelObject("axis", "i", log["i"], properties={"unit_string": "A", **wave})])


def write_mdf(path, log):
    from asammdf import MDF, Signal

    mdf = MDF(version="4.10")
    mdf.append([Signal(log["x"], log["t"], name="x", unit="m"), Signal(log["i"], log["t"], name="i", unit="A")])
    mdf.save(path, overwrite=True)
    mdf.close()


def write_hdf5(path, log):
    import h5py

    with h5py.File(path, "w") as f:
        for name, unit in (("t", "s"), ("x", "m"), ("i", "A")):
            f[f"axis/{name}"] = log[name]
            f[f"axis/{name}"].attrs["unit"] = unit


def write_parquet(path, log):
    import pyarrow as pa
    import pyarrow.parquet as pq

    fields = [pa.field(name, pa.float64(), metadata={"unit": unit}) for name, unit in (("t", "s"), ("x", "m"),
                                                                                         ("i", "A"))]
    pq.write_table(pa.table({k: log[k] for k in ("t", "x", "i")}, schema=pa.schema(fields)), path)


def write_mcap(path, log):
    from mcap_ros2.writer import Writer

    with open(path, "wb") as f:
        w = Writer(f)
        schema = w.register_msgdef("sensor_msgs/msg/JointState", JOINT_STATE)
        for k, (x, i) in enumerate(zip(log["x"], log["i"])):
            ns = STAMP0 + k * STEP_NS
            msg = {"header": {"stamp": {"sec": ns // 10**9, "nanosec": ns % 10**9}, "frame_id": "base"},
                   "name": ["axis"], "position": [float(x)], "velocity": [0.0], "effort": [float(i)]}
            w.write_message("/joint_states", schema, msg, log_time=ns + 12_345, publish_time=ns)
        w.finish()


#: format -> (writer, file name, flags that pick the channels with a time channel, without one (the file's own)).
WRITERS = {
    "TDMS": (write_tdms, "run.tdms", ["--position", "axis/x", "--input", "axis/i", "--time", "axis/t"],
             ["--position", "axis/x", "--input", "axis/i"]),
    "MDF4": (write_mdf, "run.mf4", None, ["--position", "x", "--input", "i"]),
    "HDF5": (write_hdf5, "run.h5", ["--position", "axis/x", "--input", "axis/i", "--time", "axis/t"], None),
    "Parquet": (write_parquet, "run.parquet", ["--position", "x", "--input", "i", "--time", "t"], None),
    "MCAP": (write_mcap, "run.mcap", None, ["--position", "/joint_states/position/axis",
                                            "--input", "/joint_states/effort/axis"]),
}


#: MCAP's decoder is pure Python: 24000 messages take 5 to 10 s to write and as long to read.
FORMAT_PARAMS = [pytest.param(n, marks=pytest.mark.slow) if n == "MCAP" else n for n in sorted(WRITERS)]


def test_every_format_is_tested_and_documented_with_its_install_line():
    assert set(WRITERS) | {"CSV", "MATLAB"} == set(FORMATS)
    page = (Path(__file__).resolve().parents[1] / "docs" / "measured-data.md").read_text(encoding="utf-8")
    for fmt in FORMATS.values():
        assert all(f"`{ext}`" in page for ext in fmt.extensions), fmt.name
        assert fmt.extra is None or f'`pip install "obsdesign[{fmt.extra}]"`' in page, fmt.name
    extras = __import__("tomllib").loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())
    extras = extras["project"]["optional-dependencies"]
    for fmt in FORMATS.values():
        if fmt.extra is not None:  # each extra is in the test extra (CI reads every format) and in 'formats'
            assert set(extras[fmt.extra]) <= set(extras["test"]) and set(extras[fmt.extra]) <= set(extras["formats"])


@pytest.mark.parametrize("name", FORMAT_PARAMS)
def test_every_format_identifies_like_the_csv_bit_for_bit(samples, reference, tmp_path, name):
    d, log = samples
    write, file, with_time, own_time = WRITERS[name]
    path = tmp_path / file
    write(path, log)
    assert read_log(path).format == name
    if with_time is not None:
        assert identified(path, *with_time) == reference
    if own_time is not None:
        ref = reference
        if name == "MCAP":  # the stamps in ns since the first, in s: the reference with that time column
            t = np.arange(log["t"].size) * STEP_NS / 1e9
            write_csv(tmp_path / "mcap_ref.csv", {"t": t, "x": log["x"], "i": log["i"]})
            ref = identified(tmp_path / "mcap_ref.csv", "--position", "x", "--input", "i", "--time", "t")
            assert not np.array_equal(t, log["t"])  # so the reference is not the common one by accident
        assert identified(path, *own_time) == ref


def test_units_from_the_files_metadata(samples, tmp_path):
    """Each format's own unit field is read: a position in mm in the file is taken as mm."""
    _, log = samples
    from nptdms import ChannelObject, TdmsWriter

    with TdmsWriter(tmp_path / "mm.tdms") as w:
        w.write_segment([ChannelObject("g", "x", log["x"] * 1e3, properties={"unit_string": "mm",
                                                                          "wf_increment": DT}),
                         ChannelObject("g", "i", log["i"] * 1e3, properties={"unit_string": "mA",
                                                                          "wf_increment": DT})])
    tr = load_trace(tmp_path / "mm.tdms", position="g/x", input="g/i", input_gain=GAIN)
    np.testing.assert_allclose(tr.position, log["x"], rtol=1e-15, atol=0)
    np.testing.assert_allclose(tr.force, GAIN * log["i"], rtol=1e-15, atol=0)
    assert (tr.units.position, tr.units.input, tr.units.input_unit(GAIN), tr.format) == ("mm", "mA", "A", "TDMS")
    assert tr.metadata["time base"] == "the file's time base of channel 'g/x'"


# -- CSV as the tools write it --------------------------------------------------------------------

def german(values) -> list[str]:
    return [format(v, ".17g").replace(".", ",") for v in values]


def test_twincat_style_german_export(samples, tmp_path):
    """Header block, names, a units row, ';' and decimal commas, Latin-1 (the degree sign of a comment)."""
    d, log = samples
    head = ["TwinCAT Scope Export;Achse 2", "Datum;07.12.2026", "Kommentar;Temperatur 21 °C", "Abtastzeit;0,5 ms",
            "Zeit;Position;Strom", "s;mm;A"]
    rows = [";".join(r) for r in zip(german(log["t"]), german(log["x"] * 1e3), german(log["i"]))]
    path = tmp_path / "scope.csv"
    path.write_bytes(("\r\n".join(head + rows) + "\r\n").encode("latin-1"))
    tr = load_trace(path, position="Position", input="Strom", time="Zeit", input_gain=GAIN)
    np.testing.assert_allclose(tr.position, log["x"], rtol=1e-15, atol=0)
    assert np.array_equal(tr.t, log["t"]) and np.array_equal(tr.force, GAIN * log["i"])
    assert tr.metadata["Kommentar"] == "Temperatur 21 °C" and tr.metadata["encoding"] == "Latin-1"
    assert (tr.metadata["delimiter"], tr.metadata["decimal"]) == (";", ",")
    a = identified(path, "--position", "Position", "--input", "Strom", "--time", "Zeit")
    b = identified(d / "reference.csv", "--position", "x", "--input", "i", "--time", "t")
    for key in ("m", "sigma", "Cf", "offset", "nrmse_percent"):
        assert a[key] == pytest.approx(b[key], rel=1e-9), key
    # the same table with a point: bit for bit the reference (no unit conversion)
    same = tmp_path / "scope_si.csv"
    same.write_text("\n".join(head[:4] + ["Zeit;Position;Strom", "s;m;A"] + [
        ";".join(r) for r in zip(german(log["t"]), german(log["x"]), german(log["i"]))]), encoding="utf-8-sig")
    assert identified(same, "--position", "Position", "--input", "Strom", "--time", "Zeit") == b


def test_rotary_log_in_deg_with_current_in_ma(samples, tmp_path):
    d, log = samples
    theta = log["x"] * RAD_PER_M
    write_csv(tmp_path / "rad.csv", {"t": log["t"], "theta": theta, "i": log["i"]})
    write_csv(tmp_path / "deg.csv", {"t [s]": log["t"], "theta [deg]": np.degrees(theta), "i [mA]": log["i"] * 1e3},
              delimiter=";")
    code, out, err = run("identify", tmp_path / "deg.csv", "--position", "theta", "--input", "i", "--time", "t",
                         "--input-gain", GAIN, "--bootstrap", "0", "--json")
    assert code == 0, err
    a = json.loads(out)
    b = identified(tmp_path / "rad.csv", "--position", "theta", "--input", "i", "--time", "t", "--position-unit",
                   "rad")
    assert a["units"]["axis"] == "rotary" and a["units"]["input_unit"] == "A" and a["units"]["mass_unit"] == "kg m^2"
    assert a["config"]["plant.K"]["unit"] == "N m/A"
    for key in ("m", "sigma", "Cf", "offset", "nrmse_percent"):
        assert a[key] == pytest.approx(b[key], rel=1e-9), key
    # the same torque numbers over an angle RAD_PER_M times the travel: inertia = the linear mass / RAD_PER_M, to
    # the bit where both readings leave out the same rows; the pre-sliding window is in the axis's unit (0.1 mm,
    # 0.1 mrad, and 10 times it), so the metres resolve s (a 1.9 um travel floor) where the radians (50 rad per
    # metre: 2 um, 20 um) do not, and the estimates differ within their standard errors
    lin = identified(samples[0] / "reference.csv", "--position", "x", "--input", "i", "--time", "t")
    same_rows = a["travel_floor"] == pytest.approx(lin["travel_floor"] * RAD_PER_M, rel=1e-9)
    assert a["m"] == pytest.approx(lin["m"] / RAD_PER_M, rel=1e-6 if same_rows else 3.0 * lin["m_std"] / lin["m"])


@pytest.mark.parametrize("how", ["flag", "header"])
def test_current_in_percent_of_rated(samples, tmp_path, how):
    d, log = samples
    pct = 100.0 * log["i"] / RATED
    name = "i_pct" if how == "flag" else "i [%]"
    write_csv(tmp_path / "pct.csv", {"t": log["t"], "x": log["x"], name: pct})
    flags = ["--input-unit", "%"] if how == "flag" else []
    code, out, err = run("identify", tmp_path / "pct.csv", "--position", "x", "--input", name.split(" ")[0], "--time",
                         "t", *flags, "--rated", RATED, "A", "--input-gain", GAIN, "--bootstrap", "0", "--json")
    assert code == 0, err
    a = json.loads(out)
    b = identified(d / "reference.csv", "--position", "x", "--input", "i", "--time", "t")
    for key in ("m", "sigma", "Cf", "offset"):
        assert a[key] == pytest.approx(b[key], rel=1e-9), key
    assert a["units"]["input_unit"] == "A"
    code, _, err = run("identify", tmp_path / "pct.csv", "--position", "x", "--input", name.split(" ")[0], "--time",
                       "t", *flags, "--bootstrap", "0")
    assert code == 2 and "--rated: expected the rated value" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("text, kind, factor", [
    ("deg", "angle", math.pi / 180), ("rev", "angle", 2 * math.pi), ("µm", "length", 1e-6), ("inch", "length", 0.0254),
    ("mA", "current", 1e-3), ("mN m", "torque", 1e-3), ("Nm", "torque", 1.0), ("kNm", "torque", 1e3),
    ("%", "fraction", 0.01), ("us", "time", 1e-6), ("min", "time", 60.0), ("counts", "count", 1.0),
    ("lbf", "force", 4.4482216152605),
])
def test_units_by_pint(text, kind, factor):
    """Factors against their definitions (NIST SP 811: 1 inch = 0.0254 m, 1 lbf = 4.4482216152605 N)."""
    from obsdesign.data.units import parse_unit

    found = parse_unit("unit", text)
    assert found[0] == kind and found[1] == pytest.approx(factor, rel=1e-12)


@pytest.mark.parametrize("header, where, unit", [
    ("pos [mm]", "header", "mm"), ("pos[deg]", "header", "deg"), ("pos (um)", "header", "um"),
    ("pos / inch", "header", "inch"), ("pos_mm", "name", "mm"), ("x(t)", "", None),
])
def test_units_written_in_the_header(tmp_path, header, where, unit):
    path = tmp_path / "h.csv"
    path.write_text(f"t,{header},u\n0,1,2\n1,2,3\n", encoding="utf-8")
    ch = list(read_log(path).channels.values())[1]
    assert (ch.unit_from, ch.unit) == (where, unit)


def test_channels_command(samples, tmp_path):
    _, log = samples
    write_tdms(tmp_path / "run.tdms", log)
    code, out, err = run("channels", tmp_path / "run.tdms", "--json")
    assert code == 0, err
    got = json.loads(out)
    assert got["format"] == "TDMS" and [c["name"] for c in got["channels"]] == ["axis/t", "axis/x", "axis/i"]
    x = got["channels"][1]
    assert (x["unit"], x["length"], x["rate"]) == ("m", log["x"].size, f"{1 / DT:.6g} Hz")
    path = tmp_path / "scope.csv"
    path.write_text("Scope;Achse 2\nZeit;Position;Strom\ns;mm;A\n0;1,5;2\n0,001;1,75;3\n", encoding="utf-8")
    code, out, err = run("channels", path)
    assert code == 0, err
    assert "Scope: Achse 2" in out and "Position  mm (units row)" in out and "CSV, 3 columns" in out


# -- bad input: one line, exit 2, nothing written --------------------------------------------------

def test_missing_extra_names_the_install_line(samples, tmp_path, monkeypatch):
    _, log = samples
    write_tdms(tmp_path / "run.tdms", log)
    monkeypatch.setitem(sys.modules, "nptdms", None)  # as if npTDMS were not installed
    with pytest.raises(MissingExtra, match=r'pip install "obsdesign\[tdms\]"'):
        read_log(tmp_path / "run.tdms")
    code, out, err = run("identify", tmp_path / "run.tdms", "--position", "axis/x", "--input", "axis/i", "-o",
                         tmp_path / "never.toml")
    assert code == 2 and 'pip install "obsdesign[tdms]"' in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "never.toml").exists()


@pytest.mark.parametrize("name", FORMAT_PARAMS)
def test_bad_files_are_one_line_exit_2(samples, tmp_path, name):
    _, log = samples
    write, file, with_time, own_time = WRITERS[name]
    flags = with_time or own_time
    good = tmp_path / file
    write(good, log)
    raw = good.read_bytes()
    out_file = tmp_path / "never.toml"
    cases = {"truncated": raw[: len(raw) // 3], "empty": b"", "csv text": b"t,x,i\n0,1,2\n1,2,3\n"}
    for case, content in cases.items():
        bad = tmp_path / f"bad{good.suffix}"
        bad.write_bytes(content)
        code, out, err = run("identify", bad, *flags, "-o", out_file)
        assert code == 2, (case, err)
        assert len(err.strip().splitlines()) == 1 and "Traceback" not in err and "internal" not in err, (case, err)
        assert f"expected a {name} file" in err or f"expected an {name} file" in err or "expected" in err, (case, err)
        assert not out_file.exists()
    # an absent channel lists the channels found
    code, _, err = run("identify", good, *flags[:1], "nope", *flags[2:], "-o", out_file)
    assert code == 2 and "position: expected the name of a channel, found 'nope'; available: " in err.replace(
        "column", "channel")
    assert flags[3] in err and not out_file.exists()


@pytest.mark.slow
def test_the_report_shows_the_file_its_format_units_and_metadata(samples, tmp_path):
    """``report --data`` reads through the same loader; the header block is shown, escaped."""
    _, log = samples
    head = ["Scope;<b>Achse 2</b>", "Zeit [s];Position [mm];Strom [mA]"]
    rows = [";".join(r) for r in zip(german(log["t"]), german(log["x"] * 1e3), german(log["i"] * 1e3))]
    path = tmp_path / "scope.csv"
    path.write_text("\n".join(head + rows) + "\n", encoding="utf-8")
    out = tmp_path / "r.html"
    code, _, err = run("report", "--preset", "vcm", "--no-circle", "--quiet", "--data", path, "--position", "Position",
                       "--input", "Strom", "--time", "Zeit", "--input-gain", GAIN, "-o", out)
    assert code == 0, err
    html = out.read_text()
    assert "<code>scope.csv</code> (CSV)" in html and "position mm, input mA" in html
    assert "&lt;b&gt;Achse 2&lt;/b&gt;" in html and "<b>Achse 2</b>" not in html


CSV_BAD = [
    # digit grouping: a German thousands point, an English thousands comma in a ';' file
    ("t;x;u\n" + "\n".join(f"{k};1.234,5;{k % 7}" for k in range(150)), {}, "digit grouping (thousands separators) "
     "is not read"),
    ("t;x;u\n" + "\n".join(f"{k};1,234.5;{k % 7}" for k in range(150)), {}, "digit grouping"),
    # a decimal comma read with --decimal .
    ("t;x;u\n" + "\n".join(f"{k};0,5;{k % 7}" for k in range(150)), {"decimal": "."}, "a decimal comma: read it "
     "with decimal=','"),
    # a unit of the wrong dimension in the header: the column, the unit, the dimension expected
    ("t;x [A];u\n" + "\n".join(f"{k};{k % 5};{k % 7}" for k in range(150)), {},
     "position: expected a length, an angle or counts for column 'x', found the unit 'A' (a current) in the file's "
     "header; give position_unit (--position-unit)"),
    ("t;x;u\ns;m;kg\n" + "\n".join(f"{k};{k % 5};{k % 7}" for k in range(150)), {},
     "input: expected a current, a voltage, a force, a torque or a fraction (%) for column 'u', found the unit 'kg' "
     "(dimension [mass]) in the file's units row"),
    # a header row of numbers above the first numeric row
    ("1;2;3\n" + "\n".join(f"{k};{k % 5};{k % 7}" for k in range(150)), {}, "expected a header row of column "
     "names above the numeric rows, found numbers on line 1"),
    ("x;u\n" + "\n".join(f"{k};{k % 5};{k % 7}" for k in range(150)), {}, "expected 2 values per row"),
]


@pytest.mark.parametrize("text, kwargs, match", CSV_BAD)
def test_csv_refusals_name_the_cause(tmp_path, text, kwargs, match):
    path = tmp_path / "bad.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ValueError, match=re.escape(match)):
        load_trace(path, position="x", input="u", time="t", time_unit="ms", **kwargs)


def test_decimal_comma_given_and_detected_read_the_same(tmp_path):
    rows = "\n".join(f"{k * 0.001:.3f};{math.sin(k / 10):.6f};{math.cos(k / 10):.6f}".replace(".", ",")
                     for k in range(150))
    path = tmp_path / "c.csv"
    path.write_text("t;x;u\n" + rows, encoding="utf-8")
    a = load_trace(path, position="x", input="u", time="t")
    b = load_trace(path, position="x", input="u", time="t", decimal=",", delimiter=";")
    assert np.array_equal(a.position, b.position) and a.position[10] == pytest.approx(math.sin(1.0), abs=1e-6)
