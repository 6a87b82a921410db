"""The sampled controller's step (numba): what runs once per sample, in the simulator and over a log.

One sample ``n`` of :func:`controller_sample` (the closed loop of :func:`obsdesign.sim.kernel.run_loop`
calls it, and every export of :mod:`obsdesign.export.controller` does the same arithmetic in the
same order):

1. estimator: :func:`observer_sample` (the paper's observer: exact ZOH/FOH recursion of
   :mod:`obsdesign.design.discretize` over the last interval with its stiffness, back
   transformation eq:3:1:3, low-pass eq:3:4:5 of ``f_hat``, stiffness schedule of the coming
   interval, the recursion recomputed only when the stiffness changed) or a linear baseline
   (:func:`obsdesign.estimators.base.estimator_step`, compensating with its unfiltered ``f_hat``);
2. controller: open loop (``u_open / K``), or the parallel PID eq:PIDparallel on the measured error
   with a first-order filtered derivative and conditional integration under saturation, plus
   ``comp / K`` for ``pid+observer``: mode ``observer`` :func:`compensation_force`; ``feedforward``
   and ``blend`` :func:`reference_compensation` of the reference velocity ``v_ref`` and weight
   ``w_ff`` (inputs of the sample, :func:`obsdesign.sampled.reference.reference_feedforward`);
3. load feed-forward ``G / K``, saturation at ``u_max``; the net force ``K command - G`` of the command
   the drive applies until the next sample is what the estimator is fed at the next sample: this
   sample's command without a drive delay; with ``d = [hardware] delay_samples`` the command of sample
   ``n - d`` (``ring``, the last ``d`` commands, starting at ``ControllerArgs.held_command``).

The controller does not wait: the drive's delay between the sampled position and the applied command
belongs to the plant and is simulated there (:func:`obsdesign.sim.kernel.run_loop`), so an exported
controller on hardware that has the delay sees the loop that was simulated; the controller only keeps
its last ``d`` commands so that its estimator sees the force the plant gets (docs/delay.md).

:func:`observe_loop` runs step 1 alone over measured data. The arguments come in named groups
(:class:`~obsdesign.sampled.controller.ObserverArgs`, ``EstimatorArgs``, ``ControllerArgs``) built
by :meth:`obsdesign.sampled.SampledController.kernel_args`; the integer codes are those of
:mod:`obsdesign.sampled.choices`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..design.discretize import coefficients
from ..estimators.base import estimator_output, estimator_step
from ..friction.presliding import stiffness, track_reversal, track_reversal_hysteresis
from ..estimators.registry import FIRST_BASELINE_CODE
from ..compensation import COMPENSATION_MODES
from .choices import CONTROLLERS, ESTIMATORS, SCHEDULES

__all__ = ["observer_sample", "controller_sample", "compensation_force", "reference_compensation",
           "feedforward_model", "observe_loop", "command_ring", "OBSERVER_STATE", "CONTROLLER_STATE"]

# Codes read once from the registries; numba freezes module globals at compile time (the registries
# are append-only: a code never changes meaning).
SCHEDULE_ESTIMATED = SCHEDULES.code("estimated")
SCHEDULE_TRUE = SCHEDULES.code("true")
SCHEDULE_CONSTANT = SCHEDULES.code("constant")
SCHEDULE_ESTIMATED_RAW = SCHEDULES.code("estimated-raw")
ESTIMATOR_PAPER_K0 = ESTIMATORS.code("paper-k0")
CONTROLLER_OPEN = CONTROLLERS.code("open-loop")
CONTROLLER_PID_OBSERVER = CONTROLLERS.code("pid+observer")
COMP_OBSERVER = COMPENSATION_MODES.code("observer")
COMP_BLEND = COMPENSATION_MODES.code("blend")

#: The observer's state before the first measurement: ``(y1, y2, zf1, zf2, fh_prev, xm_prev, e_dir,
#: e_xr, e_fr, k_coef, P11, P12, P21, P22, bu1, bu2, gx01, gx02, gx11, gx12, e_ext)``: observer,
#: filter, previous sample, branch of the estimated schedule, the recursion of the current stiffness
#: (``k_coef = -1``: none yet) and the extreme displacement of the branch (hysteresis). A tuple, not
#: an array, so the compiler keeps it in registers.
OBSERVER_STATE = (0.0,) * 9 + (-1.0,) + (0.0,) * 11
#: The controller's state before the first sample: ``(u_prev, xm_prev, integ, deriv, e_prev, zb1, zb2,
#: fb_prev)``: the last three are the low-pass of the model part of mode ``blend``.
CONTROLLER_STATE = (0.0,) * 8


@njit(cache=True, error_model="numpy", inline="always")
def lowpass_step(z1, z2, u_prev, u, obs):
    """One sample of the low-pass filter eq:3:4:5 in state space with FOH input: the state ``(z1, z2)``
    after the input went from ``u_prev`` to ``u`` (``obs.lp_phi``, ``obs.lp_g0``, ``obs.lp_g1``)."""
    lp_phi, lp_g0, lp_g1 = obs.lp_phi, obs.lp_g0, obs.lp_g1
    t1 = lp_phi[0, 0] * z1 + lp_phi[0, 1] * z2 + lp_g0[0] * u_prev + lp_g1[0] * u
    t2 = lp_phi[1, 0] * z1 + lp_phi[1, 1] * z2 + lp_g0[1] * u_prev + lp_g1[1] * u
    return t1, t2


@njit(cache=True, error_model="numpy", inline="always")
def observer_sample(st, n, xm, u_prev, k_true, obs):
    """Process measurement ``xm`` of sample ``n`` (``u_prev``: the net force held since sample ``n - 1``).

    ``st`` is the observer state (:data:`OBSERVER_STATE` before the first sample), ``obs`` the
    :class:`~obsdesign.sampled.controller.ObserverArgs`; returns the new state and ``(v_hat, f_hat,
    f_hat_filtered, k)`` with ``k`` the stiffness scheduled for the coming interval; ``k_true`` is
    the plant's stiffness (used by the ``true`` schedule). ``obs.reversal_threshold`` [m] is the
    hysteresis of the ``estimated`` schedule (0: as ``estimated-raw``, reversals at sign changes of
    ``v_hat``).
    """
    (y1, y2, zf1, zf2, fh_prev, xm_prev, e_dir, e_xr, e_fr, k_coef,
     P11, P12, P21, P22, bu1, bu2, gx01, gx02, gx11, gx12, e_ext) = st
    L1 = obs.L1
    L2 = obs.L2
    # observer recursion over the last interval, then the back transformation eq:3:1:3
    if n == 0:
        y1 = obs.v_hat0 - L1 * xm
        y2 = obs.f_hat0 - L2 * xm
    else:
        t1 = P11 * y1 + P12 * y2 + bu1 * u_prev + gx01 * xm_prev + gx11 * xm
        t2 = P21 * y1 + P22 * y2 + bu2 * u_prev + gx02 * xm_prev + gx12 * xm
        y1 = t1
        y2 = t2
    vh = y1 + L1 * xm
    fh = y2 + L2 * xm
    # low-pass filter eq:3:4:5 of the friction estimate (state-space, FOH input)
    if n > 0:
        zf1, zf2 = lowpass_step(zf1, zf2, fh_prev, fh, obs)
    ff = zf1
    # stiffness schedule for the coming interval
    schedule = obs.schedule
    threshold = obs.reversal_threshold
    s = obs.s
    if obs.estimator == ESTIMATOR_PAPER_K0:
        k_now = 0.0
    elif schedule == SCHEDULE_ESTIMATED_RAW or (schedule == SCHEDULE_ESTIMATED and threshold == 0.0):
        e_dir, e_xr, e_fr = track_reversal(vh, xm, e_dir, e_xr, e_fr, s)
        k_now = stiffness(xm, e_dir, e_xr, e_fr, obs.Cf, s, obs.kappa)
    elif schedule == SCHEDULE_ESTIMATED:
        e_dir, e_xr, e_fr, e_ext = track_reversal_hysteresis(xm, e_dir, e_xr, e_fr, e_ext, s, threshold)
        k_now = stiffness(xm, e_dir, e_xr, e_fr, obs.Cf, s, obs.kappa)
    elif schedule == SCHEDULE_TRUE:
        k_now = k_true
    else:
        k_now = obs.kappa
    if k_now != k_coef:
        k_coef = k_now
        A0, A1 = obs.A0, obs.A1
        c = coefficients(A0[0, 0] + k_now * A1[0, 0], A0[0, 1] + k_now * A1[0, 1],
                         A0[1, 0] + k_now * A1[1, 0], A0[1, 1] + k_now * A1[1, 1], obs.dt)
        P11, P12, P21, P22 = c[0], c[1], c[2], c[3]
        bb1 = obs.b0[0] + k_now * obs.b1[0]
        bb2 = obs.b0[1] + k_now * obs.b1[1]
        gg1 = obs.g0[0] + k_now * obs.g1[0]
        gg2 = obs.g0[1] + k_now * obs.g1[1]
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
def _estimate(ost, ez, n, xm, u_prev, xm_prev, k_true, obs, est):
    """Step 1 of :func:`controller_sample`: ``(ost, v_hat, f_hat, compensated signal, k)``."""
    if obs.estimator >= FIRST_BASELINE_CODE:  # a linear baseline of obsdesign.estimators
        if n == 0:
            for i in range(ez.shape[0]):
                ez[i] = est.init[i, 0] * xm + est.init[i, 1] * obs.v_hat0 + est.init[i, 2] * obs.f_hat0
            vh, fh = estimator_output(est.Cz, est.d, ez, xm)
        else:
            vh, fh = estimator_step(est.Phi, est.gu, est.g0, est.g1, est.Cz, est.d, ez, u_prev, xm_prev, xm)
        return ost, vh, fh, fh, 0.0
    ost, vh, fh, ff, k_now = observer_sample(ost, n, xm, u_prev, k_true, obs)
    return ost, vh, fh, ff, k_now


@njit(cache=True, error_model="numpy", inline="always")
def compensation_force(ff, vh, ctrl):
    """Compensated friction force [N] (:mod:`obsdesign.compensation`): ``gain (ff + sigma v_hat
    [viscous]) fade`` with ``fade = min(1, |v_hat| / deadzone)``; the defaults return ``ff`` itself,
    so the paper's law ``ff / K`` is computed with exactly its own operations."""
    if ctrl.comp_gain == 1.0 and not ctrl.comp_viscous and ctrl.comp_deadzone == 0.0:
        return ff
    fade = 1.0
    if ctrl.comp_deadzone > 0.0:
        fade = abs(vh) / ctrl.comp_deadzone
        if not (fade < 1.0):
            fade = 1.0
    return ctrl.comp_gain * (ff + (ctrl.sigma * vh if ctrl.comp_viscous else 0.0)) * fade


