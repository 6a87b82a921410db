"""The sampled-data closed loop: the plant and its sensor around the sampled controller (numba).

One call of :func:`run_loop` simulates the whole horizon; there is no Python work per sample.
The controller is :func:`obsdesign.sampled.kernel.controller_sample`, the one step that the
exports reproduce and that :func:`obsdesign.sampled.kernel.observe_loop` runs over a log; this
module adds the plant, the sensor and the records. Arguments come in named groups: the
controller's (:meth:`obsdesign.sampled.SampledController.kernel_args`), the loop's
:class:`~obsdesign.loop.args.PlantArgs` and :class:`~obsdesign.loop.args.Signals`
(:meth:`obsdesign.loop.LoopInputs.kernel_args`) and :class:`Outputs`.

Per sample ``n`` (time ``n dt``):

1. measure ``x_meas = Q(x + noise[n])`` (``Q``: rounding to the encoder resolution);
2. the sampled controller: estimator, PID with compensation, feed-forward, saturation
   (:mod:`obsdesign.sampled.kernel`);
3. the drive's delay of ``d = PlantArgs.delay`` samples (``[hardware] delay_samples``): the command
   computed at sample ``n`` is applied from sample ``n + d`` on (a ring buffer of ``d`` commands that
   holds ``PlantArgs.delay_init``, the saturated feed-forward ``G / K``, before the first computed
   command arrives); the plant's net force is ``K_plant applied - G_plant``;
4. integrate the plant to ``(n+1) dt`` with the input held: ``n_sub`` substeps of
   Heun's method (explicit trapezoidal rule, order 2), the pre-sliding branch frozen
   within a substep and updated after it (reversals are detected at substep
   resolution).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from ..friction.kernels import friction_force, friction_n_state, friction_plant_step, friction_stiffness
from ..friction.kernels import friction_viscous
from ..friction.presliding import coulomb_normalized, stiffness, track_reversal
from ..friction.registry import FRICTION_MODELS
from ..loop.args import PlantArgs, Signals
from ..sampled.choices import PLANTS, SCHEDULES
from ..sampled.kernel import CONTROLLER_STATE, OBSERVER_STATE, command_ring, controller_sample

__all__ = ["run_loop", "delay_buffer", "measure", "plant_interval", "plant_friction", "plant_stiffness", "paper_scalars",
           "PlantArgs", "Signals", "Outputs", "empty_outputs", "OUTPUT_NAMES", "PLANT_PHYSICAL", "PLANT_MODEL"]

PLANT_PHYSICAL = PLANTS.code("physical")
PLANT_MODEL = PLANTS.code("model")
SCHEDULE_TRUE = SCHEDULES.code("true")
FRICTION_PAPER = FRICTION_MODELS.code("paper")  # other codes: the models of obsdesign.friction
#: Paper plant parameter array: Cf, Cf_neg, sigma, sigma_neg, offset, s, beta, kappa.
PP_CF, PP_CF_NEG, PP_SIGMA, PP_SIGMA_NEG, PP_OFFSET, PP_S, PP_BETA, PP_KAPPA = 0, 1, 2, 3, 4, 5, 6, 7

#: States beyond these magnitudes count as diverged.
DIVERGED_X = 1e3
DIVERGED_F = 1e12


#: Output arrays of :func:`run_loop`, in the order of :class:`Outputs`.
OUTPUT_NAMES = ("x", "x_meas", "v", "f", "v_hat", "f_hat", "f_hat_filtered", "u", "stiffness")


class Outputs(NamedTuple):
    """The arrays :func:`run_loop` writes, one value per sample (SI units).

    Attributes
    ----------
    x, x_meas, v, f, v_hat, f_hat, f_hat_filtered, u, stiffness : ndarray
    """

    x: np.ndarray
    x_meas: np.ndarray
    v: np.ndarray
    f: np.ndarray
    v_hat: np.ndarray
    f_hat: np.ndarray
    f_hat_filtered: np.ndarray
    u: np.ndarray
    stiffness: np.ndarray


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


@njit(cache=True, error_model="numpy")
def _true_friction(x, v, w, direction, x_r, f_r, mode, lag_model, Cf, s, sigma, beta):
    """The plant's value of the estimated state w3 (Fc + Fv for ``lag``, Fc for ``static``)."""
    if mode == PLANT_MODEL:
        return w
    fc = Cf * coulomb_normalized(x, direction, x_r, f_r, s)
    if not lag_model:
        return fc
    return fc + (w if beta > 0.0 else sigma * v)


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


