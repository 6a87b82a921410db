"""The result memo under attack (issue 36, reliability review 2026-12-04): a poisoned, planted or odd entry
is a miss with one warning, never a hang, never markup on the page, never a forged number printed.

Each case failed on the code before issue 36 (commit 5089376): the FIFO hung ``pid`` and ``check``,
the symlinked and oversized entries were read, the forged PID printed 89 deg, the planted derivation put
an ``<img onerror>`` (through ``<!-->``) and a ``<style>`` on the page, the folder was created 0755 and
entries carried no signature.
"""

from __future__ import annotations

import json
import math
import os
import re
import stat
import warnings

import numpy as np
import pytest

import obsdesign as od
from obsdesign import _memo
from obsdesign.design.loop import loop_analysis


def _entry(memo_dir, namespace):
    (entry,) = (memo_dir / namespace).iterdir()
    return entry


def _sign(memo_dir, data) -> None:
    """Sign ``data`` as the memo does, with the folder's own secret (a forger who can read it)."""
    secret = bytes.fromhex((memo_dir / "secret").read_text())
    data["digest"] = _memo._digest(data["key"], _memo._canonical(data["value"]), secret)


def _forge(entry, memo_dir, value, *, sign=True) -> None:
    data = json.loads(entry.read_text())
    data["value"] = _memo._encode(value)
    if sign:
        _sign(memo_dir, data)
    entry.write_text(json.dumps(data))


def _pid_fields(cfg):
    return od.pid_from_config(cfg).to_dict()


def test_the_folder_is_created_0700_and_entries_are_signed(memo_dir):
    _pid_fields(od.load_preset("vcm"))
    for folder in (memo_dir, memo_dir / "pid"):
        assert stat.S_IMODE(os.stat(folder).st_mode) == 0o700
    assert stat.S_IMODE(os.stat(memo_dir / "secret").st_mode) == 0o600
    data = json.loads(_entry(memo_dir, "pid").read_text())
    assert set(data) == {"format", "key", "digest", "value"} and len(data["digest"]) == 64


@pytest.mark.parametrize("kind", ["fifo", "symlink-out", "symlink-dev", "huge", "directory"])
def test_an_entry_that_is_not_a_small_regular_file_is_not_read(kind, memo_dir, tmp_path, within):
    cfg = od.load_preset("vcm")
    fresh = _pid_fields(cfg)
    entry = _entry(memo_dir, "pid")
    outside = tmp_path / "outside.json"
    data = json.loads(entry.read_text())
    data["value"][2] = 89.0
    _sign(memo_dir, data)
    outside.write_text(json.dumps(data))  # a signed forgery outside the folder: a symlink must not reach it
    entry.unlink()
    if kind == "fifo":
        os.mkfifo(entry)
    elif kind == "symlink-out":
        entry.symlink_to(outside)
    elif kind == "symlink-dev":
        entry.symlink_to("/dev/zero")
    elif kind == "huge":
        entry.write_bytes(b" " * (_memo.MAX_ENTRY_BYTES + 1))
    else:
        entry.mkdir()
    with within(30), pytest.warns(_memo.MemoWarning, match="computed instead"):
        got = _pid_fields(cfg)
    assert got == fresh


def test_a_namespace_folder_that_is_a_symlink_is_not_followed(memo_dir, tmp_path):
    cfg = od.load_preset("vcm")
    fresh = _pid_fields(cfg)
    elsewhere = tmp_path / "elsewhere"
    (memo_dir / "pid").rename(elsewhere)
    (memo_dir / "pid").symlink_to(elsewhere)
    with pytest.warns(_memo.MemoWarning, match="symbolic link"):
        assert _pid_fields(cfg) == fresh


def test_a_folder_writable_by_others_is_not_used(memo_dir):
    cfg = od.load_preset("vcm")
    fresh = _pid_fields(cfg)
    entry = _entry(memo_dir, "pid")
    _forge(entry, memo_dir, [0.1, 1.0, 89.0, math.inf, 1.0, True])
    os.chmod(memo_dir, 0o777)
    with pytest.warns(_memo.MemoWarning, match="writable by other users"):
        assert _pid_fields(cfg) == fresh


@pytest.mark.parametrize("sign", [False, True])
def test_a_forged_pid_entry_is_not_printed(sign, memo_dir, cli):
    """The review's case: the PID's phase margin edited to 89 deg. Unsigned, the signature catches it;
    signed with the folder's secret, the re-verification against the loop's response does."""
    cfg = od.load_preset("vcm")
    fresh = _pid_fields(cfg)
    entry = _entry(memo_dir, "pid")
    value = json.loads(entry.read_text())["value"]
    value[2] = 89.0
    _forge(entry, memo_dir, value, sign=sign)
    status, out, err = cli("pid", "--json")
    assert status == 0 and json.loads(out)["phase_margin_achieved_deg"] == fresh["phase_margin_achieved_deg"]
    assert len(err) == 1 and "result memo" in err[0] and ("signature" in err[0] or "89 deg" in err[0]), err


