"""The sampled-data closed loop: plant, sensor, observer, filter and controller (numba).

One call of :func:`run_loop` simulates the whole horizon; there is no Python
work per sample. The observer enters only through affine-in-stiffness arrays
(``A(k) = A0 + k A1``, likewise ``b``, ``g``: :meth:`obsdesign.design.ObserverDesign.affine`),
so the kernel is the same for both model variants. Integer codes of the choices
(controller, schedule, estimator, plant) are those of :mod:`obsdesign.sampled.choices`.

Per sample ``n`` (time ``n dt``):

1. measure ``x_meas = Q(x + noise[n])`` (``Q``: rounding to the encoder resolution);
2. :func:`observer_sample`: advance the observer from ``n-1`` to ``n`` with the exact
   ZOH/FOH recursion of :mod:`obsdesign.design.discretize` (stiffness of the interval) and apply
   the back transformation eq:3:1:3; advance the low-pass filter eq:3:4:5 (exact for a
   linear input between samples); update the stiffness schedule for the next interval
   (``estimated``: a pre-sliding branch driven by ``x_meas`` and the sign of ``v_hat``;
   ``true``; ``constant``; estimator ``paper-k0``: k = 0) and recompute the recursion only
   when the stiffness changed. The same function runs the observer over measured data
   (:func:`observe_loop`), so offline and closed-loop estimates come from one implementation;
3. controller: open loop, or parallel PID eq:PIDparallel on the measured error
   with a first-order filtered derivative, conditional integration under
   saturation, plus ``comp / K`` for ``pid+observer`` (``comp = f_hat_filtered`` by default;
   gain, viscous term and deadzone of :mod:`obsdesign.compensation`);
4. integrate the plant to ``(n+1) dt`` with the input held: ``n_sub`` substeps of
   Heun's method (explicit trapezoidal rule, order 2), the pre-sliding branch frozen
   within a substep and updated after it (reversals are detected at substep
   resolution).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..design.discretize import coefficients
from ..estimators.base import estimator_output, estimator_step
from ..friction.kernels import friction_advance, friction_force, friction_n_state, friction_stiffness
from ..friction.kernels import friction_viscous
from ..friction.presliding import coulomb_normalized, stiffness, track_reversal, track_reversal_hysteresis

__all__ = ["run_loop", "observer_sample", "observe_loop", "new_observer_state", "empty_outputs",
           "OUTPUT_NAMES", "OBSERVER_STATE_SIZE", "PLANT_PHYSICAL", "PLANT_MODEL"]

PLANT_PHYSICAL, PLANT_MODEL = 0, 1
SCHEDULE_ESTIMATED, SCHEDULE_TRUE, SCHEDULE_CONSTANT, SCHEDULE_ESTIMATED_RAW = 0, 1, 2, 3
ESTIMATOR_PAPER, ESTIMATOR_PAPER_K0 = 0, 1  # codes >= 2: linear estimators (estimator_step)
FRICTION_PAPER = 0  # plant friction codes: obsdesign.friction (paper 0, lugre 1, dahl 2, gms 3)
#: Paper plant parameter array: Cf, Cf_neg, sigma, sigma_neg, offset, s, beta, kappa.
PP_CF, PP_CF_NEG, PP_SIGMA, PP_SIGMA_NEG, PP_OFFSET, PP_S, PP_BETA, PP_KAPPA = 0, 1, 2, 3, 4, 5, 6, 7
CONTROLLER_OPEN, CONTROLLER_PID, CONTROLLER_PID_OBSERVER = 0, 1, 2

#: States beyond these magnitudes count as diverged.
DIVERGED_X = 1e3
DIVERGED_F = 1e12

#: Length of the observer's state tuple (see :func:`new_observer_state`).
OBSERVER_STATE_SIZE = 21


def new_observer_state() -> tuple:
    """A fresh observer state for :func:`observer_sample` (before the first measurement).

    The state is a tuple of floats ``(y1, y2, zf1, zf2, fh_prev, xm_prev, e_dir, e_xr, e_fr,
    k_coef, P11, P12, P21, P22, bu1, bu2, gx01, gx02, gx11, gx12, e_ext)``: observer, filter, previous
    sample, branch of the estimated schedule, the recursion of the current stiffness and the
    extreme displacement of the branch (hysteresis of the ``estimated`` schedule). A tuple
    (not an array) lets the compiler keep it in registers inside the loop.
    """
    return _FRESH_STATE


_FRESH_STATE = (0.0,) * 9 + (-1.0,) + (0.0,) * 11


@njit(cache=True, error_model="numpy", inline="always")
def observer_sample(st, n, xm, u_prev, k_true, dt, Cf, s, kappa,
                    A0, A1, b0, b1, g0, g1, L1, L2, schedule, estimator, v_hat0, f_hat0,
                    lp_phi, lp_g0, lp_g1, reversal_threshold=0.0):
    """Process measurement ``xm`` of sample ``n`` (``u_prev``: the force held since sample ``n - 1``).

    ``st`` is the observer state (:func:`new_observer_state`); returns the new state and
    ``(v_hat, f_hat, f_hat_filtered, k)`` with ``k`` the stiffness scheduled for the coming
    interval; ``k_true`` is the plant's stiffness (used by the ``true`` schedule);
    ``reversal_threshold`` [m] is the hysteresis of the ``estimated`` schedule (0: as
    ``estimated-raw``, reversals at sign changes of ``v_hat``).
    """
    (y1, y2, zf1, zf2, fh_prev, xm_prev, e_dir, e_xr, e_fr, k_coef,
     P11, P12, P21, P22, bu1, bu2, gx01, gx02, gx11, gx12, e_ext) = st
    # observer recursion over the last interval, then the back transformation eq:3:1:3
    if n == 0:
        y1 = v_hat0 - L1 * xm
        y2 = f_hat0 - L2 * xm
    else:
        t1 = P11 * y1 + P12 * y2 + bu1 * u_prev + gx01 * xm_prev + gx11 * xm
        t2 = P21 * y1 + P22 * y2 + bu2 * u_prev + gx02 * xm_prev + gx12 * xm
        y1 = t1
        y2 = t2
    vh = y1 + L1 * xm
    fh = y2 + L2 * xm
    # low-pass filter eq:3:4:5 of the friction estimate (state-space, FOH input)
    if n > 0:
        t1 = lp_phi[0, 0] * zf1 + lp_phi[0, 1] * zf2 + lp_g0[0] * fh_prev + lp_g1[0] * fh
        t2 = lp_phi[1, 0] * zf1 + lp_phi[1, 1] * zf2 + lp_g0[1] * fh_prev + lp_g1[1] * fh
        zf1 = t1
        zf2 = t2
    ff = zf1
    # stiffness schedule for the coming interval
    if estimator == ESTIMATOR_PAPER_K0:
        k_now = 0.0
    elif schedule == SCHEDULE_ESTIMATED_RAW or (schedule == SCHEDULE_ESTIMATED and reversal_threshold == 0.0):
        e_dir, e_xr, e_fr = track_reversal(vh, xm, e_dir, e_xr, e_fr, s)
        k_now = stiffness(xm, e_dir, e_xr, e_fr, Cf, s, kappa)
    elif schedule == SCHEDULE_ESTIMATED:
        e_dir, e_xr, e_fr, e_ext = track_reversal_hysteresis(xm, e_dir, e_xr, e_fr, e_ext, s, reversal_threshold)
        k_now = stiffness(xm, e_dir, e_xr, e_fr, Cf, s, kappa)
    elif schedule == SCHEDULE_TRUE:
        k_now = k_true
    else:
        k_now = kappa
    if k_now != k_coef:
        k_coef = k_now
        c = coefficients(A0[0, 0] + k_now * A1[0, 0], A0[0, 1] + k_now * A1[0, 1],
                         A0[1, 0] + k_now * A1[1, 0], A0[1, 1] + k_now * A1[1, 1], dt)
        P11, P12, P21, P22 = c[0], c[1], c[2], c[3]
        bb1 = b0[0] + k_now * b1[0]
        bb2 = b0[1] + k_now * b1[1]
        gg1 = g0[0] + k_now * g1[0]
        gg2 = g0[1] + k_now * g1[1]
        bu1 = c[4] * bb1 + c[5] * bb2
        bu2 = c[6] * bb1 + c[7] * bb2
        gx11 = c[8] * gg1 + c[9] * gg2
        gx12 = c[10] * gg1 + c[11] * gg2
        gx01 = c[4] * gg1 + c[5] * gg2 - gx11
        gx02 = c[6] * gg1 + c[7] * gg2 - gx12
    st = (y1, y2, zf1, zf2, fh, xm, e_dir, e_xr, e_fr, k_coef,
          P11, P12, P21, P22, bu1, bu2, gx01, gx02, gx11, gx12, e_ext)
    return st, vh, fh, ff, k_now


@njit(cache=True, error_model="numpy", inline="always")
def _paper_coulomb(x, direction, x_r, f_r, pp):
    """Coulomb force [N] of the paper plant, ``Cf_neg`` on the negative side."""
    cn = coulomb_normalized(x, direction, x_r, f_r, pp[PP_S])
    return (pp[PP_CF] if cn >= 0.0 else pp[PP_CF_NEG]) * cn


@njit(cache=True, error_model="numpy", inline="always")
def _paper_sigma(v, pp):
    """Viscous coefficient [N s/m] of the paper plant for velocity ``v``."""
    return pp[PP_SIGMA] if v >= 0.0 else pp[PP_SIGMA_NEG]


@njit(cache=True, error_model="numpy")
def _plant_rhs(x, v, w, u, direction, x_r, f_r, mode, lag_model, m, Cf, s, sigma, beta, kappa):
    """Derivatives (v', w') of the paper plant; ``w`` is Fv (physical, lag) or w3 (model)."""
    if mode == PLANT_MODEL:
        k = stiffness(x, direction, x_r, f_r, Cf, s, kappa)
        if lag_model:
            return (u - w) / m, (k + sigma / beta) * v
        return (u - sigma * v - w) / m, k * v
    fc = Cf * coulomb_normalized(x, direction, x_r, f_r, s)
    if beta > 0.0:
        return (u - fc - w) / m, (sigma * v - w) / beta
    return (u - fc - sigma * v) / m, 0.0


@njit(cache=True, error_model="numpy")
def _plant_rhs_asym(x, v, w, u, direction, x_r, f_r, m, Cf, Cf_neg, s, sigma, sigma_neg, beta, offset):
    """:func:`_plant_rhs` of the physical paper plant with ``Cf_neg``/``sigma_neg`` for the
    negative side and a constant ``offset`` [N] (a separate loop keeps the symmetric one fast)."""
    cn = coulomb_normalized(x, direction, x_r, f_r, s)
    fc = (Cf if cn >= 0.0 else Cf_neg) * cn + offset
    sg = sigma if v >= 0.0 else sigma_neg
    if beta > 0.0:
        return (u - fc - w) / m, (sg * v - w) / beta
    return (u - fc - sg * v) / m, 0.0


@njit(cache=True, error_model="numpy", inline="never")
def _friction_plant_step(fcode, pp, fst, x, v, u, m, h, n_sub):
    """``n_sub`` Heun substeps of ``m x'' = u - F`` with a model of :mod:`obsdesign.friction`
    (``F`` with the state held in both stages, then :func:`friction_advance`)."""
    for _ in range(n_sub):
        k1v = (u - friction_force(fcode, pp, fst, x, v)) / m
        xp = x + h * v
        vp = v + h * k1v
        k2v = (u - friction_force(fcode, pp, fst, xp, vp)) / m
        x += 0.5 * h * (v + vp)
        v += 0.5 * h * (k1v + k2v)
        friction_advance(fcode, pp, fst, x, v, h)
    return x, v


@njit(cache=True, error_model="numpy")
def _true_friction(x, v, w, direction, x_r, f_r, mode, lag_model, Cf, s, sigma, beta):
    """The plant's value of the estimated state w3 (Fc + Fv for ``lag``, Fc for ``static``)."""
    if mode == PLANT_MODEL:
        return w
    fc = Cf * coulomb_normalized(x, direction, x_r, f_r, s)
    if not lag_model:
        return fc
    return fc + (w if beta > 0.0 else sigma * v)


