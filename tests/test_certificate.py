"""The stability certificate of the switched sampled observer (obsdesign.design.certificate).

* soundness: every certified design contracts the P-norm of the error by the certified factor at
  every sample of 1,000 random stiffness sequences of 10,000 samples (the kernel's own Phi(k));
* the continuous verdict against the independent closed-form criterion of Shorten and Narendra
  (a pair of stable 2x2 matrices has a common quadratic Lyapunov function iff A1 A2 and A1 A2^-1
  have no negative real eigenvalue): never certified where it says none exists, found where it
  says one exists with margin;
* the paper's pair rho 0.98 / 1.02, a destabilising sequence, and the verdict in ``check``;
* the verdict without the search (``search=False``, what ``simulate`` and ``export`` use) is the
  full one, and the closed-form objective gives the bits of its NumPy-scalar form (the same search).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import obsdesign as od
from obsdesign.design import certificate as certificate_module
from obsdesign.design.certificate import certify, common_lyapunov, log_norm, lyapunov_candidates, p_norm
from obsdesign.design.discretize import coefficient_matrices

TABLE1 = od.load_preset("table1")
VCM = od.load_preset("vcm")


class _Pair:
    """A design-like pair of 2x2 ends, A(k) = A0 + k/kappa (A1 - A0) (the interface certify reads)."""

    def __init__(self, A0, A1, dt, kappa=1.0):
        self.A0, self.A1, self.dt, self.kappa = np.asarray(A0, float), np.asarray(A1, float), dt, kappa

    def matrices(self, k):
        return self.A0 + k / self.kappa * (self.A1 - self.A0), None, None


def _spirals(w):
    """Two stable spirals turned against each other: no CQLF for w = 3 (Shorten-Narendra)."""
    return np.array([[-1.0, 1.0], [-w * w, -1.0]]), np.array([[-1.0, w * w], [-1.0, -1.0]])


def _random_switching_contracts(cfg, sequences=1000, samples=10_000, grid=513, seed=0):
    d = od.design_observer(cfg) if isinstance(cfg, od.Config) else cfg
    cert = certify(d)
    assert cert.certified
    ks = np.linspace(0.0, d.kappa, grid)
    Phis = np.array([coefficient_matrices(d.matrices(k)[0], d.dt)[0] for k in ks])
    Lc = np.linalg.cholesky(cert.P)  # ||x||_P = ||Lc^T x||
    rng = np.random.default_rng(seed)
    x = rng.standard_normal((sequences, 2)) @ np.diag([1.0, 1e3])  # (v, f) of different scales
    worst = 0.0
    norm = np.linalg.norm(x @ Lc, axis=1)
    for _ in range(samples):
        x = np.einsum("nij,nj->ni", Phis[rng.integers(0, grid, sequences)], x)
        new = np.linalg.norm(x @ Lc, axis=1)
        worst = max(worst, float(np.max(new / norm)))
        norm = new
        x /= norm[:, None]  # keep the numbers in range: only ratios matter
        norm = np.ones(sequences)
    return cert, worst


@pytest.mark.slow
@pytest.mark.parametrize("cfg", [TABLE1, VCM, VCM.override(rho=1.2, kappa=2e5), TABLE1.override(dt=2e-3)],
                         ids=["table1", "vcm", "vcm-stiff", "table1-2ms"])
def test_certified_designs_contract_under_random_switching(cfg):
    cert, worst = _random_switching_contracts(cfg)
    assert worst <= cert.radius * (1 + 1e-9)
    assert cert.radius < 1.0


def test_a_sampled_certificate_where_no_continuous_one_exists():
    A, B = _spirals(3.0)
    assert not _shorten_narendra(A, B)[0]
    cert, worst = _random_switching_contracts(_Pair(A, B, 1.0), sequences=1000, samples=2000)
    assert cert.method == "sampled" and cert.max_dt == 1.0 and cert.grid > 64
    assert worst <= cert.radius * (1 + 1e-9) < 1.0


def test_a_destabilising_sequence_is_reported_and_grows():
    from scipy.linalg import expm

    A, B = _spirals(3.0)
    cert = certify(_Pair(A, B, 0.3))
    assert cert.verdict == "not certified" and not cert.condition().holds
    M = np.eye(2)
    for k in cert.sequence:  # an independent product of the exact transitions
        M = expm((A + k * (B - A)) * 0.3) @ M
    growth = max(abs(np.linalg.eigvals(M))) ** (1 / len(cert.sequence))
    assert growth == pytest.approx(cert.growth, rel=1e-9) and growth > 1.5
    # frozen, each end is stable: only switching destabilises
    assert max(abs(np.linalg.eigvals(expm(A * 0.3)))) < 1 and max(abs(np.linalg.eigvals(expm(B * 0.3)))) < 1


def test_undecided_is_said_honestly():
    A, B = _spirals(2.0)
    cert = certify(_Pair(A, B, 0.1))
    assert cert.verdict == "undecided" and cert.sequence is None and cert.jsr_lower < 1.0
    assert "undecided" in cert.condition().detail


def test_the_paper_pair():
    good, bad = (certify(od.design_observer(TABLE1.override(rho=r))) for r in (1.02, 0.98))
    assert good.certified and good.method == "continuous" and math.isinf(good.max_dt)
    # the guaranteed rate cannot beat the slowest frozen pole, -sqrt(kappa/m)(rho - 1) = -2.4388 1/s
    slowest = math.sqrt(8000 / 0.538) * 0.02
    assert good.decay_rate == pytest.approx(slowest, rel=1e-6)
    assert bad.verdict == "not certified" and bad.sequence == (0.0,)
    assert bad.growth == pytest.approx(math.exp(slowest * 1e-4), rel=1e-9)  # +2.44 1/s held at k = 0


def _shorten_narendra(A1, A2) -> tuple[bool, float]:
    """CQLF exists iff no eigenvalue of A1 A2 or A1 A2^-1 is real and negative; also the margin."""
    eig = np.concatenate([np.linalg.eigvals(A1 @ A2), np.linalg.eigvals(A1 @ np.linalg.inv(A2))])
    neg = [e for e in eig if abs(e.imag) <= 1e-12 * abs(e) and e.real < 0]
    if neg:
        return False, 0.0
    # distance of the eigenvalues from the negative real axis, relative to their size
    margin = min(abs(np.angle(e)) if e.real < 0 else math.pi for e in eig)
    margin = min(margin, min(math.pi - abs(np.angle(e)) for e in eig))
    return True, margin


def _hurwitz(rng):
    while True:
        A = rng.standard_normal((2, 2)) * 3
        if np.linalg.eigvals(A).real.max() < -0.05:
            return A


@pytest.mark.slow
def test_continuous_verdict_agrees_with_shorten_narendra():
    rng = np.random.default_rng(7)
    exists = none = 0
    for _ in range(400):
        A1, A2 = _hurwitz(rng), _hurwitz(rng)
        truth, margin = _shorten_narendra(A1, A2)
        found = common_lyapunov(A1, A2)
        if not truth:
            none += 1
            assert found is None  # soundness: never a certificate where none can exist
        elif margin > 0.05:
            exists += 1
            assert found is not None
            alpha, P = found
            assert max(log_norm(A1, P), log_norm(A2, P)) <= -alpha
    assert exists > 50 and none > 20  # both sides exercised


def test_norms_against_their_definitions():
    rng = np.random.default_rng(3)
    for _ in range(20):
        M = rng.standard_normal((2, 2))
        Q = rng.standard_normal((2, 2))
        P = Q @ Q.T + 0.1 * np.eye(2)
        xs = rng.standard_normal((20000, 2))
        ratios = np.sqrt(np.einsum("ni,ij,nj->n", xs @ M.T, P, xs @ M.T) / np.einsum("ni,ij,nj->n", xs, P, xs))
        assert p_norm(M, P) >= ratios.max() and p_norm(M, P) == pytest.approx(ratios.max(), rel=1e-3)
        # d/dt ||expm(M t) x||_P at t = 0 is at most mu_P(M) ||x||_P
        from scipy.linalg import expm
        h = 1e-7
        assert p_norm(expm(M * h), P) <= 1 + log_norm(M, P) * h + 1e-12


def test_check_carries_the_certificate_as_its_own_verdict():
    rep = od.check_stability(TABLE1)
    names = [c.name for c in rep.conditions]
    assert names[-1] == "switched sampled observer certified" and rep.conditions[-1].holds
    assert rep.to_dict()["certificate"]["any_dt"] is True
    rep = od.check_stability(TABLE1.override(rho=0.98))
    assert "switched sampled observer certified" in rep.failed()


def test_rho_range_is_where_the_slowest_frozen_pole_is_stable():
    lo, hi = od.design.certified_rho_range(VCM, np.linspace(0.9, 1.1, 21))
    assert lo == pytest.approx(1.01) and hi == pytest.approx(1.1)


def _mu2_numpy_scalars(A, P):
    """The closed form as first written, on NumPy float64 scalars (the reference of the fast one)."""
    S = A.T @ P
    S = S + S.T
    a = P[0, 0] * P[1, 1] - P[0, 1] * P[0, 1]
    b = -(S[0, 0] * P[1, 1] + S[1, 1] * P[0, 0] - 2.0 * S[0, 1] * P[0, 1])
    c = S[0, 0] * S[1, 1] - S[0, 1] * S[0, 1]
    if not (a > 0.0 and math.isfinite(a) and math.isfinite(b) and math.isfinite(c)):
        return 0.5 * 1e300
    sq = math.sqrt(max(b * b - 4.0 * a * c, 0.0))
    if b <= 0.0:
        return 0.5 * ((-b + sq) / (2.0 * a))
    den = -b - sq
    return 0.5 * (2.0 * c / den if den != 0.0 else 0.0)


def test_fast_objective_gives_the_bits_of_numpy_scalars_and_the_same_search(monkeypatch):
    certificate = certificate_module
    rng = np.random.default_rng(11)
    for _ in range(2000):
        A = rng.standard_normal((2, 2)) * 10.0 ** rng.uniform(-3, 5)
        p, lq = rng.standard_normal(2) * 3
        P = np.array([[1.0, p], [p, p * p + math.exp(lq)]])
        assert certificate._mu2(A, P) == _mu2_numpy_scalars(A, P)
    designs = [od.design_observer(c) for c in (VCM, TABLE1, VCM.override(rho=2.0), TABLE1.override(rho=1.5))]
    fast = [certify(d).to_dict() for d in designs]
    monkeypatch.setattr(certificate, "_mu2", _mu2_numpy_scalars)
    assert [certify(d).to_dict() for d in designs] == fast  # the same Nelder-Mead path, bit for bit


def test_lyapunov_candidates_solve_the_equation():
    from scipy.linalg import solve_continuous_lyapunov

    rng = np.random.default_rng(5)
    for _ in range(50):
        A1, A2 = _hurwitz(rng), _hurwitz(rng)
        for A, P in zip((A1, A2, 0.5 * (A1 + A2)), lyapunov_candidates(A1, A2), strict=True):
            ref = solve_continuous_lyapunov(A.T, -np.eye(2))
            assert np.allclose(P, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())


def _generalized_max(A, P):
    """Largest eigenvalue of (A^T P + P A, P), by SciPy's symmetric generalized solver: 2 mu_P(A)."""
    from scipy.linalg import eigh

    return float(eigh(A.T @ P + P @ A, P, eigvals_only=True).max())