@njit(cache=True, error_model="numpy", inline="always")
def feedforward_model(v_ref, w_ff, viscous, ctrl):
    """The feed-forward friction model [N] of mode ``feedforward``: ``w_ff (sign(v_ref) (Cf + Fst
    exp(-(v_ref / vst)^2)) + sigma v_ref [viscous]) + offset`` (``sign(0) = 0``)."""
    c = 0.0
    if v_ref != 0.0:
        q = v_ref / ctrl.ff_vs
        c = ctrl.ff_cf + ctrl.ff_stribeck * np.exp(-(q * q))
        if v_ref < 0.0:
            c = -c
    if viscous:
        c += ctrl.sigma * v_ref
    return w_ff * c + ctrl.ff_offset


@njit(cache=True, error_model="numpy", inline="always")
def reference_compensation(n, ff, v_ref, w_ff, zb1, zb2, fb_prev, obs, ctrl):
    """Compensated force [N] of modes ``feedforward`` and ``blend``, and the blend's low-pass state.

    ``feedforward``: ``gain F(v_ref)`` (:func:`feedforward_model`). ``blend``: ``gain (F(v_ref) +
    ff - LP[F_o])`` with ``ff`` the observer's low-passed estimate eq:3:4:5 and ``LP[F_o]`` the same
    low-pass (same recursion, same start) of ``F_o``, the part of the model the observer estimates
    (all of it for variant ``lag``; without the viscous term for ``static``): the sum is ``(1 - LP) F
    + LP f_hat``, so each frequency of the friction is compensated once. Returns ``(comp, zb1, zb2,
    fb)``.
    """
    f_model = feedforward_model(v_ref, w_ff, True, ctrl)
    if ctrl.comp_mode != COMP_BLEND:
        return ctrl.comp_gain * f_model, zb1, zb2, fb_prev
    fo = f_model if ctrl.blend_viscous else feedforward_model(v_ref, w_ff, False, ctrl)
    if n > 0:
        zb1, zb2 = lowpass_step(zb1, zb2, fb_prev, fo, obs)
    return ctrl.comp_gain * (f_model + ff - zb1), zb1, zb2, fo


