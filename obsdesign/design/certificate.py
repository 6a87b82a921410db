"""A stability certificate for the observer as it runs: switched stiffness, exact discretization.

The paper proves uniform asymptotic stability of the continuous-time observer (Ignatyev's theorem,
Proposition 2). What runs is the exactly discretized observer whose matrix ``Phi(k) = expm(A(k) dt)``
switches with the scheduled stiffness ``k`` at every sample, ``k`` anywhere in ``[0, kappa]``.
Frozen-``k`` pole radii below 1 do not prove stability under switching; a common quadratic Lyapunov
function (CQLF) does. This module searches one and verifies it:

1. **Continuous**: a ``P > 0`` with ``A(k)^T P + P A(k) <= -2 alpha P`` for every ``k`` in
   ``[0, kappa]``. ``A(k) = A0 + k A1`` is affine in ``k`` (proved symbolically), and the condition is
   convex in ``A``, so it holds on the interval iff it holds at the two ends: the check is exact.
   It says ``mu_P(A(k)) <= -alpha`` (``mu_P`` the logarithmic norm in the ``P``-norm), hence
   ``||expm(A(k) t)||_P <= exp(-alpha t)`` for every ``t`` and every frozen ``k``: each interval of the
   sampled observer, whatever its stiffness, contracts the ``P``-norm of the error by
   ``exp(-alpha dt)``. **The continuous certificate therefore covers the sampled observer at every
   dt** (with the decay rate ``alpha``), and every switching sequence.
2. **Sampled, at the config's dt** (tried when 1. finds none): a ``P`` with ``||Phi(k)||_P <= r < 1``
   on the whole interval, ``Phi`` computed by the kernel's own :func:`obsdesign.design.discretize.coefficients`
   on a grid of ``k``; between grid points ``||Phi(k) - Phi(k_j)||_P <= L |k - k_j|`` with the proven
   Lipschitz bound ``L = dt exp(mu* dt) ||A1||_P``, ``mu* = max(mu_P(A(0)), mu_P(A(kappa)))``
   (``dPhi/dk = int_0^dt expm(A (dt - s)) A1 expm(A s) ds`` and ``mu_P`` is convex in ``k``); the grid is
   refined until ``max_j ||Phi(k_j)||_P + L h / 2 < 1``.
3. **Otherwise**, a destabilising switching sequence is searched: a frozen stiffness with an
   unstable pole, or a product of ``Phi(k)`` over a periodic sequence of grid stiffnesses whose
   spectral radius per sample is ``>= 1`` (a lower bound of the joint spectral radius). With one the
   verdict is *not certified (destabilising sequence)*, without *undecided*.

The search for ``P`` (Nelder-Mead on the two free entries of a normalised ``P`` in balanced
coordinates, started from the Lyapunov solutions of the ends) only proposes; the verdict comes from
the verification, so a weak search can only cost a certificate, never give a false one. When the
searched ``P`` fails the verification, the Lyapunov solutions of the ends and of the midpoint are
verified themselves (:func:`lyapunov_candidates`): a certificate one of them proves is never lost.

``certify(design, search=False)`` (what ``simulate``, ``export`` and ``noise`` use, which print only
whether the design is certified) verifies those candidates first and skips the search, and SciPy,
when one holds: the verdict and the method are those of ``certify(design)`` by construction (a
candidate that verifies makes the full certificate continuous too), the decay rate is the
candidate's, a valid but usually smaller one than the searched optimum.

Examples
--------
>>> import obsdesign as od
>>> design = od.design_observer(od.load_preset("table1"))  # rho = 1.02
>>> cert = certify(design)
>>> cert.certified, cert.method, round(cert.decay_rate, 3)  # the dominant pole is -2.439 1/s
(True, 'continuous', 2.439)
>>> cert.max_dt
inf
>>> bad = certify(od.design_observer(od.load_preset("table1").override(rho=0.98)))
>>> bad.verdict, bad.sequence                               # k = 0 held has a pole at +2.44 1/s
('not certified', (0.0,))
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._display import Condition, ResultDisplay
from .._memo import memo

__all__ = ["StabilityCertificate", "certify", "common_lyapunov", "lyapunov_candidates", "log_norm", "p_norm"]

#: Relative safety margin of a verified decay rate (floating point of the 2x2 eigenvalues).
MARGIN = 1e-9
#: Finest grid of the sampled certificate (points on [0, kappa]).
MAX_GRID = 2**14
#: Longest periodic switching sequence tried in the search for a destabilising one.
MAX_SEQUENCE = 6


@dataclass(frozen=True)
class StabilityCertificate(ResultDisplay):
    """The verdict on the switched, sampled observer of one design.

    Attributes
    ----------
    verdict : str
        ``certified``, ``not certified`` (a destabilising sequence was found) or ``undecided``.
    method : str or None
        ``continuous`` (a CQLF of the continuous observer: every dt), ``sampled`` (a CQLF of the
        discretized observer at this dt), or None.
    decay_rate : float or None
        Guaranteed decay rate [1/s] of the error's ``P``-norm under any stiffness sequence.
    radius : float or None
        Guaranteed contraction per sample, ``exp(-decay_rate dt)``.
    P : ndarray or None
        The Lyapunov matrix (state ``(v, f)`` of the reduced observer, SI units).
    dt : float
        Sample time [s] of the sampled verdict.
    max_dt : float or None
        Largest certified sample time: ``inf`` with a continuous certificate, ``dt`` with a sampled
        one, None otherwise.
    sequence : tuple of float or None
        A destabilising periodic stiffness sequence [N/m] (one value: that stiffness held).
    growth : float or None
        Its growth per sample (spectral radius of the product to the power 1 / length); for a held
        stiffness with an unstable continuous pole, ``exp(max Re(lambda) dt)``.
    jsr_lower : float
        The largest growth per sample found over the tried sequences (a lower bound of the joint
        spectral radius of ``{Phi(k)}``).
    grid : int
        Grid points of the sampled verification (0 when not used).
    """

    _title = "Stability certificate of the switched sampled observer"
    verdict: str
    method: str | None
    decay_rate: float | None
    radius: float | None
    P: np.ndarray | None = field(repr=False)
    dt: float
    max_dt: float | None
    sequence: tuple | None
    growth: float | None
    jsr_lower: float
    grid: int

    @property
    def certified(self) -> bool:
        """Whether a common quadratic Lyapunov function was verified."""
        return self.verdict == "certified"

    def condition(self) -> Condition:
        """The certificate as one named verdict of ``obsdesign check``."""
        if self.certified:
            scope = "every dt" if self.method == "continuous" else f"dt = {self.dt:g} s"
            detail = (f"common Lyapunov function on [0, kappa] ({self.method}; {scope}): decay rate "
                      f"{self.decay_rate:.6g} 1/s, contraction {self.radius:.6g} per sample")
        elif self.sequence is not None:
            seq = ", ".join(f"{k:g}" for k in self.sequence)
            detail = (f"destabilising stiffness sequence [{seq}] N/m repeated: growth {self.growth:.6g} per sample")
        else:
            detail = (f"no common Lyapunov function found and no destabilising sequence (joint spectral radius "
                      f">= {self.jsr_lower:.6g}): undecided")
        return Condition("switched sampled observer certified", self.certified, detail)

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        return {"verdict": self.verdict, "method": self.method, "decay_rate": self.decay_rate,
                "radius": self.radius, "P": None if self.P is None else self.P.tolist(), "dt": self.dt,
                "max_dt": None if self.max_dt is None or math.isinf(self.max_dt) else self.max_dt,
                "any_dt": self.max_dt is not None and math.isinf(self.max_dt),
                "sequence": None if self.sequence is None else list(self.sequence), "growth": self.growth,
                "jsr_lower": self.jsr_lower, "grid": self.grid}

    def _rows(self):
        c = self.condition()
        return [("verdict", self.verdict), ("method", self.method or "-"), ("detail", c.detail)]


def _chol(P: np.ndarray) -> np.ndarray:
    return np.linalg.cholesky(P)


def p_norm(M: np.ndarray, P: np.ndarray) -> float:
    """Induced norm ``||M||_P = max ||M x||_P / ||x||_P`` with ``||x||_P = sqrt(x^T P x)``.

    Parameters
    ----------
    M, P : ndarray, shape (n, n)
        The matrix and a symmetric positive definite ``P``.

    >>> p_norm(np.diag([0.5, 2.0]), np.eye(2))
    2.0
    """
    Lc = _chol(P)  # P = Lc Lc^T, ||x||_P = ||Lc^T x||
    T = Lc.T @ M @ np.linalg.inv(Lc.T)
    return float(np.linalg.norm(T, 2))


def log_norm(A: np.ndarray, P: np.ndarray) -> float:
    """Logarithmic norm ``mu_P(A) = max eig(sym(Lc^T A Lc^-T))`` in the ``P``-norm (``P = Lc Lc^T``).

    ``A^T P + P A <= 2 mu P`` exactly when ``mu >= mu_P(A)``, and ``||expm(A t)||_P <= exp(mu_P(A) t)``.

    Parameters
    ----------
    A, P : ndarray, shape (n, n)

    >>> log_norm(np.array([[-1.0, 10.0], [0.0, -1.0]]), np.eye(2))
    4.0
    """
    Lc = _chol(P)
    T = Lc.T @ A @ np.linalg.inv(Lc.T)
    return float(np.linalg.eigvalsh(0.5 * (T + T.T)).max())


def _gen_eig_max(S: np.ndarray, P: np.ndarray) -> float:
    """Largest ``mu`` with ``det(S - mu P) = 0`` for symmetric 2x2 ``S`` and ``P > 0`` (closed form)."""
    (s00, s01), (_, s11) = S.tolist()
    (p00, p01), (_, p11) = P.tolist()
    return _gen_eig_max_of(s00, s01, s11, p00, p01, p11)


def _gen_eig_max_of(s00: float, s01: float, s11: float, p00: float, p01: float, p11: float) -> float:
    """:func:`_gen_eig_max` of the entries (Python floats: the same IEEE operations as NumPy's
    float64 scalars, several times faster; the search calls it thousands of times)."""
    a = p00 * p11 - p01 * p01
    b = -(s00 * p11 + s11 * p00 - 2.0 * s01 * p01)
    c = s00 * s11 - s01 * s01
    if not (a > 0.0 and math.isfinite(a) and math.isfinite(b) and math.isfinite(c)):
        return 1e300  # a degenerate candidate: never the minimiser (finite: the simplex subtracts)
    sq = math.sqrt(max(b * b - 4.0 * a * c, 0.0))
    if b <= 0.0:
        return (-b + sq) / (2.0 * a)
    den = -b - sq  # the stable form of the larger root when b > 0
    return 2.0 * c / den if den != 0.0 else 0.0


def _mu2(A: np.ndarray, P: np.ndarray) -> float:
    """:func:`log_norm` of a 2x2 ``A`` (closed form): the largest ``mu`` of ``A^T P + P A = 2 mu P``."""
    (m00, m01), (m10, m11) = (A.T @ P).tolist()  # S = M + M^T entry by entry: the same sums
    (p00, p01), (_, p11) = P.tolist()
    return 0.5 * _gen_eig_max_of(m00 + m00, m01 + m10, m11 + m11, p00, p01, p11)


def _norm2(F: np.ndarray, P: np.ndarray) -> float:
    """:func:`p_norm` of a 2x2 ``F`` (closed form): ``sqrt`` of the largest ``mu`` of ``F^T P F = mu P``."""
    return math.sqrt(max(_gen_eig_max(F.T @ P @ F, P), 0.0))


def _from_params(x) -> np.ndarray:
    p, lq = x
    return np.array([[1.0, p], [p, p * p + math.exp(max(min(lq, 300.0), -300.0))]])


def _to_params(P: np.ndarray):
    P = P / P[0, 0]
    p = P[0, 1]
    return np.array([p, math.log(max(P[1, 1] - p * p, 1e-300))])


def _lyap(A: np.ndarray) -> np.ndarray:
    from scipy.linalg import solve_continuous_lyapunov

    return solve_continuous_lyapunov(A.T, -np.eye(A.shape[0]))


def _lyap2(A: np.ndarray) -> np.ndarray | None:
    """``P`` with ``A^T P + P A = -I`` for a 2x2 ``A``: the 3x3 linear system of ``p11, p12, p22`` (NumPy)."""
    (a, b), (c, d) = A.tolist()
    M = np.array([[2.0 * a, 2.0 * c, 0.0], [b, a + d, c], [0.0, 2.0 * b, 2.0 * d]])
    try:
        x = np.linalg.solve(M, np.array([-1.0, 0.0, -1.0]))
    except np.linalg.LinAlgError:  # an eigenvalue pair summing to 0: no unique solution
        return None
    return np.array([[x[0], x[1]], [x[1], x[2]]])


def lyapunov_candidates(A_a: np.ndarray, A_b: np.ndarray) -> list[np.ndarray]:
    """The Lyapunov solutions (``A^T P + P A = -I``) of both ends and of the midpoint of a pair.

    They are what :func:`common_lyapunov` verifies when its search fails, and what
    ``certify(design, search=False)`` verifies first (NumPy only: a 3x3 linear system each).

    Parameters
    ----------
    A_a, A_b : ndarray, shape (2, 2)

    Returns
    -------
    list of ndarray
        The solutions that exist and are finite (none needs to be positive definite).

    Examples
    --------
    >>> A = np.array([[-1.0, 2.0], [0.0, -3.0]])
    >>> P = lyapunov_candidates(A, A)[0]
    >>> bool(np.allclose(A.T @ P + P @ A, -np.eye(2), rtol=0, atol=1e-15))
    True
    """
    out = []
    for A in (A_a, A_b, 0.5 * (A_a + A_b)):
        P = _lyap2(np.asarray(A, float))
        if P is not None and np.all(np.isfinite(P)):
            out.append(P)
    return out


def _verified(A_a: np.ndarray, A_b: np.ndarray, P: np.ndarray, scale: float) -> tuple[float, np.ndarray] | None:
    """``(alpha, P)`` when ``P`` verifies ``mu_P(A) < 0`` at both ends with the margin, else None."""
    try:
        mu = max(log_norm(A_a, P), log_norm(A_b, P))  # the verification, by Cholesky and eigvalsh
    except np.linalg.LinAlgError:  # not positive definite
        return None
    if mu < -MARGIN * scale:
        return -mu * (1.0 - MARGIN), P
    return None


def _candidate(A_a: np.ndarray, A_b: np.ndarray, scale: float) -> tuple[float, np.ndarray] | None:
    for P in lyapunov_candidates(A_a, A_b):
        found = _verified(A_a, A_b, P, scale)
        if found is not None:
            return found
    return None


def _search(objective, starts) -> np.ndarray:
    """Minimise ``objective(P)`` over normalised 2x2 ``P > 0`` from the given starting matrices."""
    from scipy.optimize import minimize

    best_x, best_f = None, math.inf
    for P0 in starts:
        try:
            x0 = _to_params(0.5 * (P0 + P0.T))
        except (ValueError, ZeroDivisionError, FloatingPointError):
            continue
        if not np.all(np.isfinite(x0)):
            continue
        res = minimize(lambda x: objective(_from_params(x)), x0, method="Nelder-Mead",
                       options={"xatol": 1e-9, "fatol": 1e-13, "maxiter": 600})
        if res.fun < best_f:
            best_x, best_f = res.x, float(res.fun)
    return _from_params(best_x) if best_x is not None else np.eye(2)


def _positive_definite(P) -> bool:
    """A finite, symmetric, positive definite 2x2 matrix (what a stored search result must be)."""
    P = np.asarray(P, dtype=float)
    ok = P.shape == (2, 2) and bool(np.all(np.isfinite(P))) and P[0, 1] == P[1, 0]
    return ok and P[0, 0] > 0.0 and P[0, 0] * P[1, 1] - P[0, 1] ** 2 > 0.0  # Sylvester's criterion


def _ends(d):
    A_lo, A_hi = d.matrices(0.0)[0], d.matrices(d.kappa)[0]
    # balanced coordinates (as the kernel's discretization): x = D x', D = diag(1, c)
    c = math.sqrt(abs(A_lo[1, 0] / A_lo[0, 1])) if A_lo[0, 1] != 0.0 and A_lo[1, 0] != 0.0 else 1.0
    D = np.diag([1.0, c])
    Di = np.diag([1.0, 1.0 / c])
    return d, Di @ A_lo @ D, Di @ A_hi @ D, D, Di


def certify(design, *, search: bool = True) -> StabilityCertificate:
    """Certify (or refute) stability of the switched, exactly discretized observer of a design.

    Parameters
    ----------
    design : ObserverDesign
        The designed observer (:func:`obsdesign.design_observer`); its ``dt`` is the sample time of
        the sampled verdict.
    search : bool
        False: accept the first Lyapunov solution of the ends or the midpoint that verifies, without
        searching the best ``P`` (no SciPy). The verdict and the method are the same as with True;
        the decay rate (and ``P``) may be weaker. For a caller that needs the verdict only.

    Returns
    -------
    StabilityCertificate
        See the module notes for what each verdict proves.

    Examples
    --------
    >>> import obsdesign as od
    >>> vcm = od.design_observer(od.load_preset("vcm"))
    >>> certify(vcm).condition().holds
    True
    >>> full, quick = certify(vcm), certify(vcm, search=False)
    >>> (quick.verdict, quick.method) == (full.verdict, full.method), quick.decay_rate <= full.decay_rate
    (True, True)
    """
    if not all(hasattr(design, a) for a in ("matrices", "kappa", "dt")):
        raise TypeError(f"design: expected an ObserverDesign, found {type(design).__name__}")
    d, B_lo, B_hi, D, Di = _ends(design)
    dt = d.dt
    frozen_stable = all(np.linalg.eigvals(B).real.max() < 0.0 for B in (B_lo, B_hi))
    # 1. continuous CQLF (exact at the two ends)
    if frozen_stable:
        found = common_lyapunov(B_lo, B_hi, search=search)
        if found is not None:
            alpha, P = found
            return _certified("continuous", alpha, Di.T @ P @ Di, dt, math.inf, 0)
    # 2. sampled CQLF at dt, on a refined grid with the Lipschitz bound
    from .discretize import coefficient_matrices

    def phi(k):
        A = B_lo + (k / d.kappa) * (B_hi - B_lo) if d.kappa > 0 else B_lo
        return coefficient_matrices(A, dt)[0]

    A1 = (B_hi - B_lo) / d.kappa if d.kappa > 0 else np.zeros((2, 2))
    n = 64
    grid = np.linspace(0.0, d.kappa, n + 1)
    Phis = [phi(k) for k in grid]
    if max(np.abs(np.linalg.eigvals(F)).max() for F in Phis) >= 1.0:  # a frozen stiffness is unstable
        return _refute(d, B_lo, B_hi, phi, dt)
    def search_P():
        starts = [np.eye(2), *(_dlyap(Phis[i]) for i in (0, n // 2, n))]
        coarse = Phis[:: n // 16]
        return _search(lambda P: max(_norm2(F, P) for F in coarse), starts).tolist()

    P = np.array(memo("dcqlf", (B_lo, B_hi, dt), search_P, valid=_positive_definite))  # a proposal; verified on the grid below
    while True:
        r = max(p_norm(F, P) for F in Phis)
        if r >= 1.0:
            break
        mu_star = max(log_norm(B_lo, P), log_norm(B_hi, P))
        lip = dt * math.exp(mu_star * dt) * p_norm(A1, P) if d.kappa > 0 else 0.0
        h = d.kappa / n
        bound = r + lip * h / 2.0
        if bound < 1.0 - MARGIN:
            return _certified("sampled", -math.log(bound) / dt, Di.T @ P @ Di, dt, dt, n + 1)
        if n >= MAX_GRID:
            break
        n *= 2
        grid = np.linspace(0.0, d.kappa, n + 1)
        Phis = [phi(k) for k in grid]
    # 3. a destabilising sequence
    return _refute(d, B_lo, B_hi, phi, dt)


def common_lyapunov(A_a: np.ndarray, A_b: np.ndarray, *, search: bool = True) -> tuple[float, np.ndarray] | None:
    """A verified common quadratic Lyapunov function of two 2x2 matrices (and of their convex hull).

    Parameters
    ----------
    A_a, A_b : ndarray, shape (2, 2)
        The ends of the interval of matrices (best in balanced coordinates).
    search : bool
        True: the best ``P`` of the search (Nelder-Mead), else a verified :func:`lyapunov_candidates`
        solution. False: a verified candidate without the search when one exists (no SciPy);
        None in exactly the same cases as True.

    Returns
    -------
    (float, ndarray) or None
        ``(alpha, P)`` with ``A^T P + P A <= -2 alpha P`` verified for both (``alpha > 0``), or None.

    Examples
    --------
    >>> alpha, P = common_lyapunov(np.array([[-1.0, 0.0], [0.0, -2.0]]), np.array([[-3.0, 1.0], [0.0, -1.0]]))
    >>> round(alpha, 6)   # the slowest pole of both: no CQLF can give more
    1.0
    """
    A_a, A_b = np.asarray(A_a, float), np.asarray(A_b, float)
    if max(np.linalg.eigvals(A_a).real.max(), np.linalg.eigvals(A_b).real.max()) >= 0.0:
        return None
    scale = max(np.abs(np.linalg.eigvals(A_a)).max(), np.abs(np.linalg.eigvals(A_b)).max(), 1e-300)
    if not search:
        found = _candidate(A_a, A_b, scale)
        if found is not None:
            return found
    def search_P():
        starts = [_lyap(A_a), _lyap(A_b), _lyap(0.5 * (A_a + A_b)), np.eye(2)]
        return _search(lambda P: max(_mu2(A_a, P), _mu2(A_b, P)), starts).tolist()

    # the search only proposes (kept on disk, obsdesign._memo); the verification below decides, every time
    P = np.array(memo("cqlf", (A_a, A_b), search_P, valid=_positive_definite))
    found = _verified(A_a, A_b, P, scale)  # the verification, by Cholesky and eigvalsh
    return found if found is not None else _candidate(A_a, A_b, scale)  # a weak search never loses a candidate


def _dlyap(F: np.ndarray):
    from scipy.linalg import solve_discrete_lyapunov

    if np.abs(np.linalg.eigvals(F)).max() >= 1.0:
        return None
    return solve_discrete_lyapunov(F.T, np.eye(2))


def _certified(method, alpha, P, dt, max_dt, grid) -> StabilityCertificate:
    return StabilityCertificate(verdict="certified", method=method, decay_rate=float(alpha),
                                radius=float(math.exp(-alpha * dt)), P=P, dt=dt, max_dt=max_dt, sequence=None,
                                growth=None, jsr_lower=float(math.exp(-alpha * dt)), grid=grid)


def _refute(d, B_lo, B_hi, phi, dt) -> StabilityCertificate:
    import itertools

    ks = np.linspace(0.0, d.kappa, 9)
    best_seq, best_growth = None, 0.0
    for k in ks:  # a held stiffness with an unstable pole
        A = B_lo + (k / d.kappa) * (B_hi - B_lo) if d.kappa > 0 else B_lo
        growth = math.exp(float(np.linalg.eigvals(A).real.max()) * dt)
        if growth > best_growth:
            best_seq, best_growth = (float(k),), growth
    if best_growth < 1.0:
        mats = {float(k): phi(k) for k in ks[:: 2]}  # 0, kappa/4, ..., kappa
        for length in range(2, MAX_SEQUENCE + 1):
            for seq in itertools.product(mats, repeat=length):
                if seq[0] != min(seq):  # rotations have the same spectral radius
                    continue
                M = np.eye(2)
                for k in seq:
                    M = mats[k] @ M
                growth = float(np.abs(np.linalg.eigvals(M)).max()) ** (1.0 / length)
                if growth > best_growth:
                    best_seq, best_growth = seq, growth
    refuted = best_growth >= 1.0
    return StabilityCertificate(verdict="not certified" if refuted else "undecided", method=None, decay_rate=None,
                                radius=None, P=None, dt=dt, max_dt=None, sequence=best_seq if refuted else None,
                                growth=best_growth if refuted else None, jsr_lower=best_growth, grid=0)

