"""The reference side of the feed-forward modes: reference velocity and look-ahead/build-up weight.

The feed-forward modes of :data:`obsdesign.compensation.COMPENSATION_MODES` compensate the
friction model of the *reference* velocity, not of the noisy estimate. Both inputs of that term
come from the reference trajectory, which on an axis is the trajectory generator's (it knows the
path ahead); :func:`reference_feedforward` is the one computation of them: the simulator feeds its
arrays to the kernel sample by sample and the exported controller takes the same two numbers as
inputs of its step (``step(x_ref, x_meas, v_ref, w_ff)``), so simulation and export agree to the bit.

* ``v_ref``: the central difference ``(x_ref[n+1] - x_ref[n-1]) / (2 dt)`` (one-sided at the ends,
  :func:`numpy.gradient`), with values below ``1e-9`` of its peak set to exactly 0 (a held reference);
* ``w_ff`` in [-1, 1]: ``p min(look-ahead, build-up)``. ``p`` (with ``presliding = s``, the
  default of the feed-forward modes: ``[compensation] ff_presliding``) is the friction model's own
  pre-sliding curve along the reference, ``p = sign(v_ref) Fc(x_ref) / Cf`` with ``Fc / Cf`` of
  eq:2:3:1-4 and its memory of the last reversal (:func:`obsdesign.friction.presliding.coulomb_along`):
  after a reversal the model's Coulomb force turns over ``1/s`` of reference travel, as the paper's
  plant does, instead of switching at once (``p`` runs from -1 to 1; 1 without pre-sliding). The
  ramps are the rule ``min(look-ahead, build-up)`` of the drives' friction tables. Look-ahead: over the ``lookahead`` samples before a reversal of ``v_ref`` (the next
  non-zero direction is the opposite one) ``w = (b - n) / lookahead`` with ``b`` the first sample
  that no longer moves in the old direction, so the term ramps through zero at the reversal instead
  of jumping.
  Build-up: after a start or a reversal at sample ``a``, ``w = |x_ref[n] - x_ref[a-1]| / buildup``
  until it reaches 1.

Examples
--------
>>> import numpy as np
>>> t = np.arange(400) * 0.01
>>> x = np.sin(np.pi * t + 0.1)            # reversals every 1 s (100 samples)
>>> v, w = reference_feedforward(x, 0.01, lookahead=10)
>>> round(float(v[0]), 2), float(w.min()), float(w[20]), w[44:49].tolist()   # reversal at sample 47
(3.12, 0.1, 1.0, [0.3, 0.2, 0.1, 1.0, 1.0])
>>> v, w = reference_feedforward(x, 0.01, presliding=20.0)   # 1/s = 5 cm of pre-sliding travel
>>> z = 20.0 * (x[52] - x[47])                                 # eq:2:3:1, branch from f_r = +1 at sample 47
>>> float(w[46]), float(w[47]), bool(np.isclose(w[52], -(2 * z * (1 - np.log(-z)) + 1))), float(w[60])
(1.0, -1.0, True, 1.0)
>>> reference_feedforward(x, 0.01, lookahead=150)
Traceback (most recent call last):
...
ValueError: compensation.lookahead: expected at most 100 samples (the reference's shortest half period between reversals, 1 s), found 150
"""

from __future__ import annotations

import numpy as np

from .._validate import NONNEGATIVE, POSITIVE, check_integer

__all__ = ["reference_feedforward", "ZERO_VELOCITY"]

#: A reference velocity below this fraction of the peak is a standstill (exactly 0).
ZERO_VELOCITY = 1e-9


def _segments(d: np.ndarray) -> list[tuple[int, int, int]]:
    """Runs ``(start, end, direction)`` of constant ``d`` (end exclusive)."""
    cuts = np.flatnonzero(np.diff(d)) + 1
    bounds = [0, *cuts.tolist(), len(d)]
    return [(a, b, int(d[a])) for a, b in zip(bounds[:-1], bounds[1:])]


def reference_feedforward(x_ref, dt: float, *, lookahead: int = 0, buildup: float = 0.0,
                          presliding: float | None = None):
    """Reference velocity and feed-forward weight of every sample of a reference.

    Parameters
    ----------
    x_ref : array_like
        Reference position [m] per sample.
    dt : float
        Sample time [s].
    lookahead : int
        Ramp length [samples] before a reversal (0: none); at most the shortest time between two
        reversals of the reference (its half period).
    buildup : float
        Build-up distance [m] after a start or a reversal (0: none).
    presliding : float, optional
        Pre-sliding stiffness ``s`` [1/m] of the model whose curve ``w_ff`` follows (``None``: none,
        the model switches at a reversal).

    Returns
    -------
    v_ref, w_ff : ndarray
        Reference velocity [m/s] and weight in [-1, 1] (in [0, 1] without ``presliding``).

    Raises
    ------
    ValueError
        ``lookahead`` longer than the reference's half period, or a bad argument.
    """
    x = np.asarray(x_ref, dtype=np.float64)
    lookahead = check_integer("compensation.lookahead", lookahead, minimum=0)
    buildup = NONNEGATIVE.check("compensation.buildup", buildup)
    if presliding is not None:
        presliding = POSITIVE.check("friction.s", presliding)
    if x.ndim != 1:
        raise ValueError(f"x_ref: expected a 1-d array, found shape {x.shape}")
    n = len(x)
    if n < 2:
        return np.zeros(n), np.ones(n)
    v = np.gradient(x, dt)
    peak = float(np.max(np.abs(v)))
    v[np.abs(v) <= ZERO_VELOCITY * peak] = 0.0
    d = np.sign(v).astype(np.int64)
    w = np.ones(n)
    moving = [seg for seg in _segments(d) if seg[2] != 0]
    reversal_after = [i + 1 < len(moving) and moving[i + 1][2] == -seg[2] for i, seg in enumerate(moving)]
    if lookahead > 0:
        half = [b - a for i, (a, b, _) in enumerate(moving) if reversal_after[i] and i > 0 and reversal_after[i - 1]]
        if half and lookahead > min(half):
            raise ValueError(f"compensation.lookahead: expected at most {min(half)} samples (the reference's "
                             f"shortest half period between reversals, {min(half) * dt:.6g} s), found {lookahead}")
        for (a, b, _), rev in zip(moving, reversal_after):
            if rev:
                idx = np.arange(max(a, b - lookahead), b)
                w[idx] = np.minimum(w[idx], (b - idx) / lookahead)
    if buildup > 0.0:
        for a, b, _ in moving:
            start = x[a - 1] if a > 0 else x[0]
            w[a:b] = np.minimum(w[a:b], np.minimum(np.abs(x[a:b] - start) / buildup, 1.0))
    if presliding is not None:
        from ..friction.presliding import coulomb_along

        w *= np.where(v != 0.0, coulomb_along(x, v, 1.0, presliding) * np.sign(v), 1.0)
    return v, w
