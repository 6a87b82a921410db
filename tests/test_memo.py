"""The on-disk memo (issue 19): exact values, keys that see every bit, and results equal to a fresh computation.

A kept result must be indistinguishable from computing it: every float bit, every field, every
printed line. These tests compare against the same computation with the memo off
(``OBSDESIGN_CACHE=off``), so a value that is kept wrongly, read back wrongly or keyed too coarsely
fails here.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
import shutil
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import obsdesign as od
from obsdesign import _memo
from obsdesign.design.certificate import certify, log_norm
from obsdesign.design.loop import loop_analysis
from obsdesign.design.sampled_loop import sampled_loop


@pytest.fixture
def memo_dir(tmp_path, monkeypatch):
    monkeypatch.setenv("OBSDESIGN_CACHE_DIR", str(tmp_path / "memo"))
    monkeypatch.delenv("OBSDESIGN_CACHE", raising=False)
    return tmp_path / "memo"


def _same(a, b) -> bool:
    """Equal, float bits included (nan equals nan, -0.0 differs from 0.0), containers recursively."""
    if isinstance(a, float) and isinstance(b, float):
        return (math.isnan(a) and math.isnan(b)) or (a == b and math.copysign(1, a) == math.copysign(1, b))
    if isinstance(a, complex) and isinstance(b, complex):
        return _same(a.real, b.real) and _same(a.imag, b.imag)
    if isinstance(a, (list, tuple)) and type(a) is type(b):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if dataclasses.is_dataclass(a) and not isinstance(a, type) and type(a) is type(b):  # a result held in a result
        return _same(_fields(a), _fields(b))
    return type(a) is type(b) and a == b


_leaf = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-2**70, 2**70), st.booleans(),
                  st.none(), st.text(max_size=5),
                  st.complex_numbers(allow_nan=True, allow_infinity=True))
_values = st.recursive(_leaf, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                      st.lists(inner, max_size=4).map(tuple),
                                                      st.dictionaries(st.text(max_size=3), inner, max_size=3)),
                       max_leaves=12)


@given(value=_values)
def test_a_value_comes_back_bit_for_bit(value, tmp_path_factory):
    import os

    saved = os.environ["OBSDESIGN_CACHE_DIR"]
    os.environ["OBSDESIGN_CACHE_DIR"] = str(tmp_path_factory.mktemp("m"))  # each example its own folder
    calls = []

    def compute():
        calls.append(1)
        return value

    try:
        first = _memo.memo("t", (1.0,), compute)
        again = _memo.memo("t", (1.0,), compute)
    finally:
        os.environ["OBSDESIGN_CACHE_DIR"] = saved
    assert len(calls) == 1
    assert _same(first, value) and _same(again, value)


def test_the_key_sees_one_ulp_and_the_namespace(memo_dir):
    calls = []

    def compute():
        calls.append(1)
        return len(calls)

    x = 0.1
    assert _memo.memo("a", (x, np.array([1.0, 2.0])), compute) == 1
    assert _memo.memo("a", (math.nextafter(x, 1.0), np.array([1.0, 2.0])), compute) == 2
    assert _memo.memo("a", (x, np.array([1.0, math.nextafter(2.0, 3.0)])), compute) == 3
    assert _memo.memo("b", (x, np.array([1.0, 2.0])), compute) == 4
    assert _memo.memo("a", (x, np.array([1.0, 2.0])), compute) == 1  # the first one, from disk
    assert _memo.memo("a", (x, np.array([[1.0, 2.0]])), compute) == 5  # another shape
    with pytest.raises(TypeError, match="memo key"):
        _memo.memo("a", (object(),), compute)


def test_off_computes_every_time_and_writes_nothing(memo_dir, monkeypatch):
    monkeypatch.setenv("OBSDESIGN_CACHE", "off")
    calls = []
    for _ in range(3):
        _memo.memo("a", (1.0,), lambda: calls.append(1) or 7.0)
    assert len(calls) == 3 and not memo_dir.exists()


def test_a_broken_entry_is_a_miss(memo_dir):
    assert _memo.memo("a", (2.0,), lambda: [1.0, 2.0], valid=_memo.list_of(2)) == [1.0, 2.0]
    (entry,) = (memo_dir / "a").iterdir()
    for broken in ("{not json", json.dumps([1.0]), json.dumps({"__complex__": 3})):
        entry.write_text(broken)
        with pytest.warns(_memo.MemoWarning, match="computed instead"):
            assert _memo.memo("a", (2.0,), lambda: [1.0, 2.0], valid=_memo.list_of(2)) == [1.0, 2.0]
    assert json.loads(entry.read_text())["value"] == [1.0, 2.0]  # rewritten


def test_an_unwritable_folder_still_gives_the_value(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    monkeypatch.setenv("OBSDESIGN_CACHE_DIR", str(blocker / "below"))  # a folder under a file: cannot exist
    assert _memo.memo("a", (1.0,), lambda: 3.5) == 3.5
    assert _memo.memo("a", (1.0,), lambda: 4.5) == 4.5  # nothing was kept


def test_the_source_hash_sees_every_python_file_and_nothing_else(tmp_path):
    import obsdesign

    root = tmp_path / "pkg"
    shutil.copytree(obsdesign.__path__[0], root, ignore=shutil.ignore_patterns("__pycache__"))
    before = _memo.source_hash(root)
    (root / "__pycache__").mkdir(exist_ok=True)
    (root / "__pycache__" / "x.pyc").write_bytes(b"\0")
    (root / "notes.txt").write_text("not code")
    assert _memo.source_hash(root) == before
    target = root / "design" / "pid.py"
    target.write_text(target.read_text() + "\n# an edit\n")
    assert _memo.source_hash(root) != before


def _forge(entry, value) -> None:
    """Replace an entry's value and sign it as the memo does (a forger who knows the format): only the
    schema and the re-verification stand between it and the result."""
    data = json.loads(entry.read_text())
    data["value"] = _memo._encode(value)
    secret = bytes.fromhex((entry.parent.parent / "secret").read_text())
    data["digest"] = _memo._digest(data["key"], _memo._canonical(data["value"]), secret)
    entry.write_text(json.dumps(data))


def _fields(result) -> dict:
    return {f.name: getattr(result, f.name) for f in dataclasses.fields(result)
            if not dataclasses.is_dataclass(getattr(result, f.name))}


CONFIGS = [
    ("vcm", {}),
    ("table1", {}),
    ("vcm", {"phi": 0.05, "tau": 0.01}),
    ("vcm", {"delay_samples": 2}),
    ("vcm", {"rho": 1.5, "kappa": 2e4}),
    ("table1", {"rho": 0.98}),  # a refuted certificate
]


@pytest.mark.parametrize("preset, override", CONFIGS)
def test_kept_results_equal_a_fresh_computation(preset, override, memo_dir, monkeypatch):
    cfg = od.load_preset(preset).override(**override)

    def results():
        la = loop_analysis(cfg)
        return {"pid": _fields(la.pid), "loop": _fields(la), "sampled": _fields(sampled_loop(cfg)),
                "certificate": certify(od.design_observer(cfg)).to_dict(),
                "noise": od.noise_analysis(cfg).to_dict(),
                "noise at kappa": od.noise_analysis(cfg, stiffness=cfg.friction.kappa, noise_bandwidth=500.0).to_dict()}

    monkeypatch.setenv("OBSDESIGN_CACHE", "off")
    fresh = results()
    monkeypatch.delenv("OBSDESIGN_CACHE")
    results()  # fills the memo
    assert memo_dir.exists()
    kept = results()  # read back
    assert _same(kept, fresh)


def test_kept_systems_are_rebuilt_as_computed(memo_dir):
    import control as ct

    cfg = od.load_preset("vcm")
    loop_analysis(cfg)
    la = loop_analysis(cfg)  # numbers from disk, systems built on request
    H = ct.tf([cfg.phi], [cfg.pid.tau, 1.0, 0.0])
    pid = la.pid
    C = ct.tf([pid.k * pid.tau * pid.T_I, pid.k * (pid.tau + pid.T_I), pid.k], [pid.T_I, 0.0])
    w = np.logspace(-1, 4, 50)
    for got, want in ((pid.S, ct.feedback(H, C)), (la.T, ct.feedback(C * H, 1)), (la.sampled.L.dt, cfg.observer.dt)):
        if isinstance(want, float):
            assert got == want
        else:
            np.testing.assert_allclose(ct.frequency_response(got, w).complex, ct.frequency_response(want, w).complex,
                                       rtol=1e-12)
    # the kept phase margin is python-control's own for the rebuilt loop
    assert ct.stability_margins(pid.C * pid.H)[1] == pid.phase_margin_achieved_deg


@pytest.mark.parametrize("preset, override", [("vcm", {}), ("table1", {"delay_samples": 1})])
def test_kept_frequency_responses_are_python_control_s(preset, override, memo_dir):
    """The figures' curves (design.pid.kept_response) are python-control's frequency responses of the
    systems, every bit, computed or read back; another grid or system is another entry."""
    import control as ct

    from obsdesign.design.pid import kept_response

    cfg = od.load_preset(preset).override(**override)
    la, na = loop_analysis(cfg), od.noise_analysis(cfg)
    w = np.logspace(-1, 5, 300)
    wz = np.logspace(-1, math.log10(0.99 * math.pi / cfg.observer.dt), 300)  # a sampled loop: below Nyquist
    cases = [(la.pid, "S", w), (la, "L", w), (la, "T", w), (la.sampled, "L", wz), (la.sampled, "S", wz),
             (na, "G_friction", w), (na, "G_friction_filtered", w)]
    wants = [np.asarray(ct.frequency_response(getattr(r, n), grid).complex).ravel() for r, n, grid in cases]
    product = np.asarray(ct.frequency_response(na.lowpass * na.G_friction, w).complex).ravel()
    for _ in range(2):  # computed, then read back
        for (result, name, grid), want in zip(cases, wants):
            got = kept_response(result, name, grid)
            assert got.dtype == want.dtype and got.tobytes() == want.tobytes(), name
        assert kept_response(na, "G_friction_filtered", w).tobytes() == product.tobytes()
    for entry in (memo_dir / "frequency_response").iterdir():
        entry.write_text(json.dumps([[1.0], [2.0]]))  # not an entry: computed again
    with pytest.warns(_memo.MemoWarning):
        assert kept_response(la, "L", w).tobytes() == wants[1].tobytes()
    with pytest.raises(ValueError, match="name: expected a system of LoopAnalysis, found 'K'"):
        kept_response(la, "K", w)


def test_a_tampered_search_result_cannot_certify_more(memo_dir):
    design = od.design_observer(od.load_preset("vcm"))
    honest = certify(design)
    entries = list((memo_dir / "cqlf").iterdir())
    assert entries
    for bad in ([[1.0, 0.0], [0.0, -1.0]], [[1.0, 0.0], [0.0, 1e-300]], [[1.0, 5.0], [5.0, 26.0]], "x"):
        for e in entries:
            _forge(e, bad)
        with warnings.catch_warnings():  # a positive definite proposal is used (and verified), another warns
            warnings.simplefilter("ignore", _memo.MemoWarning)
            got = certify(design)
        assert got.verdict == honest.verdict and got.decay_rate <= honest.decay_rate * (1 + 1e-12)
        # whatever P came back, it proves the decay rate claimed, at both ends (balanced or not)
        A_lo, A_hi = design.matrices(0.0)[0], design.matrices(design.kappa)[0]
        P = np.asarray(got.P)
        assert max(log_norm(A_lo, P), log_norm(A_hi, P)) <= -got.decay_rate * (1 - 1e-6)


@pytest.mark.parametrize("name, rule", [("eso", "noise"), ("kalman", "noise"), ("dob", "rate"), ("eso", "min-error")])
def test_a_kept_tuning_equals_a_fresh_one(name, rule, memo_dir, monkeypatch):
    from obsdesign.estimators import tune

    cfg = od.load_preset("vcm")
    monkeypatch.setenv("OBSDESIGN_CACHE", "off")
    fresh = tune(name, cfg, rule=rule)
    monkeypatch.delenv("OBSDESIGN_CACHE")
    tune(name, cfg, rule=rule)
    kept = tune(name, cfg, rule=rule)
    assert (memo_dir / "tune").exists() or (name, rule) == ("dob", "rate")  # dob's rate knob is the pole itself
    assert (memo_dir / "dlqe").exists() == (name == "kalman")  # the Kalman filter's Riccati solution is kept too
    assert _same(kept.params, fresh.params)
    for field in ("Phi", "gu", "g0", "g1", "Cz", "d"):
        assert np.array_equal(getattr(kept, field), getattr(fresh, field))


@pytest.mark.parametrize("preset, override", [("vcm", {}), ("table1", {"rho": 1.5}), ("vcm", {"noise_rms": 3e-7})])
def test_the_kept_equal_noise_target_is_the_computed_one(preset, override, memo_dir, monkeypatch):
    from obsdesign.estimators import friction_noise_rms, noise_level, reference_noise_rms
    from obsdesign.estimators.tuning import reference_estimator

    cfg = od.load_preset(preset).override(**override)
    fresh = friction_noise_rms(reference_estimator(cfg), *noise_level(cfg))  # the definition, never kept
    first, kept = reference_noise_rms(cfg), reference_noise_rms(cfg)
    assert (memo_dir / "reference_noise_rms").exists()
    assert _same(first, fresh) and _same(kept, fresh)
    for entry in (memo_dir / "reference_noise_rms").iterdir():
        _forge(entry, -1.0)  # not a noise RMS: computed again
    with pytest.warns(_memo.MemoWarning):
        assert _same(reference_noise_rms(cfg), fresh)


def test_a_mis_shaped_riccati_entry_is_solved_again(memo_dir):
    from obsdesign.estimators import build_kalman

    cfg = od.load_preset("vcm")
    fresh = build_kalman(cfg, q=1e3)
    for bad in ([[1.0, 2.0], [3.0, 4.0]], "x", [[1.0, 2.0, "3"]] * 3, None):
        for entry in (memo_dir / "dlqe").iterdir():
            _forge(entry, bad)
        with pytest.warns(_memo.MemoWarning):
            again = build_kalman(cfg, q=1e3)
        assert np.array_equal(again.Phi, fresh.Phi) and np.array_equal(again.g1, fresh.g1), bad


def test_a_kept_derivation_is_data_rendered_with_escaping(memo_dir, monkeypatch):
    """The memo keeps the derivation as a tree; the page's markup is rendered from it every time, the same
    with and without the memo, and a tree with an element outside the allowlist is derived again."""
    from obsdesign.report.markup import derivation_tree, is_derivation_tree, render_derivation
    from obsdesign.report.page import derivation_markup
    from obsdesign.symbolic import derive
    from obsdesign.symbolic.printing import derivation_html

    fresh = {v: render_derivation(derivation_tree(derivation_html(derive(v)))) for v in ("static", "lag")}
    monkeypatch.setenv("OBSDESIGN_CACHE", "off")
    assert derivation_markup("static") == fresh["static"]
    monkeypatch.delenv("OBSDESIGN_CACHE")
    assert derivation_markup("static") == fresh["static"]  # computed and kept
    (entry,) = (memo_dir / "derivation_tree").iterdir()
    kept = json.loads(entry.read_text())["value"]
    assert is_derivation_tree(kept) and re.search(r"<[a-z/!?]", entry.read_text()) is None  # data, not markup
    assert derivation_markup("static") == fresh["static"]  # read back
    for bad in (["table", [], ["style", [], "td {display: none}"]], ["table", [["onclick", "x"]]], "<table>", []):
        _forge(entry, bad)
        with pytest.warns(_memo.MemoWarning, match="shape"):
            assert derivation_markup("static") == fresh["static"]  # derived again, not embedded
        assert json.loads(entry.read_text())["value"] == kept  # and the entry rewritten