@njit(cache=True, error_model="numpy", inline="always")
def _compensation(ff, vh, sigma, gain, viscous, deadzone):
    """Compensated friction force [N] (:mod:`obsdesign.compensation`); the defaults return ``ff``
    itself, so the paper's law ``ff / K`` is computed with exactly its own operations."""
    if gain == 1.0 and not viscous and deadzone == 0.0:
        return ff
    fade = 1.0
    if deadzone > 0.0:
        fade = abs(vh) / deadzone
        if not (fade < 1.0):
            fade = 1.0
    return gain * (ff + (sigma * vh if viscous else 0.0)) * fade


@njit(cache=True, error_model="numpy")
def _true_friction_other(x, v, w, direction, x_r, f_r, mode, lag_model, pp, fcode, fst):
    """:func:`_true_friction` of an asymmetric/offset paper plant or of a model of
    :mod:`obsdesign.friction`: for ``lag`` the whole friction, for ``static`` the friction less
    its viscous part (Fc + offset for the paper plant)."""
    if fcode != FRICTION_PAPER:
        F = friction_force(fcode, pp, fst, x, v)
        return F if lag_model else F - friction_viscous(fcode, pp, v)
    if mode == PLANT_MODEL:
        return w
    fc = _paper_coulomb(x, direction, x_r, f_r, pp) + pp[PP_OFFSET]
    if not lag_model:
        return fc
    return fc + (w if pp[PP_BETA] > 0.0 else _paper_sigma(v, pp) * v)