@njit(cache=True, error_model="numpy", inline="always")
def paper_scalars(plant):
    """The paper plant's parameters as scalars ``(Cf, Cf_neg, sigma, sigma_neg, offset, s, beta, kappa,
    asym)`` (``asym``: a physical plant with a negative side or an offset); placeholders for the other
    models. Computed once per run: the hot loop of :func:`plant_interval` then reads no arrays."""
    pp, fcode = plant.plant_params, plant.friction_code
    Cf_p, Cfn_p, sig_p, sgn_p, off_p, s_p, beta_p, kap_p = pp[0], pp[0], pp[0], pp[0], 0.0, pp[0], pp[0], pp[0]
    if fcode == FRICTION_PAPER:
        Cf_p, Cfn_p, sig_p, sgn_p = pp[PP_CF], pp[PP_CF_NEG], pp[PP_SIGMA], pp[PP_SIGMA_NEG]
        off_p, s_p, beta_p, kap_p = pp[PP_OFFSET], pp[PP_S], pp[PP_BETA], pp[PP_KAPPA]
    asym = plant.mode == PLANT_PHYSICAL and (Cfn_p != Cf_p or sgn_p != sig_p or off_p != 0.0)
    return Cf_p, Cfn_p, sig_p, sgn_p, off_p, s_p, beta_p, kap_p, asym


@njit(cache=True, error_model="numpy", inline="always")
def measure(x, noise, quantization):
    """The sensor: ``Q(x + noise)``, ``Q`` rounding to the encoder resolution (0: none)."""
    xm = x + noise
    if quantization > 0.0:
        xm = quantization * np.floor(xm / quantization + 0.5)  # float: no int64 overflow
    return xm


@njit(cache=True, error_model="numpy", inline="always")
def plant_interval(ps, u, fst, h, plant, sc):
    """The plant over one sample with the net force ``u`` [N] held: ``n_sub`` Heun substeps (explicit
    trapezoidal, order 2) from the state ``ps = (x, v, w, p_dir, p_xr, p_fr)`` (``w``: the viscous
    state or w3, then the pre-sliding branch); ``fst``: the friction state of lugre/dahl/gms (updated
    in place); ``sc``: :func:`paper_scalars`. Returns the new ``ps``."""
    x, v, w, p_dir, p_xr, p_fr = ps
    n_sub, mode, lag_model, m = plant.n_sub, plant.mode, plant.lag_model, plant.m
    fcode, pp = plant.friction_code, plant.plant_params
    Cf_p, Cfn_p, sig_p, sgn_p, off_p, s_p, beta_p, kap_p, asym = sc
    if fcode != FRICTION_PAPER:
        x, v = friction_plant_step(fcode, pp, fst, x, v, u, m, h, n_sub)
        return x, v, w, p_dir, p_xr, p_fr
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
        return x, v, w, p_dir, p_xr, p_fr
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
    return x, v, w, p_dir, p_xr, p_fr


@njit(cache=True, error_model="numpy", inline="always")
def plant_friction(ps, fst, plant, sc):
    """The plant's value of the estimated state w3 at state ``ps`` (:func:`plant_interval`)."""
    x, v, w, p_dir, p_xr, p_fr = ps
    Cf_p, s_p, sig_p, beta_p, asym = sc[0], sc[5], sc[2], sc[6], sc[8]
    if asym or plant.friction_code != FRICTION_PAPER:
        return _true_friction_other(x, v, w, p_dir, p_xr, p_fr, plant.mode, plant.lag_model, plant.plant_params,
                                    plant.friction_code, fst)
    return _true_friction(x, v, w, p_dir, p_xr, p_fr, plant.mode, plant.lag_model, Cf_p, s_p, sig_p, beta_p)


@njit(cache=True, error_model="numpy", inline="always")
def plant_stiffness(ps, fst, plant, sc, kappa):
    """The plant's pre-sliding stiffness at state ``ps``, at most ``kappa`` (the ``true`` schedule)."""
    x, v, w, p_dir, p_xr, p_fr = ps
    if plant.friction_code == FRICTION_PAPER:
        return stiffness(x, p_dir, p_xr, p_fr, sc[0], sc[5], kappa)
    return min(friction_stiffness(plant.friction_code, plant.plant_params, fst, x, v), kappa)


