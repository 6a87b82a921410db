"""The symbolic engine against the paper's printed formulas (lag) and DESIGN.md (static)."""

import numpy as np
import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st

import obsdesign as od
from obsdesign.symbolic import derive, regular_form
from obsdesign.symbolic.derivation import EXTRA_SYMBOLS, LAPLACE

S = od.symbolic.model.SYMBOLS
m, sigma, beta, Cf, s, kappa, rho, k, L1, L2 = (S[n] for n in ("m", "sigma", "beta", "Cf", "s", "kappa", "rho", "k", "L1", "L2"))

# The paper's formulas, typed from the text (eq:3:1 ... eq:3:3:7), and DESIGN.md's static variant.
PAPER = {
    "lag": {
        "A": sp.Matrix([[0, 1, 0], [0, 0, -1 / m], [0, k + sigma / beta, 0]]),
        "observer_matrix": sp.Matrix([[-L1, -1 / m], [k + sigma / beta - L2, 0]]),  # eq:3:2:1
        "a0": (k + sigma / beta - L2) / m,  # eq:3:2:3
        "a1": L1,  # eq:3:2:4
        "eig": [  # eq:3:3:1
            -sp.Rational(1, 2) * (L1 - sp.sqrt(L1**2 + 4 / m * (L2 - k - sigma / beta))),
            -sp.Rational(1, 2) * (L1 + sp.sqrt(L1**2 + 4 / m * (L2 - k - sigma / beta))),
        ],
        "L1": 2 * rho * sp.sqrt(kappa / m),  # eq:3:3:3
        "L2": sigma / beta + kappa * (1 - rho**2),  # eq:3:3:4
        "prop1": (sp.Gt(L1, 0), sp.Lt(L2, sigma / beta)),  # eq:3:2:5-6
    },
    "static": {
        "A": sp.Matrix([[0, 1, 0], [0, -sigma / m, -1 / m], [0, k, 0]]),
        "observer_matrix": sp.Matrix([[-L1 - sigma / m, -1 / m], [k - L2, 0]]),
        "a0": (k - L2) / m,
        "a1": L1 + sigma / m,
        "eig": None,
        "L1": 2 * rho * sp.sqrt(kappa / m) - sigma / m,
        "L2": kappa * (1 - rho**2),
        "prop1": (sp.Gt(L1, -sigma / m), sp.Lt(L2, 0)),
    },
}
DESIGNED = [  # eq:3:3:7, both variants
    -rho * sp.sqrt(kappa / m) + sp.sqrt((kappa - k) / m),
    -rho * sp.sqrt(kappa / m) - sp.sqrt((kappa - k) / m),
]
DOMINANT = -sp.sqrt(kappa / m) * (rho - 1)  # eq:3:3:2

VARIANTS = ["lag", "static"]


def same(a, b):
    return sp.simplify(sp.Matrix([a]) - sp.Matrix([b])) == sp.zeros(*sp.Matrix([a]).shape)


@pytest.mark.parametrize("variant", VARIANTS)
def test_model_and_observer_match_the_paper(variant):
    d, ref = derive(variant), PAPER[variant]
    assert same(d.A, ref["A"])
    assert d.B == sp.Matrix([0, 1 / m, 0]) and d.C == sp.Matrix([[1, 0, 0]])
    assert same(d.observer_matrix, ref["observer_matrix"])
    assert same(d.a0, ref["a0"]) and same(d.a1, ref["a1"])
    assert d.observer_input == sp.Matrix([1 / m, 0])  # B2 - L B1 with B1 = 0
    # Regular-form blocks of eq:3:1:1 with x measured.
    assert d.A11 == sp.Matrix([[0]]) and d.A12 == sp.Matrix([[1, 0]]) and d.A21 == sp.zeros(2, 1)
    assert same(d.A22, ref["A"][1:, 1:])
    assert same(d.back_transform, sp.Matrix(sp.symbols("ytilde_1 ytilde_2", real=True)) + sp.Matrix([L1, L2]) * EXTRA_SYMBOLS["x"])


def test_lag_eigenvalues_match_eq_3_3_1():
    d = derive("lag")
    for ours, paper in zip(d.eigenvalues, PAPER["lag"]["eig"]):
        assert same(ours, paper)


@pytest.mark.parametrize("variant", VARIANTS)
def test_eigenvalues_are_roots_of_the_observer_matrix(variant):
    d = derive(variant)
    lam = sp.Symbol("lambda")
    assert sp.expand(d.charpoly - d.observer_matrix.charpoly(lam).as_expr()) == 0
    for ev in d.eigenvalues:
        assert sp.simplify(d.charpoly.subs(lam, ev)) == 0