@njit(cache=True, error_model="numpy")
def command_ring(ctrl):
    """The controller's ring of its last ``d`` commands before the first sample (``d = ctrl.delay``, the
    drive's delay): ``max(d, 1)`` times ``ctrl.held_command`` [V], what the drive applies until the
    first computed command arrives.

    Parameters
    ----------
    ctrl : ControllerArgs

    Examples
    --------
    >>> import obsdesign as od
    >>> from obsdesign.sampled import sampled_controller
    >>> ctrl = sampled_controller(od.load_preset("vcm").override(delay_samples=2)).kernel_args()[2]
    >>> [round(float(u), 4) for u in command_ring(ctrl)]   # G / K = 5.27 / 3.28 V
    [1.6067, 1.6067]
    """
    return np.full(max(ctrl.delay, 1), ctrl.held_command)


@njit(cache=True, error_model="numpy", inline="always")
def controller_sample(cst, ost, ez, ring, n, x_ref, v_ref, w_ff, u_open, xm, k_true, obs, est, ctrl):
    """One sample of the whole controller: measurement ``xm`` and reference ``x_ref`` in, command out.

    ``cst`` is the controller state (:data:`CONTROLLER_STATE`), ``ost`` the observer's
    (:data:`OBSERVER_STATE`), ``ez`` the state array of a linear baseline and ``ring`` the last
    ``ctrl.delay`` commands (:func:`command_ring`; both updated in place); ``v_ref``
    [m/s] and ``w_ff`` are the reference velocity and feed-forward weight of the sample (read by the
    modes ``feedforward`` and ``blend`` only); ``u_open`` is the open-loop force [N] of the sample
    (``open-loop`` only). Returns ``(cst, ost, command [V]
    computed at this sample (after saturation, with the feed-forward), v_hat, f_hat,
    f_hat_filtered (the compensated signal), k)``.
    """
    u_prev, xm_prev, integ, deriv, e_prev, zb1, zb2, fb_prev = cst
    ost, vh, fh, ff, k_now = _estimate(ost, ez, n, xm, u_prev, xm_prev, k_true, obs, est)
    K = ctrl.K
    if ctrl.controller == CONTROLLER_OPEN:
        u_volt = u_open / K
    else:
        e = x_ref - xm
        if n == 0:
            e_prev = e
        deriv = ctrl.alpha_d * deriv + (1.0 - ctrl.alpha_d) * (e - e_prev) / ctrl.dt
        integ_new = integ + e * ctrl.dt
        u_volt = ctrl.kp * e + ctrl.ki * integ_new + ctrl.kd * deriv
        if ctrl.controller == CONTROLLER_PID_OBSERVER:
            if ctrl.comp_mode == COMP_OBSERVER:
                u_volt += compensation_force(ff, vh, ctrl) / K
            else:
                comp, zb1, zb2, fb_prev = reference_compensation(n, ff, v_ref, w_ff, zb1, zb2, fb_prev, obs, ctrl)
                u_volt += comp / K
        total = u_volt + ctrl.G / K
        if abs(total) <= ctrl.u_max:
            integ = integ_new  # conditional integration (anti-windup)
        e_prev = e
    total = u_volt + ctrl.G / K
    if total > ctrl.u_max:
        total = ctrl.u_max
    elif total < -ctrl.u_max:
        total = -ctrl.u_max
    applied = total
    if ctrl.delay > 0:  # the drive applies the command of sample n - delay: the estimator's next input
        slot = n % ctrl.delay
        applied = ring[slot]
        ring[slot] = total
    cst = (K * applied - ctrl.G, xm, integ, deriv, e_prev, zb1, zb2, fb_prev)
    return cst, ost, total, vh, fh, ff, k_now