@njit(cache=True, error_model="numpy")
def run_loop(
    dt, n_sub, mode, lag_model, m, K, G, Cf, s, sigma, beta, kappa,
    A0, A1, b0, b1, g0, g1, L1, L2, schedule, estimator, v_hat0, f_hat0,
    controller, kp, ki, kd, tau_d, u_max, lp_phi, lp_g0, lp_g1,
    comp_gain, comp_viscous, comp_deadzone,
    x_ref, u_open, noise, quantization,
    fcode, pp, K_plant, G_plant, reversal_threshold, e_Phi, e_gu, e_g0, e_g1, e_Cz, e_d, e_init,
    out_x, out_xm, out_v, out_f, out_vh, out_fh, out_ff, out_u, out_k,
):
    """Run the loop over ``len(x_ref)`` samples, writing the ``out_*`` arrays.

    The observer, controller and load feed-forward use the design (``K``, ``G``, ``Cf``, ``s``,
    ``kappa``); the plant uses ``m``, ``K_plant``, ``G_plant`` and the friction model ``fcode``
    with parameters ``pp`` (paper: the ``PP_*`` layout; others: :mod:`obsdesign.friction`).
    ``estimator`` >= 2 runs the linear estimator ``e_*`` (:func:`obsdesign.estimators.estimator_step`)
    instead of the paper observer; its ``f_hat`` compensates unfiltered.
    Returns the number of samples written (less than the length when the run diverged).
    ``comp_gain``, ``comp_viscous`` (bool) and ``comp_deadzone`` [m/s] are the knobs of
    :class:`obsdesign.params.CompensationSpec` (``pid+observer`` only).
    """
    n_samples = x_ref.shape[0]
    h = dt / n_sub
    x = 0.0
    v = 0.0
    w = 0.0
    p_dir, p_xr, p_fr = 0.0, 0.0, 0.0  # plant pre-sliding branch
    ost = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    fst = np.zeros(max(friction_n_state(fcode, pp), 1))  # the friction state of lugre/dahl/gms
    ez = np.zeros(e_Phi.shape[0])  # state of a linear estimator
    # the paper plant's parameters as scalars (the hot loop below reads no arrays)
    Cf_p, Cfn_p, sig_p, sgn_p, off_p, s_p, beta_p, kap_p = pp[0], pp[0], pp[0], pp[0], 0.0, pp[0], pp[0], pp[0]
    if fcode == FRICTION_PAPER:
        Cf_p, Cfn_p, sig_p, sgn_p = pp[PP_CF], pp[PP_CF_NEG], pp[PP_SIGMA], pp[PP_SIGMA_NEG]
        off_p, s_p, beta_p, kap_p = pp[PP_OFFSET], pp[PP_S], pp[PP_BETA], pp[PP_KAPPA]
    asym = mode == PLANT_PHYSICAL and (Cfn_p != Cf_p or sgn_p != sig_p or off_p != 0.0)
    xm_prev = 0.0
    u_prev = 0.0
    integ = 0.0
    deriv = 0.0
    e_prev = 0.0
    alpha_d = math.exp(-dt / tau_d) if tau_d > 0.0 else 0.0
    for n in range(n_samples):
        # 1. measurement
        xm = x + noise[n]
        if quantization > 0.0:
            xm = quantization * np.floor(xm / quantization + 0.5)  # float: no int64 overflow
        # 2. observer, filter and stiffness schedule
        if estimator > ESTIMATOR_PAPER_K0:
            if n == 0:
                for i in range(ez.shape[0]):
                    ez[i] = e_init[i, 0] * xm + e_init[i, 1] * v_hat0 + e_init[i, 2] * f_hat0
                vh, fh = estimator_output(e_Cz, e_d, ez, xm)
            else:
                vh, fh = estimator_step(e_Phi, e_gu, e_g0, e_g1, e_Cz, e_d, ez, u_prev, xm_prev, xm)
            ff = fh
            k_now = 0.0
            xm_prev = xm
        else:
            k_true = 0.0
            if schedule == SCHEDULE_TRUE:
                if fcode == FRICTION_PAPER:
                    k_true = stiffness(x, p_dir, p_xr, p_fr, Cf_p, s_p, kappa)
                else:
                    k_true = min(friction_stiffness(fcode, pp, fst, x, v), kappa)
            ost, vh, fh, ff, k_now = observer_sample(ost, n, xm, u_prev, k_true, dt, Cf, s, kappa,
                                                     A0, A1, b0, b1, g0, g1, L1, L2, schedule, estimator,
                                                     v_hat0, f_hat0, lp_phi, lp_g0, lp_g1, reversal_threshold)
        # 3. controller (volts), load feed-forward, saturation
        if controller == CONTROLLER_OPEN:
            u_volt = u_open[n] / K
        else:
            e = x_ref[n] - xm
            if n == 0:
                e_prev = e
            deriv = alpha_d * deriv + (1.0 - alpha_d) * (e - e_prev) / dt
            integ_new = integ + e * dt
            u_volt = kp * e + ki * integ_new + kd * deriv
            if controller == CONTROLLER_PID_OBSERVER:
                u_volt += _compensation(ff, vh, sigma, comp_gain, comp_viscous, comp_deadzone) / K
            total = u_volt + G / K
            if abs(total) <= u_max:
                integ = integ_new  # conditional integration (anti-windup)
            e_prev = e
        total = u_volt + G / K
        if total > u_max:
            total = u_max
        elif total < -u_max:
            total = -u_max
        u = K_plant * total - G_plant  # net driving force, load compensated
        # record
        out_x[n] = x
        out_xm[n] = xm
        out_v[n] = v
        if asym or fcode != FRICTION_PAPER:
            out_f[n] = _true_friction_other(x, v, w, p_dir, p_xr, p_fr, mode, lag_model, pp, fcode, fst)
        else:
            out_f[n] = _true_friction(x, v, w, p_dir, p_xr, p_fr, mode, lag_model, Cf_p, s_p, sig_p, beta_p)
        out_vh[n] = vh
        out_fh[n] = fh
        out_ff[n] = ff
        out_u[n] = u
        out_k[n] = k_now
        if not (abs(x) < DIVERGED_X and abs(fh) < DIVERGED_F and abs(vh) < DIVERGED_F
                and abs(ff) < DIVERGED_F and abs(v) < DIVERGED_F):
            return n + 1
        # 4. plant, Heun (explicit trapezoidal, order 2) substeps with the input held
        if fcode != FRICTION_PAPER:
            x, v = _friction_plant_step(fcode, pp, fst, x, v, u, m, h, n_sub)
            u_prev = u
            continue
        if asym:
            for _ in range(n_sub):
                k1v, k1w = _plant_rhs_asym(x, v, w, u, p_dir, p_xr, p_fr, m, Cf_p, Cfn_p, s_p, sig_p, sgn_p, beta_p, off_p)
                xp = x + h * v
                vp = v + h * k1v
                wp = w + h * k1w
                k2v, k2w = _plant_rhs_asym(xp, vp, wp, u, p_dir, p_xr, p_fr, m, Cf_p, Cfn_p, s_p, sig_p, sgn_p, beta_p,
                                           off_p)
                x += 0.5 * h * (v + vp)
                v += 0.5 * h * (k1v + k2v)
                w += 0.5 * h * (k1w + k2w)
                p_dir, p_xr, p_fr = track_reversal(v, x, p_dir, p_xr, p_fr, s_p)
            u_prev = u
            continue
        for _ in range(n_sub):
            k1v, k1w = _plant_rhs(x, v, w, u, p_dir, p_xr, p_fr, mode, lag_model, m, Cf_p, s_p, sig_p, beta_p, kap_p)
            xp = x + h * v
            vp = v + h * k1v
            wp = w + h * k1w
            k2v, k2w = _plant_rhs(xp, vp, wp, u, p_dir, p_xr, p_fr, mode, lag_model, m, Cf_p, s_p, sig_p, beta_p, kap_p)
            x += 0.5 * h * (v + vp)
            v += 0.5 * h * (k1v + k2v)
            w += 0.5 * h * (k1w + k2w)
            p_dir, p_xr, p_fr = track_reversal(v, x, p_dir, p_xr, p_fr, s_p)
        u_prev = u
    return n_samples