@pytest.mark.parametrize("variant", VARIANTS)
def test_gain_rule_designed_eigenvalues_and_dominant_pole(variant):
    d, ref = derive(variant), PAPER[variant]
    assert set(d.gain_rule) == {L1, L2}
    assert same(d.gain_rule[L1], ref["L1"]) and same(d.gain_rule[L2], ref["L2"])
    for ours, paper in zip(d.designed_eigenvalues, DESIGNED):
        assert same(ours, paper)
    assert same(d.dominant_pole, DOMINANT)


@pytest.mark.parametrize("variant", VARIANTS)
def test_proposition_1(variant):
    d = derive(variant)
    assert d.stability_conditions == PAPER[variant]["prop1"]


@pytest.mark.parametrize("variant", VARIANTS)
def test_observable_for_every_stiffness(variant):
    d = derive(variant)
    assert d.observable is True
    assert k not in d.observability_determinant.free_symbols
    assert same(d.observability_determinant, -1 / m)
    # Independent check: numeric rank 3 at the two ends of the stiffness range.
    num = {m: 0.538, sigma: 21.1, beta: 1e-3}
    for kk in (0.0, 8000.0):
        observability = np.array(d.observability_matrix.subs(num).subs(k, kk), dtype=float)
        assert np.linalg.matrix_rank(observability) == 3


@pytest.mark.parametrize("variant", VARIANTS)
def test_designed_eigenvalues_real_and_negative_on_the_whole_stiffness_range(variant):
    """Proof for 0 <= k <= kappa and rho > 1, by substitution of nonnegative slack variables."""
    d = derive(variant)
    lam = sp.Symbol("lambda")
    poly = sp.Poly(d.charpoly.subs(d.gain_rule), lam)
    a1, a0 = poly.coeff_monomial(lam), poly.coeff_monomial(1)
    delta, r = sp.Symbol("delta", nonnegative=True), sp.Symbol("r", positive=True)
    disc = sp.simplify((a1**2 - 4 * a0).subs(k, kappa - delta))  # k = kappa - delta <= kappa
    assert same(disc, 4 * delta / m) and disc.is_nonnegative
    # Real roots with positive sum and product of their negatives: both negative.
    assert sp.expand(a1.subs(rho, 1 + r)).is_positive
    assert sp.expand(a0.subs(rho, 1 + r)).is_positive  # k >= 0 by assumption
    # rho < 1 loses stability in gross sliding (k = 0): a0 < 0.
    r1 = sp.Symbol("r", positive=True)
    a0_gross = sp.factor(a0.subs(k, 0).subs(rho, 1 - r1))
    assert sp.simplify(a0_gross.subs(r1, sp.Rational(1, 10))).is_negative


@given(
    mass=st.floats(0.05, 20), sig=st.floats(0.1, 200), bet=st.floats(1e-4, 1e-1),
    kap=st.floats(10, 1e7), r=st.floats(1.001, 10), frac=st.floats(0, 1),
)
def test_numeric_eigenvalues_agree_with_symbolic(mass, sig, bet, kap, r, frac):
    for variant in VARIANTS:
        d = derive(variant)
        vals = {m: mass, sigma: sig, beta: bet, kappa: kap, rho: r, k: frac * kap}
        A_obs = np.array(d.observer_matrix.subs(d.gain_rule).subs(vals), dtype=float)
        numeric = np.sort(np.linalg.eigvals(A_obs).real)
        ours = np.sort([complex(sp.N(e.subs(vals))).real for e in d.designed_eigenvalues])
        scale = r * np.sqrt(kap / mass)
        np.testing.assert_allclose(numeric, ours, rtol=1e-7, atol=1e-6 * scale)
        assert np.all(numeric < 0)


def test_stiffness_rate_sign_differs_from_eq_3_2_7():
    """dk/dt after a reversal is negative (the paper prints +C1 s x'/z, a non-negative term)."""
    d = derive("lag")
    z, D, xdot = EXTRA_SYMBOLS["z"], EXTRA_SYMBOLS["D"], EXTRA_SYMBOLS["v_dot"]
    # Independent: finite difference of k(z) = -s Cf D ln z along z = s x(t), x = v t.
    vals = {s: 3000.0, Cf: 0.35, D: 1.0}
    v, t, h = 1e-4, 0.5e-3, 1e-9

    def kfun(tt):
        return -vals[s] * vals[Cf] * np.log(vals[s] * v * tt)

    fd = (kfun(t + h) - kfun(t - h)) / (2 * h)
    ours = float(d.stiffness_rate.subs(vals).subs({xdot: v, z: vals[s] * v * t}))
    assert ours == pytest.approx(fd, rel=1e-5) and ours < 0