@njit(cache=True, error_model="numpy")
def observe_loop(obs, est, x_meas, u, k_true, out_vh, out_fh, out_ff, out_k):
    """Step 1 of :func:`controller_sample` over measured data: ``x_meas[n]`` and the net force
    ``u[n]`` applied from sample ``n`` to ``n + 1`` (``k_true``: a stiffness trace for the ``true``
    schedule); writes the estimates of every sample into the ``out_*`` arrays."""
    if obs.estimator >= FIRST_BASELINE_CODE:
        _observe(obs, est, x_meas, u, k_true, out_vh, out_fh, out_ff, out_k)
    else:  # the same step with the baseline branch known false: a tighter loop for the paper's observer
        _observe_paper(obs, x_meas, u, k_true, out_vh, out_fh, out_ff, out_k)


@njit(cache=True, error_model="numpy")
def _observe(obs, est, x_meas, u, k_true, out_vh, out_fh, out_ff, out_k):
    ost = OBSERVER_STATE
    ez = est.init[:, 0] * 0.0
    u_prev = 0.0
    xm_prev = 0.0
    for n in range(x_meas.shape[0]):
        xm = x_meas[n]
        ost, vh, fh, ff, k_now = _estimate(ost, ez, n, xm, u_prev, xm_prev, k_true[n], obs, est)
        out_vh[n] = vh
        out_fh[n] = fh
        out_ff[n] = ff
        out_k[n] = k_now
        u_prev = u[n]
        xm_prev = xm


@njit(cache=True, error_model="numpy", _nrt=False)  # type: ignore[call-overload]  # numba-internal flag
def _observe_paper(obs, x_meas, u, k_true, out_vh, out_fh, out_ff, out_k):
    # no reference counting (_nrt=False; it allocates nothing, its arrays are the caller's): the inlined
    # step binds obs's nine arrays afresh every sample, 18 atomic operations (obsdesign.sim.kernel._run_samples)
    ost = OBSERVER_STATE
    u_prev = 0.0
    for n in range(x_meas.shape[0]):
        ost, vh, fh, ff, k_now = observer_sample(ost, n, x_meas[n], u_prev, k_true[n], obs)
        out_vh[n] = vh
        out_fh[n] = fh
        out_ff[n] = ff
        out_k[n] = k_now
        u_prev = u[n]