@njit(cache=True, error_model="numpy")
def run_loop(obs, est, ctrl, plant, sig, out):
    """Run the loop over ``len(sig.x_ref)`` samples, writing the arrays of ``out``.

    ``obs``, ``est``, ``ctrl``: the sampled controller's groups
    (:meth:`obsdesign.sampled.SampledController.kernel_args`), which use the design; ``plant``
    (:class:`PlantArgs`): the simulated plant with its own mass, gain, load, friction model and the
    drive's delay; ``sig`` (:class:`Signals`): reference, open-loop force, noise; ``out`` (:class:`Outputs`).
    Returns the number of samples written (less than the length when the run diverged).
    """
    fst = np.zeros(max(friction_n_state(plant.friction_code, plant.plant_params), 1))  # lugre/dahl/gms state
    ez = np.zeros(est.Phi.shape[0])  # state of a linear estimator
    ubuf = delay_buffer(plant)  # the commands in flight of the drive's delay
    ring = command_ring(ctrl)  # the controller's copy of them: its estimator's input
    return _run_samples(obs, est, ctrl, plant, sig, out, fst, ez, ubuf, ring)


@njit(cache=True, error_model="numpy", _nrt=False)  # type: ignore[call-overload]  # numba-internal flag
def _run_samples(obs, est, ctrl, plant, sig, out, fst, ez, ubuf, ring):
    """The samples of :func:`run_loop`, with its work arrays ``fst``, ``ez``, ``ubuf`` and ``ring``.

    Compiled without numba's reference counting (``_nrt=False``): every array here is borrowed from
    :func:`run_loop`, which holds it for the whole call, and nothing is allocated. With it, each sample
    paid about 60 atomic increments and decrements of the arrays in the argument groups, bound afresh by
    every inlined step (the refcount pruning pass removes none of them), about 30 % of the kernel's
    time (benchmarks/RESULTS.md, issue 37). The arithmetic is the same, operation for operation.
    """
    x_ref, u_open, noise, quantization = sig.x_ref, sig.u_open, sig.noise, sig.quantization
    v_ref, w_ff = sig.v_ref, sig.w_ff
    K_plant, G_plant = plant.K, plant.G
    kappa = obs.kappa
    n_samples = x_ref.shape[0]
    h = obs.dt / plant.n_sub
    ps = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)  # x, v, w and the plant's pre-sliding branch
    ost = OBSERVER_STATE
    cst = CONTROLLER_STATE
    delay = plant.delay
    sc = paper_scalars(plant)
    for n in range(n_samples):
        x, v = ps[0], ps[1]
        # 1. measurement
        xm = measure(x, noise[n], quantization)
        # 2. the sampled controller
        k_true = 0.0
        if obs.schedule == SCHEDULE_TRUE:
            k_true = plant_stiffness(ps, fst, plant, sc, kappa)
        cst, ost, total, vh, fh, ff, k_now = controller_sample(cst, ost, ez, ring, n, x_ref[n], v_ref[n], w_ff[n],
                                                               u_open[n], xm, k_true, obs, est, ctrl)
        # 3. the drive's delay: apply the command of sample n - delay
        if delay > 0:
            slot = n % delay
            applied = ubuf[slot]
            ubuf[slot] = total
            total = applied
        u = K_plant * total - G_plant  # net driving force, load compensated
        # record
        out.x[n] = x
        out.x_meas[n] = xm
        out.v[n] = v
        out.f[n] = plant_friction(ps, fst, plant, sc)
        out.v_hat[n] = vh
        out.f_hat[n] = fh
        out.f_hat_filtered[n] = ff
        out.u[n] = u
        out.stiffness[n] = k_now
        if not (abs(x) < DIVERGED_X and abs(fh) < DIVERGED_F and abs(vh) < DIVERGED_F
                and abs(ff) < DIVERGED_F and abs(v) < DIVERGED_F):
            return n + 1
        # 4. the plant to (n + 1) dt with the input held
        ps = plant_interval(ps, u, fst, h, plant, sc)
    return n_samples


@njit(cache=True, error_model="numpy")
def delay_buffer(plant):
    """The commands in flight of the drive's delay before the first sample: ``max(delay, 1)`` times
    ``plant.delay_init`` [V] (the drive holds the load until the first computed command arrives).

    Parameters
    ----------
    plant : PlantArgs

    Examples
    --------
    >>> import obsdesign as od
    >>> from obsdesign.sim import prepare
    >>> plant = prepare(od.load_preset("vcm").override(delay_samples=2), "positioning").kernel_args()[3]
    >>> [round(float(u), 4) for u in delay_buffer(plant)]   # G / K = 5.27 / 3.28 V
    [1.6067, 1.6067]
    """
    return np.full(max(plant.delay, 1), plant.delay_init)


def empty_outputs(n: int) -> Outputs:
    """Output arrays for :func:`run_loop` (NaN where a diverged run stopped).

    Parameters
    ----------
    n : int
        Number of samples.
    """
    return Outputs(*(np.full(n, np.nan) for _ in OUTPUT_NAMES))