@pytest.mark.parametrize("variant", VARIANTS)
def test_noise_transfer_against_python_control(variant):
    import control

    d = derive(variant)
    nt = d.noise
    vals = {m: 0.538, sigma: 21.1, beta: 1e-3, kappa: 8000.0, rho: 1.5, k: 3000.0}
    gains = {g: float(e.subs(vals)) for g, e in d.gain_rule.items()}
    vals.update(gains)
    A_o = np.array(d.observer_matrix.subs(vals), dtype=float)
    G_o = np.array(d.observer_output_gain.subs(vals), dtype=float)
    sys = control.ss(A_o, G_o, np.eye(2), np.array([[gains[L1]], [gains[L2]]]))
    w = np.logspace(-1, 5, 13)
    ref = control.frequency_response(sys, w).complex  # (2, 1, nw)
    for row, expr in enumerate((nt.velocity, nt.friction)):
        f = sp.lambdify(LAPLACE, expr.subs(vals), "numpy")
        np.testing.assert_allclose(f(1j * w), ref[row, 0], rtol=1e-9)
    # Feedthroughs are the gains (eq:3:4:3: -kappa (rho^2 - 1) for static; lag adds sigma/beta).
    assert same(nt.friction_feedthrough, L2) and same(nt.velocity_feedthrough, L1)
    assert same(nt.friction_feedthrough.subs(d.gain_rule), PAPER[variant]["L2"])
    # Translation invariance: a constant measurement offset produces no estimate (DC gain 0).
    assert sp.simplify(nt.friction.subs(LAPLACE, 0)) == 0 and sp.simplify(nt.velocity.subs(LAPLACE, 0)) == 0


def test_regular_form_moves_the_measured_state_first():
    A = sp.Matrix([[1, 2, 3], [4, 5, 6], [7, 8, 9]])
    rf = regular_form(A, sp.Matrix([1, 2, 3]), sp.Matrix([[0, 0, 1]]))
    assert rf["order"] == (2, 0, 1)
    assert rf["A11"] == sp.Matrix([[9]]) and rf["A12"] == sp.Matrix([[7, 8]])
    assert rf["A21"] == sp.Matrix([3, 6]) and rf["A22"] == sp.Matrix([[1, 2], [4, 5]])
    assert rf["B1"] == sp.Matrix([[3]]) and rf["B2"] == sp.Matrix([1, 2])
    with pytest.raises(ValueError, match="C must select one state with gain 1"):
        regular_form(A, sp.Matrix([1, 2, 3]), sp.Matrix([[1, 1, 0]]))


def test_ignatyev_conditions_reduce_to_proposition_1_without_stiffness_change():
    d = derive("lag")
    kdot = EXTRA_SYMBOLS["k_dot"]
    lhs = d.ignatyev_conditions["ii"].lhs.subs(kdot, 0)
    assert same(lhs, 2 * PAPER["lag"]["a0"] * PAPER["lag"]["a1"])
    assert same(d.ignatyev_conditions["i"].lhs, sp.Abs(kdot) / m + sp.Abs(L1))


def test_derive_is_cached_and_validates():
    assert derive("lag") is derive("lag")
    assert derive() is derive("lag")
    with pytest.raises(ValueError, match=r"variant: expected one of 'lag', 'static', found 'LAG'"):
        derive("LAG")
    with pytest.raises(TypeError, match=r"variant: expected a string"):
        derive(1)


@pytest.mark.parametrize("variant", VARIANTS)
def test_steps_are_ordered_and_labelled(variant):
    steps = derive(variant).steps
    labels = [lab for lab, _, _ in steps if lab]
    for needed in ["eq:3:1", "eq:3:1:1", "eq:3:2:1", "eq:3:1:2", "eq:3:1:3", "eq:3:2:3", "eq:3:2:4",
                   "eq:3:3:1", "theorem:1", "prop:1", "eq:3:3:3", "eq:3:3:4", "eq:3:3:7", "eq:3:3:2", "eq:3:4:4"]:
        assert needed in labels
    assert labels.index("eq:3:1") < labels.index("eq:3:1:1") < labels.index("eq:3:3:3") < labels.index("eq:3:4:4")
    assert all(isinstance(e, sp.Basic) for _, _, e in steps)
    # No step may have collapsed to a truth value (an Eq of a symbol with a matrix evaluates to False).
    assert not [title for _, title, e in steps if isinstance(e, sp.logic.boolalg.BooleanAtom)]
    eig = dict(((t, e) for _, t, e in steps))["Designed eigenvalues"]
    assert [same(rel.rhs, ref) for rel, ref in zip(eig, DESIGNED)] == [True, True]