@pytest.mark.parametrize("field, value", [(0, 1e-9), (1, 1e9), (4, 3.0), (5, False), (3, 2.0)])
def test_every_kept_pid_number_is_re_verified(field, value, memo_dir):
    cfg = od.load_preset("vcm")
    fresh = _pid_fields(cfg)
    entry = _entry(memo_dir, "pid")
    forged = json.loads(entry.read_text())["value"]
    forged[field] = value
    _forge(entry, memo_dir, forged)
    with pytest.warns(_memo.MemoWarning):
        assert _pid_fields(cfg) == fresh


@pytest.mark.parametrize("index, value", [(1, 89.0), (0, 2.0), (4, 9.0), (6, 0.5), (9, 1.0),
                                          (8, [complex(-1.0, 0.0)] * 3)])
def test_a_forged_loop_entry_is_re_verified(index, value, memo_dir):
    cfg = od.load_preset("vcm")
    monkey = loop_analysis(cfg)
    fresh = (monkey.phase_margin_deg, monkey.gain_margin_db, monkey.max_S, monkey.max_T, monkey.bandwidth_rad_s,
             monkey.closed_loop_poles)
    entry = _entry(memo_dir, "loop")
    forged = _memo._strict_decode(json.loads(entry.read_text())["value"])
    forged[index] = value
    _forge(entry, memo_dir, forged)
    with pytest.warns(_memo.MemoWarning):
        again = loop_analysis(cfg)
    assert (again.phase_margin_deg, again.gain_margin_db, again.max_S, again.max_T, again.bandwidth_rad_s,
            again.closed_loop_poles) == fresh


@pytest.mark.parametrize("preset, delay", [("vcm", 0), ("table1", 2)])
@pytest.mark.parametrize("index, value", [(1, 89.0), (0, 50.0), (5, 1.01), (7, 0.9), (12, [0.5 + 0j] * 5), (13, 0.1)])
def test_a_forged_sampled_loop_entry_is_re_verified(preset, delay, index, value, memo_dir):
    """The sampled margins ``loop`` prints, re-verified against ``L(exp(j w dt))`` of the closed-form ZOH plant."""
    from obsdesign.design.sampled_loop import sampled_loop

    cfg = od.load_preset(preset).override(delay_samples=delay)
    fresh = sampled_loop(cfg).to_dict()
    entry = _entry(memo_dir, "sampled_loop")
    forged = _memo._strict_decode(json.loads(entry.read_text())["value"])
    if index == 0 and not math.isfinite(forged[0]):
        index, value = 3, 1.0  # no gain margin to forge: a phase crossover instead
    forged[index] = value
    _forge(entry, memo_dir, forged)
    with pytest.warns(_memo.MemoWarning):
        assert sampled_loop(cfg).to_dict() == fresh


def test_an_entry_from_another_memo_folder_is_not_used(memo_dir, tmp_path, monkeypatch):
    """Entries signed by another folder's secret (copied from another machine or user) are misses."""
    cfg = od.load_preset("vcm")
    fresh = _pid_fields(cfg)
    other = tmp_path / "other"
    monkeypatch.setenv("OBSDESIGN_CACHE_DIR", str(other))
    _pid_fields(cfg)
    entry = _entry(other, "pid")
    _forge(entry, other, [0.1, 1.0, 89.0, math.inf, 1.0, True])  # signed, but with the other folder's secret
    (memo_dir / "pid" / entry.name).write_bytes(entry.read_bytes())
    monkeypatch.setenv("OBSDESIGN_CACHE_DIR", str(memo_dir))
    with pytest.warns(_memo.MemoWarning, match="signature"):
        assert _pid_fields(cfg) == fresh


@pytest.mark.parametrize("text", ["{", "[" * 100_000, '{"format": 2, "key": 1, "digest": "", "value": NaN}', "\0" * 10,
                                  json.dumps({"format": 2, "key": "k", "digest": "d", "value": 1, "x": 2})])
def test_a_malformed_entry_is_a_miss(text, memo_dir):
    assert _memo.memo("t", (1.0,), lambda: 2.0) == 2.0
    entry = _entry(memo_dir, "t")
    entry.write_text(text)
    with pytest.warns(_memo.MemoWarning):
        assert _memo.memo("t", (1.0,), lambda: 2.0) == 2.0


def _deep(n: int):
    value: list = [1]
    for _ in range(n):
        value = [value]
    return value


@pytest.mark.parametrize("bad", [{"__float__": "1e400"}, {"__complex__": ["1", 2.0]}, {"__tuple__": 3},
                                 {"__float__": "inf", "x": 1}, _deep(70)])
def test_the_schema_refuses_what_the_memo_never_writes(bad, memo_dir):
    assert _memo.memo("t", (1.0,), lambda: 2.0) == 2.0
    entry = _entry(memo_dir, "t")
    data = json.loads(entry.read_text())
    data["value"] = bad
    _sign(memo_dir, data)
    entry.write_text(json.dumps(data))
    with pytest.warns(_memo.MemoWarning):
        assert _memo.memo("t", (1.0,), lambda: 2.0) == 2.0


