"""The shipped numeric functions and printed formulas against a fresh symbolic derivation (issue 19).

``obsdesign/design/_generated.py`` and ``obsdesign/export/_formulas.py`` are written once by
``python -m obsdesign.design.numeric --regenerate``; an edit of the symbolic model that is not
regenerated fails here. The generated functions are also compared, at random points, with SymPy's
``lambdify`` of the fresh derivation and with a direct substitution of the expressions.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from obsdesign.design import numeric
from obsdesign.symbolic import derive, generate
from obsdesign.symbolic.model import SYMBOLS

ARGS = tuple(SYMBOLS[n] for n in numeric.ARG_NAMES)


@pytest.mark.parametrize("path, fresh", [(generate.NUMERIC_FILE, generate.numeric_source),
                                         (generate.FORMULAS_FILE, generate.formulas_source)])
def test_shipped_file_equals_a_fresh_derivation(path, fresh):
    assert path.read_text(encoding="utf-8") == fresh(), (
        f"{path.name} is stale: run python -m obsdesign.design.numeric --regenerate")


def test_check_command_reports_a_stale_file(tmp_path, monkeypatch):
    stale = tmp_path / "_generated.py"
    stale.write_text("# an old version\n", encoding="utf-8")
    monkeypatch.setattr(generate, "_targets", lambda: {stale: "# the new version\n"})
    assert generate.main(["--check"]) == 1
    assert stale.read_text(encoding="utf-8") == "# an old version\n"
    assert generate.main(["--regenerate"]) == 0
    assert stale.read_text(encoding="utf-8") == "# the new version\n"
    assert generate.main(["--check"]) == 0
    assert generate.main(["--frobnicate"]) == 2


@pytest.mark.slow  # a fresh interpreter per command (3 s)
def test_computing_commands_do_not_import_sympy():
    code = ("import sys, obsdesign as od; from obsdesign.design import numeric; "
            "od.check_stability(od.load_preset('vcm')); od.noise_analysis(od.load_preset('table1')); "
            "numeric.poly_coeffs('lag', 'velocity'); print('sympy' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == "False"


positive = st.floats(1e-3, 1e4, allow_nan=False)
point = st.fixed_dictionaries({
    "m": positive, "sigma": positive, "beta": st.floats(1e-4, 1.0), "Cf": positive, "s": positive,
    "kappa": positive, "rho": st.floats(0.05, 10.0), "k": st.floats(0.0, 1e4),
    "L1": st.floats(-1e4, 1e4), "L2": st.floats(-1e6, 1e6)})


@pytest.mark.parametrize("variant", ["lag", "static"])
@pytest.mark.parametrize("what", generate.EXPRESSIONS)
@settings(max_examples=25)
@given(values=point)
def test_generated_functions_equal_lambdify_of_a_fresh_derivation(variant, what, values):
    expr = generate.expressions(variant, what)
    reference = sp.lambdify(ARGS, expr, modules="numpy")(*(values[n] for n in numeric.ARG_NAMES))
    got = numeric.compiled(variant, what)(**numeric.model_values(**values))
    # the same evaluation order: bit for bit
    np.testing.assert_array_equal(np.asarray(got, float), np.asarray(reference, float))
    # and the value of the expression itself (exact substitution, evaluated to 30 digits)
    subs = {SYMBOLS[n]: sp.Float(repr(values[n]), 30) for n in numeric.ARG_NAMES}
    exact = np.asarray(sp.Matrix(expr).evalf(30, subs=subs).tolist(), dtype=float).reshape(np.shape(got))
    np.testing.assert_allclose(np.asarray(got, float), exact, rtol=1e-9, atol=1e-9 * np.abs(exact).max())


@pytest.mark.parametrize("variant", ["lag", "static"])
@pytest.mark.parametrize("which", ["velocity", "friction"])
@settings(max_examples=15)
@given(values=point)
def test_noise_coefficients_equal_the_fresh_transfer(variant, which, values):
    num, den = numeric.poly_coeffs(variant, which)(**numeric.model_values(**values))
    transfer = getattr(derive(variant).noise, which)
    subs = {SYMBOLS[n]: values[n] for n in numeric.ARG_NAMES}
    for p in (0.7j, 3.0 + 11.0j):  # the ratio of the polynomials is the transfer at p
        expected = complex(transfer.subs(subs).subs(sp.Symbol("p"), p).evalf(30))
        got = np.polyval(num, p) / np.polyval(den, p)
        if math.isfinite(abs(expected)):
            assert got == pytest.approx(expected, rel=1e-7, abs=1e-12 * max(1.0, abs(expected)))


@pytest.mark.parametrize("variant", ["lag", "static"])
def test_stability_conditions_are_the_derivations(variant):
    rels = derive(variant).stability_conditions
    assert numeric.stability_conditions(variant) == tuple(
        ("L1" if r.lhs == SYMBOLS["L1"] else "L2", str(r.lhs), r.rel_op, sp.sstr(r)) for r in rels)