@njit(cache=True, error_model="numpy")
def observe_loop(dt, Cf, s, kappa, A0, A1, b0, b1, g0, g1, L1, L2, schedule, estimator, v_hat0, f_hat0,
                 lp_phi, lp_g0, lp_g1, x_meas, u, k_true, out_vh, out_fh, out_ff, out_k, reversal_threshold=0.0):
    """The observer of :func:`run_loop` over measured data: ``x_meas[n]`` and the force ``u[n]``
    applied from sample ``n`` to ``n + 1`` (``k_true``: a stiffness trace for the ``true`` schedule)."""
    st = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    u_prev = 0.0
    for n in range(x_meas.shape[0]):
        st, vh, fh, ff, k_now = observer_sample(st, n, x_meas[n], u_prev, k_true[n], dt, Cf, s, kappa,
                                            A0, A1, b0, b1, g0, g1, L1, L2, schedule, estimator,
                                            v_hat0, f_hat0, lp_phi, lp_g0, lp_g1, reversal_threshold)
        out_vh[n] = vh
        out_fh[n] = fh
        out_ff[n] = ff
        out_k[n] = k_now
        u_prev = u[n]


#: Output arrays of :func:`run_loop`, in its argument order.
OUTPUT_NAMES = ("x", "x_meas", "v", "f", "v_hat", "f_hat", "f_hat_filtered", "u", "stiffness")


def empty_outputs(n: int) -> dict[str, np.ndarray]:
    """Output arrays for :func:`run_loop` (NaN where a diverged run stopped).

    Parameters
    ----------
    n : int
        Number of samples.
    """
    return {name: np.full(n, np.nan) for name in OUTPUT_NAMES}