INJECTIONS = ["<!--> <img src=x onerror=alert(1)>", "</math></td></tr></table><style>td{display:none}</style>",
              "<script>alert(1)</script>", "]]><img src=x onerror=alert(1)>"]


def test_a_planted_derivation_never_reaches_the_page_as_markup(memo_dir):
    """The review's case: ``<!-->`` reads as a comment to Python's HTMLParser and as text to a browser.
    The memo keeps data, so planted text is rendered as text; a planted element is refused."""
    from obsdesign.report.page import derivation_markup

    fresh = derivation_markup("static")
    entry = _entry(memo_dir, "derivation_tree")
    tree = json.loads(entry.read_text())["value"]
    for text in INJECTIONS:
        planted = ["table", tree[1], ["tr", [], ["td", [], text]], *tree[2:]]
        _forge(entry, memo_dir, planted)  # signed: only the escaping stands between it and the page
        page = derivation_markup("static")
        assert "<img" not in page and "<style" not in page and "<script" not in page and "&lt;" in page
    for planted in (["table", [], ["style", [], "td {display: none}"]],
                    ["table", [], ["tr", [], ["td", [["style", "display:none"]], "x"]]],
                    ["table", [], ["img", [["src", "x"], ["onerror", "alert(1)"]]]],
                    ["table", [["class", "x\" onclick=\"y"]]]):
        _forge(entry, memo_dir, planted)
        with pytest.warns(_memo.MemoWarning, match="shape"):
            assert derivation_markup("static") == fresh
    _forge(entry, memo_dir, planted, sign=False)
    entry.write_text(entry.read_text().replace('"x', '"<img src=x onerror=alert(1)>'))
    with pytest.warns(_memo.MemoWarning, match="signature"):
        assert derivation_markup("static") == fresh


def _poison(memo_dir) -> int:
    """Poison every entry of the folder in turn: unsigned edits, FIFOs, symlinks out, oversized files."""
    entries = sorted(p for p in memo_dir.glob("*/*.json"))
    for i, entry in enumerate(entries):
        kind = i % 4
        if kind == 0:
            data = json.loads(entry.read_text())
            data["value"] = ["<!--> <img src=x onerror=alert(1)>", 89.0]
            entry.write_text(json.dumps(data))
        elif kind == 1:
            entry.unlink()
            os.mkfifo(entry)
        elif kind == 2:
            entry.unlink()
            entry.symlink_to("/etc/passwd")
        else:
            entry.write_bytes(b"[" * (_memo.MAX_ENTRY_BYTES + 10))
    return len(entries)


@pytest.mark.slow
def test_the_report_on_a_poisoned_memo_is_byte_identical_to_one_without(memo_dir, tmp_path, monkeypatch, cli):
    """The issue's criterion: ``report`` built with the memo off, then on a memo whose every entry is poisoned,
    byte for byte but for the line with the date and wall time (about 3 min on the loaded 2-core machine)."""
    monkeypatch.setenv("OBSDESIGN_CACHE", "off")
    status, _, err = cli("report", "--no-paper-studies", "--no-circle", "--quiet", "-o", tmp_path / "off.html",
                         seconds=600)
    assert status == 0, err
    monkeypatch.delenv("OBSDESIGN_CACHE")
    status, _, err = cli("report", "--no-paper-studies", "--no-circle", "--quiet", "-o", tmp_path / "fill.html",
                         seconds=600)
    assert status == 0, err
    assert _poison(memo_dir) > 10
    status, _, err = cli("report", "--no-paper-studies", "--no-circle", "--quiet", "-o", tmp_path / "poisoned.html",
                         seconds=600)
    assert status == 0 and err and all("result memo" in line for line in err), err
    def page(name):  # the one line that differs between any two builds: the date and the wall time
        text, n = re.subn(rb"Generated [0-9-]+ by obsdesign \S+ in [0-9.]+ s\.", b"Generated (when, how long)",
                          (tmp_path / name).read_bytes())
        assert n == 1
        return text

    off = page("off.html")
    assert b"<math" in off
    assert page("fill.html") == off
    assert page("poisoned.html") == off


def test_check_and_pid_do_not_hang_on_a_fifo(memo_dir, cli):
    """The review's case: a FIFO in the memo folder hung ``check`` and ``report``."""
    assert cli("pid")[0] == 0 and cli("check")[0] in (0, 1)
    for entry in list(memo_dir.glob("*/*.json")):
        entry.unlink()
        os.mkfifo(entry)
    with warnings.catch_warnings():
        status, out, err = cli("check", seconds=60)
    assert status in (0, 1) and err and all("result memo" in line and "not a regular file" in line for line in err)
    status, out, err = cli("pid", seconds=60)
    assert status == 0 and "60" in out
    assert np.isfinite(od.pid_from_config(od.load_preset("vcm")).phase_margin_achieved_deg)
