"""One general derivation of the reduced-order friction observer.

:func:`derive` takes the model ``A(k), B, C`` of a variant
(:func:`obsdesign.symbolic.model.model_matrices`) and produces, by one
procedure that does not know which variant it is working on:

1. observability (eq:3:1) with a proof that the rank is 3 for every ``k >= 0``;
2. the regular form (eq:3:1:1) with the measured state first;
3. the reduced-order Luenberger observer (eq:3:1:2, eq:3:1:3, eq:3:2:1);
4. its characteristic polynomial, coefficients ``a0, a1`` (eq:3:2:3-4) and
   eigenvalues (eq:3:3:1);
5. the conditions of Ignatyev's theorem (Theorem 1) and of Proposition 1;
6. the one-parameter gain rule of Proposition 2, *solved* from its two design
   conditions (trace ``2 rho sqrt(kappa/m)``; a double pole at ``k = kappa``),
   the designed eigenvalues (eq:3:3:7) and the dominant pole (eq:3:3:2);
7. the transfer of measurement noise into the estimates (eq:3:4:1-4).

Examples
--------
>>> from obsdesign.symbolic import derive
>>> d = derive("lag")
>>> d.gain_rule[d.symbols["L1"]]
2*sqrt(kappa)*rho/sqrt(m)
>>> d.designed_eigenvalues[0]
(-sqrt(kappa)*rho + sqrt(-k + kappa))/sqrt(m)
>>> d.dominant_pole
sqrt(kappa)*(1 - rho)/sqrt(m)
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import sympy as sp

from .model import SYMBOLS, check_variant, model_matrices, model_symbols

__all__ = ["Derivation", "NoiseTransfer", "derive", "regular_form", "LAMBDA", "LAPLACE", "EXTRA_SYMBOLS"]

#: Eigenvalue variable of the characteristic polynomial.
LAMBDA = sp.Symbol("lambda")
#: Laplace variable of the noise transfer functions.
LAPLACE = sp.Symbol("p")

#: Auxiliary symbols of the derivation (not model parameters).
EXTRA_SYMBOLS: dict[str, sp.Symbol] = {
    "x": sp.Symbol("x", real=True),  # measured displacement (w1)
    "v_dot": sp.Symbol("xdot", real=True),  # velocity dx/dt in the stiffness rate
    "k_dot": sp.Symbol("kdot", real=True),  # time derivative of the stiffness
    "z": sp.Symbol("z", positive=True),  # pre-sliding distance |z| in (0, 1]
    "D": sp.Symbol("D", positive=True),  # |sign(v) - f_r| in (0, 2]
    "alpha1": sp.Symbol("alpha_1", positive=True),
    "alpha2": sp.Symbol("alpha_2", positive=True),
}


@dataclass(frozen=True, eq=False)
class NoiseTransfer:
    """Transfer from measurement noise ``eta`` to the observer's estimates.

    At a constant stiffness ``k`` and ``u = 0`` the observer is linear time
    invariant; with ``x_meas = x + eta`` (eq:3:4:1) the estimates respond to
    ``eta`` through ``velocity(p)`` and ``friction(p)``. Each tends to its
    direct feedthrough (``L1`` and ``L2``) at high frequency: the term
    ``-kappa (rho^2 - 1) eta`` of eq:3:4:3-4 for the designed gains.

    Attributes
    ----------
    laplace : Symbol
        The Laplace variable ``p``.
    velocity, friction : Expr
        Rational functions of ``p`` in the gains ``L_1, L_2`` and ``k``.
    velocity_feedthrough, friction_feedthrough : Expr
        Their limits for ``p -> oo``.
    """

    laplace: sp.Symbol
    velocity: sp.Expr
    friction: sp.Expr
    velocity_feedthrough: sp.Expr
    friction_feedthrough: sp.Expr


@dataclass(frozen=True, eq=False)
class Derivation:
    """Every symbolic result of the observer derivation for one variant.

    Built by :func:`derive`; see the module docstring for the procedure. All
    attribute names are a public contract.

    Attributes
    ----------
    variant : {"lag", "static"}
        The model variant.
    symbols : dict
        Name -> SymPy symbol (``m, sigma, beta, Cf, s, kappa, rho, k, L1, L2``, ...).
    A, B, C : sympy.ImmutableMatrix
        The model ``w' = A(k) w + B u``, ``y = C w`` (eq:3:1).
    observability_matrix, observability_determinant, observable
        ``[C; C A; C A^2]``, its determinant and whether it is nonzero for every ``k >= 0``.
    A11, A12, A21, A22, B1, B2 : sympy.ImmutableMatrix
        Blocks of the regular form (eq:3:1:1), the measured state first.
    L : sympy.ImmutableMatrix
        The observer gain ``(L1, L2)``.
    observer_matrix, observer_input, observer_output_gain, back_transform : sympy.ImmutableMatrix
        The reduced-order observer eq:3:1:2-3 and the map back to ``(v_hat, f_hat)`` (eq:3:2:1).
    charpoly, a0, a1 : sympy.Expr
        Its characteristic polynomial in ``lambda`` and the coefficients eq:3:2:3-4.
    eigenvalues : tuple
        Its eigenvalues (eq:3:3:1).
    stiffness_rate : sympy.Expr
        ``dk/dt`` along a pre-sliding transition (eq:3:2:7).
    ignatyev_conditions : dict
        Conditions (i), (ii) of Theorem 1.
    stability_conditions : tuple
        Proposition 1.
    gain_rule : dict
        ``L1, L2`` as solved from the design conditions of Proposition 2 (eq:3:3:3-4).
    designed_eigenvalues : tuple
        The eigenvalues with the gain rule (eq:3:3:7).
    dominant_pole : sympy.Expr
        The gross-sliding dominant pole (eq:3:3:2).
    noise : NoiseTransfer
        Noise transfer into the estimates (eq:3:4:1-4).
    steps : tuple
        The derivation step by step, for the printers.
    """

    variant: str
    symbols: dict
    A: sp.ImmutableMatrix
    B: sp.ImmutableMatrix
    C: sp.ImmutableMatrix
    observability_matrix: sp.ImmutableMatrix
    observability_determinant: sp.Expr
    observable: bool
    A11: sp.ImmutableMatrix
    A12: sp.ImmutableMatrix
    A21: sp.ImmutableMatrix
    A22: sp.ImmutableMatrix
    B1: sp.ImmutableMatrix
    B2: sp.ImmutableMatrix
    L: sp.ImmutableMatrix
    observer_matrix: sp.ImmutableMatrix
    observer_input: sp.ImmutableMatrix
    observer_output_gain: sp.ImmutableMatrix
    back_transform: sp.ImmutableMatrix
    charpoly: sp.Expr
    a0: sp.Expr
    a1: sp.Expr
    eigenvalues: tuple
    stiffness_rate: sp.Expr
    ignatyev_conditions: dict
    stability_conditions: tuple
    gain_rule: dict
    designed_eigenvalues: tuple
    dominant_pole: sp.Expr
    noise: NoiseTransfer
    steps: tuple

    def __repr__(self) -> str:
        return f"<Derivation variant={self.variant!r}: {len(self.steps)} steps>"

    def _repr_html_(self) -> str:
        from .printing import derivation_html

        return derivation_html(self)

    def _repr_latex_(self) -> str:
        from .printing import derivation_latex

        return derivation_latex(self, standalone=False)


def regular_form(A, B, C):
    """Reorder a single-output model so that the measured state comes first.

    Parameters
    ----------
    A : Matrix, shape (n, n)
    B : Matrix, shape (n, 1)
    C : Matrix, shape (1, n)
        Must select exactly one state with gain 1 (a displacement sensor).

    Returns
    -------
    dict
        ``A11, A12, A21, A22, B1, B2`` of eq:3:1:1 and the permutation ``order``.

    Examples
    --------
    >>> import sympy as sp
    >>> rf = regular_form(sp.Matrix([[1, 2], [3, 4]]), sp.Matrix([5, 6]), sp.Matrix([[0, 1]]))
    >>> rf["order"], rf["A11"], rf["A12"]
    ((1, 0), Matrix([[4]]), Matrix([[3]]))
    """
    n = A.shape[0]
    if A.shape != (n, n) or B.shape != (n, 1) or C.shape != (1, n):
        raise ValueError(f"regular_form: expected A (n, n), B (n, 1), C (1, n), found {A.shape}, {B.shape}, {C.shape}")
    measured = [j for j in range(n) if C[0, j] != 0]
    if len(measured) != 1 or C[0, measured[0]] != 1:
        raise ValueError(f"regular_form: C must select one state with gain 1, found {list(C)}")
    order = (measured[0],) + tuple(j for j in range(n) if j != measured[0])
    P = sp.ImmutableMatrix(n, n, lambda i, j: 1 if order[i] == j else 0)
    Ar, Br = P * A * P.T, P * B
    return {
        "order": order,
        "A11": Ar[:1, :1],
        "A12": Ar[:1, 1:],
        "A21": Ar[1:, :1],
        "A22": Ar[1:, 1:],
        "B1": Br[:1, :],
        "B2": Br[1:, :],
    }


def _pair(name: str, values) -> sp.Tuple:
    """``(name_1 = v1, name_2 = v2)`` for the steps (an ``Eq`` with a matrix would evaluate to False)."""
    return sp.Tuple(*(sp.Eq(sp.Symbol(f"{name}_{i}"), v, evaluate=False) for i, v in enumerate(values, 1)))


def _linear_bound(expr: sp.Expr, var: sp.Symbol) -> sp.Rel:
    """Solve ``expr > 0`` for ``var`` when ``expr`` is linear in ``var``."""
    slope = sp.diff(expr, var)
    if sp.diff(slope, var) != 0:
        raise ValueError(f"stability condition is not linear in {var}: {expr}")
    bound = sp.simplify(-expr.subs(var, 0) / slope)
    if slope.is_positive:
        return sp.StrictGreaterThan(var, bound)
    if slope.is_negative:
        return sp.StrictLessThan(var, bound)
    raise ValueError(f"sign of d({expr})/d{var} = {slope} is not known")


def _derive(variant: str) -> Derivation:
    A, B, C = model_matrices(variant)
    sym = model_symbols(variant)
    m, kappa, rho, k, L1, L2 = (SYMBOLS[n] for n in ("m", "kappa", "rho", "k", "L1", "L2"))
    x, k_dot = EXTRA_SYMBOLS["x"], EXTRA_SYMBOLS["k_dot"]
    steps: list[tuple[str | None, str, sp.Basic]] = [
        ("eq:3:1", "System matrix A(k), k = dFc/dx", A),
        ("eq:3:1", "Input vector B", B),
        ("eq:3:1", "Output row C (displacement measured)", C),
    ]

    # 1. Observability: det of the Kalman observability matrix, free of zeros for k >= 0.
    n = A.shape[0]
    obs = sp.ImmutableMatrix.vstack(*[C * A**i for i in range(n)])
    det = sp.simplify(obs.det())
    observable = bool(det.is_nonzero)
    steps += [
        ("eq:3:1", "Observability matrix (C; CA; CA^2)", obs),
        ("eq:3:1", "Its determinant (nonzero for every k >= 0: rank 3)", sp.Eq(sp.Symbol("det_O"), det)),
    ]

    # 2. Regular form.
    rf = regular_form(A, B, C)
    A11, A12, A21, A22, B1, B2 = (rf[key] for key in ("A11", "A12", "A21", "A22", "B1", "B2"))
    steps += [
        ("eq:3:1:1", "Regular form block A11", A11),
        ("eq:3:1:1", "Regular form block A12", A12),
        ("eq:3:1:1", "Regular form block A21", A21),
        ("eq:3:1:1", "Regular form block A22", A22),
        ("eq:3:1:1", "Regular form input blocks (B1; B2)", sp.ImmutableMatrix.vstack(B1, B2)),
    ]

    # 3. Reduced-order observer.
    L = sp.ImmutableMatrix([L1, L2])
    observer_matrix = sp.ImmutableMatrix(A22 - L * A12)
    observer_input = sp.ImmutableMatrix(B2 - L * B1)
    output_gain = sp.ImmutableMatrix((A21 - L * A11 + A22 * L - L * A12 * L).applyfunc(sp.expand))
    y_hat = sp.ImmutableMatrix(sp.symbols("ytilde_1 ytilde_2", real=True))
    back_transform = sp.ImmutableMatrix(y_hat + L * x)
    steps += [
        ("eq:3:2:1", "Observer system matrix A22 - L A12", observer_matrix),
        ("eq:3:1:2", "Observer input vector B2 - L B1", observer_input),
        ("eq:3:1:2", "Observer measurement gain A21 - L A11 + A22 L - L A12 L", output_gain),
        ("eq:3:1:3", "Back transformation (v, f) estimate = ytilde + L x", back_transform),
    ]

    # 4. Characteristic polynomial, coefficients, eigenvalues.
    poly = sp.Poly((LAMBDA * sp.eye(2) - observer_matrix).det(), LAMBDA)
    if poly.degree() != 2 or poly.LC() != 1:
        raise ValueError(f"expected a monic quadratic characteristic polynomial, found {poly.as_expr()}")
    a1 = sp.simplify(poly.coeff_monomial(LAMBDA))
    a0 = sp.simplify(poly.coeff_monomial(1))
    charpoly = LAMBDA**2 + a1 * LAMBDA + a0
    discriminant = a1**2 - 4 * a0
    eigenvalues = ((-a1 + sp.sqrt(discriminant)) / 2, (-a1 - sp.sqrt(discriminant)) / 2)
    steps += [
        ("eq:3:2:2", "Characteristic polynomial", sp.Eq(sp.Symbol("chi"), charpoly)),
        ("eq:3:2:3", "Coefficient a0", sp.Eq(sp.Symbol("a_0"), a0)),
        ("eq:3:2:4", "Coefficient a1", sp.Eq(sp.Symbol("a_1"), a1)),
        ("eq:3:3:1", "Eigenvalues", _pair("lambda", eigenvalues)),
    ]

    # 5. Ignatyev's theorem and Proposition 1.
    # Stiffness rate in pre-sliding: k = s dFc/dz = -s Cf D ln z  (eq:2:3:5 with the chain rule),
    # z' = s x'  =>  dk/dt = -s^2 Cf D x' / z  (eq:3:2:7; its sign is negative after a reversal).
    z, D, v_dot = EXTRA_SYMBOLS["z"], EXTRA_SYMBOLS["D"], EXTRA_SYMBOLS["v_dot"]
    s_, Cf = SYMBOLS["s"], SYMBOLS["Cf"]
    stiffness_of_z = -s_ * Cf * D * sp.log(z)
    stiffness_rate = sp.diff(stiffness_of_z, z) * s_ * v_dot
    a0_dot = sp.diff(a0, k) * k_dot
    alpha1, alpha2 = EXTRA_SYMBOLS["alpha1"], EXTRA_SYMBOLS["alpha2"]
    ignatyev = {
        "i": sp.Le(sp.Abs(a0_dot) + sp.Abs(a1), alpha1),
        "ii": sp.Ge(a0_dot + 2 * a0 * a1, alpha2),
    }
    if not sp.diff(a0, k).is_positive:
        raise ValueError(f"a0 must increase with the stiffness k; found d a0/dk = {sp.diff(a0, k)}")
    # With k' = 0 (worst case of the paper's proof) condition (ii) needs a1 > 0 and a0 > 0 for all
    # k >= 0; a0 grows with k, so a0(k = 0) > 0 suffices.
    stability = (_linear_bound(a1, L1), _linear_bound(a0.subs(k, 0), L2))
    steps += [
        ("eq:2:3:5", "Pre-sliding stiffness k(z) = s dFc/dz, z in (0, 1]", sp.Eq(SYMBOLS["k"], stiffness_of_z)),
        ("eq:3:2:7", "Stiffness rate dk/dt (negative after a reversal)", sp.Eq(k_dot, stiffness_rate)),
        ("theorem:1", "Ignatyev condition (i)", ignatyev["i"]),
        ("theorem:1", "Ignatyev condition (ii)", ignatyev["ii"]),
        ("prop:1", "Stability conditions (Proposition 1)", sp.And(*stability)),
    ]

    # 6. Gain rule of Proposition 2, solved from its design conditions.
    design_conditions = [
        sp.Eq(a1, 2 * rho * sp.sqrt(kappa / m)),
        sp.Eq(discriminant.subs(k, kappa), 0),
    ]
    solutions = sp.solve(design_conditions, [L1, L2], dict=True)
    if len(solutions) != 1:
        raise ValueError(f"gain rule: expected one solution of the design conditions, found {solutions}")
    gain_rule = {L: sp.collect(sp.expand(solutions[0][L]), kappa, sp.factor) for L in (L1, L2)}
    designed = tuple(sp.simplify(ev.subs(gain_rule)) for ev in eigenvalues)
    dominant = sp.simplify(designed[0].subs(k, 0))
    steps += [
        ("prop:2", "Design condition: trace term", design_conditions[0]),
        ("prop:2", "Design condition: double pole at k = kappa", design_conditions[1]),
        ("eq:3:3:3", "Gain L1", sp.Eq(L1, gain_rule[L1])),
        ("eq:3:3:4", "Gain L2", sp.Eq(L2, gain_rule[L2])),
        ("eq:3:3:7", "Designed eigenvalues", _pair("lambda", designed)),
        ("eq:3:3:2", "Dominant pole (gross sliding, k = 0)", sp.Eq(sp.Symbol("lambda_max"), dominant)),
    ]

    # 7. Noise propagation at constant stiffness, u = 0, x_meas = eta.
    p = LAPLACE
    resolvent = p * sp.eye(2) - observer_matrix
    den = sp.collect(sp.expand(resolvent.det()), p)
    num = (resolvent.adjugate() * output_gain + L * resolvent.det()).applyfunc(lambda e: sp.collect(sp.expand(e), p))
    velocity_tf, friction_tf = num[0] / den, num[1] / den
    noise = NoiseTransfer(
        laplace=p,
        velocity=velocity_tf,
        friction=friction_tf,
        velocity_feedthrough=sp.limit(velocity_tf, p, sp.oo),
        friction_feedthrough=sp.limit(friction_tf, p, sp.oo),
    )
    steps += [
        ("eq:3:4:4", "Noise to friction estimate (constant k)", sp.Eq(sp.Symbol("G_eta_f"), friction_tf)),
        ("eq:3:4:3", "Its direct feedthrough", sp.Eq(sp.Symbol("D_eta_f"), noise.friction_feedthrough)),
        ("eq:3:4:4", "Noise to velocity estimate (constant k)", sp.Eq(sp.Symbol("G_eta_v"), velocity_tf)),
    ]

    return Derivation(
        variant=variant,
        symbols=dict(sym),
        A=A,
        B=B,
        C=C,
        observability_matrix=obs,
        observability_determinant=det,
        observable=observable,
        A11=A11,
        A12=A12,
        A21=A21,
        A22=A22,
        B1=B1,
        B2=B2,
        L=L,
        observer_matrix=observer_matrix,
        observer_input=observer_input,
        observer_output_gain=output_gain,
        back_transform=back_transform,
        charpoly=charpoly,
        a0=a0,
        a1=a1,
        eigenvalues=eigenvalues,
        stiffness_rate=stiffness_rate,
        ignatyev_conditions=ignatyev,
        stability_conditions=stability,
        gain_rule=gain_rule,
        designed_eigenvalues=designed,
        dominant_pole=dominant,
        noise=noise,
        steps=tuple(steps),
    )


@functools.lru_cache(maxsize=None)
def _derive_cached(variant: str) -> Derivation:
    return _derive(variant)


def derive(variant: str = "lag") -> Derivation:
    """Derive the reduced-order friction observer for a model variant.

    Parameters
    ----------
    variant : {'lag', 'static'}
        ``lag``: eq:3:1 as printed; ``static``: the section 4 adjustment.

    Returns
    -------
    Derivation
        Cached: repeated calls return the same object.

    Raises
    ------
    ValueError
        For an unknown variant.

    Examples
    --------
    >>> d = derive("static")
    >>> d.gain_rule
    {L_1: 2*sqrt(kappa)*rho/sqrt(m) - sigma/m, L_2: -kappa*(rho - 1)*(rho + 1)}
    >>> d.a0, d.a1
    ((-L_2 + k)/m, L_1 + sigma/m)
    >>> d.observable, d.observability_determinant
    (True, -1/m)
    >>> derive("static") is d
    True
    """
    return _derive_cached(check_variant(variant))
