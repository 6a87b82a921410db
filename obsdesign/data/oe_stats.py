"""Statistics of the output-error fit (:mod:`obsdesign.data.output_error`): the start scan of ``s``, the
grouped finite-difference Jacobian, the moments with the windows' initial states projected out, the
sensitivity to the held parameters, and the near-null directions.

Examples
--------
>>> import numpy as np
>>> _null_loadings(np.array([[1.0, 1.0], [1.0, 1.0 + 1e-12]])).tolist()   # two columns that are one
[True, True]
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["NEAR_NULL", "DIFF_STEP", "segment_covariance"]

#: A direction of the scaled Jacobian whose singular value is below this fraction of the largest is null.
NEAR_NULL = 1e-4
#: Relative finite-difference step of the Jacobian (the branch switches make a much smaller one noisy).
DIFF_STEP = 1e-4


def _scan_s(prob, g: int, w: int) -> float:
    """The ``s`` of least cost on a log grid (the others at their start), the start of the fit."""
    low, high = prob.spec("s")[1:3]
    best, best_cost = prob.values["s"], math.inf
    for s in np.geomspace(low * 1.01, high / 1.01, 15):
        prob.values["s"] = float(s)
        theta = np.array([prob.to_theta(n, prob.values[n]) for n in prob.names] + [0.0] * (2 * w))
        cost = float(np.sum(prob.residual(theta) ** 2))
        if cost < best_cost:
            best, best_cost = float(s), cost
    return best


def _grouped_jacobian(fun, last: dict, g: int, w: int, win: np.ndarray):
    """Forward-difference Jacobian (dense) in ``g + 2`` evaluations: each refined parameter alone, then every
    window's initial position at once and every window's initial velocity at once (a row depends only on
    its own window's), with steps of :data:`DIFF_STEP` relative (at least ``DIFF_STEP``); ``last`` holds the
    last evaluation of ``fun``."""
    rows = np.arange(win.size)

    def jac(theta):
        same = "x" in last and np.array_equal(last["x"], theta)
        f0 = last["f"] if same else fun(theta)  # least_squares asks for J where it last evaluated
        J = np.zeros((f0.size, theta.size))
        for j in range(g):
            h = DIFF_STEP * max(1.0, abs(theta[j]))
            step = theta.copy()
            step[j] += h
            J[:, j] = (fun(step) - f0) / h
        for block in (g, g + w):
            h = DIFF_STEP * max(1.0, float(np.max(np.abs(theta[block:block + w]))))
            step = theta.copy()
            step[block:block + w] += h
            J[rows, block + win] = (fun(step) - f0) / h
        return J

    return jac


#: Held parameters whose standard error the static fit gives: their uncertainty is carried into the intervals.
_HELD_STD = {"m": "m_std", "sigma": "sigma_std", "Cf": "Cf_std", "offset": "offset_std"}


def _held_sensitivity(prob, theta: np.ndarray, J: np.ndarray, A: np.ndarray, g: int, w: int):
    """Variance added to each refined parameter by the held ones: ``S diag(std^2) S'`` with
    ``S = -A^-1 sum_w Jp_w' Jh_w`` (implicit function theorem at the optimum), ``Jh`` the forward-difference
    columns of the held parameters with the static fit's standard errors, nuisance projected out per window."""
    held = [n for n in _HELD_STD if n not in prob.names and getattr(prob.ident, _HELD_STD[n]) > 0]
    if not held:
        return np.zeros(g)
    f0 = prob.residual(theta)
    Jh = np.empty((f0.size, len(held)))
    for j, name in enumerate(held):
        value = prob.values[name]
        h = DIFF_STEP * max(abs(value), 1e-12)
        prob.values = prob.assign(dict(prob.values), {name: value + h})
        Jh[:, j] = (prob.residual(theta) - f0) / h
        prob.values = prob.assign(dict(prob.values), {name: value})
    C = np.zeros((g, len(held)))
    pos = 0
    for i, n in enumerate(prob.lengths):
        block = J[pos:pos + n]
        Jn = block[:, [g + i, g + w + i]]
        proj = np.linalg.lstsq(Jn, np.column_stack([block[:, :g], Jh[pos:pos + n]]), rcond=None)[0]
        Jg = block[:, :g] - Jn @ proj[:, :g]
        C += Jg.T @ (Jh[pos:pos + n] - Jn @ proj[:, g:])
        pos += n
    S = -_pinv(A) @ C
    std = np.array([held_std(prob.ident, n) for n in held])
    return np.sum((S * std) ** 2, axis=1)


def held_std(ident, name: str) -> float:
    """The standard uncertainty of a held parameter: its standard error, or the larger side of its 95 %
    interval over 1.96 where that is wider (``identify`` widens its intervals by the errors-in-variables, the
    model-error and the timing shifts, which the standard error does not carry: on the shipped example log the
    mass's interval is 6 times its standard error, and ``s`` refined with the standard errors alone missed
    the truth, 16288 [14584, 18190] for 2e4 1/m).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> round(held_std(SimpleNamespace(m=2.0, m_std=0.01, intervals={"m": (1.9, 2.0392)}), "m"), 6)   # 0.1 / 1.96
    0.05102
    >>> held_std(SimpleNamespace(m=2.0, m_std=0.1, intervals={}), "m")
    0.1
    """
    std = float(getattr(ident, _HELD_STD[name]))
    if name in ident.intervals:
        lo, hi = ident.intervals[name]
        value = float(getattr(ident, name))
        std = max(std, max(value - lo, hi - value) / 1.96)
    return std


def _moments(prob, J, r, g: int, w: int):
    """``A``, ``B`` of the refined parameters (nuisance projected out per window), the RSS, the condition."""
    A = np.zeros((g, g))
    B = np.zeros((g, g))
    pos = 0
    for i, n in enumerate(prob.lengths):
        block = J[pos:pos + n]
        Jg, Jn = block[:, :g], block[:, [g + i, g + w + i]]
        Jp = Jg - Jn @ np.linalg.lstsq(Jn, Jg, rcond=None)[0]
        A += Jp.T @ Jp
        score = Jp.T @ r[pos:pos + n]
        B += np.outer(score, score)
        pos += n
    d = np.sqrt(np.maximum(np.diag(A), 1e-300))
    sv = np.linalg.svd(A / np.outer(d, d), compute_uv=False)
    cond = float(math.sqrt(sv[0] / sv[-1])) if sv[-1] > 0 else math.inf
    return A, B, float(r @ r), cond


def _pinv(A: np.ndarray) -> np.ndarray:
    d = np.sqrt(np.maximum(np.diag(A), 1e-300))
    return np.linalg.pinv(A / np.outer(d, d), rcond=NEAR_NULL**2) / np.outer(d, d)


def _null_loadings(A: np.ndarray) -> np.ndarray:
    """Per parameter: whether it loads (|component| > 0.3) on a near-null direction of the scaled Jacobian."""
    d = np.sqrt(np.maximum(np.diag(A), 1e-300))
    if not np.all(np.diag(A) > 0):
        return ~(np.diag(A) > 0)
    u, sv, _ = np.linalg.svd(A / np.outer(d, d))
    small = np.sqrt(sv) < NEAR_NULL * math.sqrt(sv[0])
    return np.any(np.abs(u[:, small]) > 0.3, axis=1) if np.any(small) else np.zeros(A.shape[0], bool)


def segment_covariance(names, r, mom):
    """Covariance of the segment fit's coordinates (:mod:`obsdesign.data.oe_segments`), the segments' initial
    states projected out (Schur complement): per parameter the larger of the white-noise and the
    segment-clustered (sandwich) variance, and the white-noise one.

    Parameters
    ----------
    names : sequence of str
        The fitted parameters (their number sets the degrees of freedom).
    r : ndarray
        Weighted residuals, segments x samples.
    mom : tuple
        ``(A, B, C, Jg, Jn)``: the moments of the Jacobian and the Jacobian itself in the global parameters
        (``Jg``, segments x samples x parameters) and in each segment's nuisances (``Jn``, x 3).

    Returns
    -------
    var, white : ndarray
        The variances used for the intervals and the white-noise ones (tests/test_refine_recovery.py checks
        both against the full least-squares problem).
    """
    A, B, C, Jg, Jn = mom
    Cinv = np.linalg.pinv(C)
    Jp = Jg - np.einsum("sln,snm,sgm->slg", Jn, Cinv, B)
    Ared = np.einsum("slg,slh->gh", Jp, Jp)
    d = np.sqrt(np.maximum(np.diag(Ared), 1e-300))
    Ainv = np.linalg.pinv(Ared / np.outer(d, d), rcond=1e-10) / np.outer(d, d)
    n_seg = r.shape[0]
    dof = max(r.size - len(names) - 3 * n_seg, 1)
    white = float(np.sum(r * r)) / dof * Ainv
    score = np.einsum("slg,sl->sg", Jp, r)
    cluster = n_seg / max(n_seg - 1, 1) * Ainv @ (score.T @ score) @ Ainv
    return np.maximum(np.diag(white), np.diag(cluster)), np.diag(white)