@pytest.mark.slow  # 60 designs certified twice, the full search each time (8 s)
def test_verdict_without_search_is_the_full_verdict():
    """search=False (simulate, export, noise) gives the verdict and method of the full certificate;
    its decay rate is proved by its own P (checked with SciPy's generalized eigensolver) and never
    above the searched one."""
    rng = np.random.default_rng(3)
    designs = [od.design_observer(base.override(rho=float(rho), dt=dt))
               for base in (VCM, TABLE1) for rho in (0.98, 1.02, 1.3, 3.0, 12.0) for dt in (1e-4, 2e-3)]
    designs += [_Pair(*_spirals(w), dt) for w in (1.2, 3.0) for dt in (0.01, 0.3)]
    designs += [_Pair(_hurwitz(rng), _hurwitz(rng), 0.05) for _ in range(40)]
    quick_hits = 0
    for d in designs:
        full, quick = certify(d), certify(d, search=False)
        assert (quick.verdict, quick.method, quick.sequence) == (full.verdict, full.method, full.sequence)
        if quick.method == "continuous":
            _, B_lo, B_hi, D, _ = certificate_module._ends(d)
            Pb = D.T @ quick.P @ D  # back to the balanced coordinates it was verified in
            assert max(_generalized_max(B, Pb) for B in (B_lo, B_hi)) / 2 <= -quick.decay_rate * (1 - 1e-7)
            assert quick.decay_rate <= full.decay_rate * (1 + 1e-12)
            quick_hits += quick.decay_rate < full.decay_rate  # the search was skipped
    assert quick_hits >= 10  # the fast path is exercised, not only the fallback
