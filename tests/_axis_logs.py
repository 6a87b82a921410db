"""Synthetic axis logs for the identification tests: a known inverse model along an analytic path.

The path is a sum of sines (exact velocity and acceleration), the force the model
``m a + sigma v + Cf sign(v) + (Fs - Cf) sign(v) exp(-(v/vs)^2) + offset`` plus white force noise,
the position plus white noise and 0.5 um encoder steps. ``slow``: speeds up to 22 mm/s with
vs = 2 mm/s (the Stribeck drop dominates the friction); ``fast``: up to 0.19 m/s.
"""

from __future__ import annotations

import numpy as np

TRUTH = {"m": 1.8, "sigma": 12.0, "Cf": 2.4, "offset": 0.3, "Fs": 3.0, "vs": 2e-3}
DT = 5e-4
GAIN = 6.5  # N/A


def axis_log(kind: str, *, seed: int = 0, noise: float = 2e-7, duration: float = 24.0) -> dict:
    """Columns ``t`` [s], ``x`` [m], ``i`` [A] of a synthetic log (``kind`` 'slow' or 'fast')."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(duration / DT))) * DT
    peak = {"slow": 0.022, "fast": 0.19}[kind]
    freqs = np.array([0.15, 0.41, 0.93, 1.7])
    amps = np.array([1.0, 0.6, 0.35, 0.2])
    phases = rng.uniform(0, 2 * np.pi, freqs.size)
    w = 2 * np.pi * freqs
    v_raw = (amps[:, None] * w[:, None] * np.cos(w[:, None] * t + phases[:, None])).sum(axis=0)
    k = peak / np.max(np.abs(v_raw))
    x = k * (amps[:, None] * np.sin(w[:, None] * t + phases[:, None])).sum(axis=0)
    v = k * v_raw
    a = -k * (amps[:, None] * w[:, None] ** 2 * np.sin(w[:, None] * t + phases[:, None])).sum(axis=0)
    p = TRUTH
    u = (p["m"] * a + p["sigma"] * v + p["Cf"] * np.sign(v)
         + (p["Fs"] - p["Cf"]) * np.sign(v) * np.exp(-((v / p["vs"]) ** 2)) + p["offset"])
    u = u + rng.normal(0.0, 0.02, t.size)
    x_meas = np.round((x + rng.normal(0.0, noise, t.size)) / 5e-7) * 5e-7
    return {"t": t, "x": x_meas, "i": u / GAIN}


def write_mm_ms(path, log: dict) -> None:
    """The log as ``time_ms;pos_mm;i_A`` with a ``#`` comment line above the header."""
    rows = np.column_stack([log["t"] * 1e3, log["x"] * 1e3, log["i"]])
    with open(path, "w") as f:
        f.write("# synthetic axis log: time in ms, position in mm, motor current in A\n")
        np.savetxt(f, rows, delimiter=";", header="time_ms;pos_mm;i_A", comments="", fmt="%.17g")


def write_si(path, log: dict) -> None:
    """The log as ``t,x,i`` (s, m, A)."""
    np.savetxt(path, np.column_stack([log["t"], log["x"], log["i"]]), delimiter=",", header="t,x,i", comments="",
               fmt="%.17g")


# -- simulated axes: a rigid axis with LuGre friction (and a Stribeck drop) in a closed loop ------------------

#: The axes of the recovery benchmark (benchmarks/bench_recovery.py) and of the timing tests. Each names the
#: plant (m, sigma, Cf, Fs, vs, offset; LuGre sigma0, sigma1), the log (rate, position delay in samples, input
#: timing ``hold`` (a sampled PD, zero-order hold) or ``sample`` (an analog PD, the current logged as it acts),
#: position noise RMS, encoder step, current noise, torque/force constant), the moves (``smooth``: a sum of
#: sines, ``peak`` its largest speed; ``saturating``: point-to-point steps of about ``peak`` that drive the amplifier into its limit ``i_max``).
AXES = {
    "linear-1k-hold-d0": dict(kind="linear", rate=1e3, delay=0, timing="hold", moves="smooth", m=1.8, sigma=12.0,
                              Cf=2.4, Fs=2.4, vs=2e-3, offset=0.3, sigma0=1e6, sigma1=400.0, gain=6.5, i_max=20.0,
                              noise=2e-7, step=5e-7, i_noise=2e-3, peak=0.2, duration=20.0),
    "linear-1k-sample-d1": dict(kind="linear", rate=1e3, delay=1, timing="sample", moves="smooth", m=1.8,
                                sigma=12.0, Cf=2.4, Fs=2.4, vs=2e-3, offset=0.3, sigma0=1e6, sigma1=400.0, gain=6.5,
                                i_max=20.0, noise=2e-7, step=5e-7, i_noise=2e-3, peak=0.2, duration=20.0),
    "rotary-4k-hold-d1-stribeck": dict(kind="rotary", rate=4e3, delay=1, timing="hold", moves="smooth", m=2.5e-3,
                                       sigma=1e-3, Cf=0.05, Fs=0.08, vs=0.5, offset=0.01, sigma0=2e5, sigma1=3.0,
                                       gain=0.1, i_max=20.0, noise=3e-6, step=2 * np.pi / 2**20, i_noise=2e-3,
                                       peak=20.0, duration=12.0),
    "rotary-4k-hold-d2": dict(kind="rotary", rate=4e3, delay=2, timing="hold", moves="smooth", m=2.5e-3, sigma=1e-3,
                              Cf=0.05, Fs=0.05, vs=0.5, offset=0.01, sigma0=2e5, sigma1=3.0, gain=0.1, i_max=20.0,
                              noise=3e-6, step=2 * np.pi / 2**20, i_noise=2e-3, peak=20.0, duration=12.0),
    "rotary-4k-hold-d1-saturating": dict(kind="rotary", rate=4e3, delay=1, timing="hold", moves="saturating",
                                         m=2.5e-3, sigma=1e-3, Cf=0.05, Fs=0.05, vs=0.5, offset=0.01, sigma0=2e5,
                                         sigma1=3.0, gain=0.1, i_max=3.3, noise=3e-6, step=2 * np.pi / 2**20,
                                         i_noise=2e-3, peak=0.4, duration=12.0),
}
#: Sub-steps of the plant's integration per sample.
SUBSTEPS = 16
#: Sub-steps of the logs the segment output-error refinement is benchmarked on (see :func:`simulate_axis`).
FINE_SUBSTEPS = 128


def _reference(spec: dict, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position, velocity and acceleration of the reference at the times ``t``."""
    peak = spec["peak"]
    if spec["moves"] == "smooth":
        freqs = np.array([0.23, 0.61, 1.37, 2.9])
        amps = np.array([1.0, 0.5, 0.3, 0.15])
        phases = np.array([0.3, 1.1, 2.0, 4.2])
        w = 2 * np.pi * freqs
        arg = w[:, None] * t + phases[:, None]
        scale = peak / float(np.sum(amps * w))
        return (scale * (amps[:, None] * np.sin(arg)).sum(0), scale * (amps[:, None] * w[:, None] * np.cos(arg)).sum(0),
                -scale * (amps[:, None] * w[:, None] ** 2 * np.sin(arg)).sum(0))
    # point-to-point: minimum-jerk moves of 0.2 s between levels near +-peak, a 0.2 s dwell after each; their
    # peak acceleration 5.77 * travel / 0.2^2 is above what the amplifier gives, so the PD saturates
    period, move = 0.4, 0.2
    k = np.floor(t / period).astype(int)
    level = peak * np.where(k % 2 == 0, 1.0, -1.0) * (1.0 + 0.2 * np.sin(1.7 * k))
    start = np.concatenate([[0.0], level[:-1]])
    start = peak * np.where((k - 1) % 2 == 0, 1.0, -1.0) * (1.0 + 0.2 * np.sin(1.7 * (k - 1)))
    tau = np.clip((t - k * period) / move, 0.0, 1.0)
    d = level - start
    pos = start + d * (10 * tau**3 - 15 * tau**4 + 6 * tau**5)
    vel = d * (30 * tau**2 - 60 * tau**3 + 30 * tau**4) / move
    acc = d * (60 * tau - 180 * tau**2 + 120 * tau**3) / move**2
    return pos, vel, acc


def _simulate_kernel():
    from numba import njit

    @njit(cache=False)
    def run(r, rv, ra, n, dt, subs, hold, delay, m, sigma, Cf, Fs, vs, offset, s0, s1, kp, kd, u_max, step):
        x = np.zeros(n)
        vel = np.zeros(n)
        zs = np.zeros(n)
        u_sub = np.zeros(n * subs)
        u_log = np.zeros(n)
        h = dt / subs
        xp, vp, z = r[0], 0.0, 0.0
        y_prev = xp
        u_hold = 0.0
        for k in range(n):
            x[k] = xp
            vel[k] = vp
            zs[k] = z
            # the sampled controller sees the encoder, ``delay`` samples late
            j = k - delay if k >= delay else 0
            y = np.round(x[j] / step) * step
            if hold:
                u_hold = m * ra[k] + kp * (r[k] - y) + kd * (rv[k] - (y - y_prev) / dt)
                u_hold = min(max(u_hold, -u_max), u_max)
                y_prev = y
                u_log[k] = u_hold
            for i in range(subs):
                if hold:
                    u = u_hold
                else:  # an analog PD on the true state, the reference interpolated
                    tt = (i * h) / dt
                    kk = min(k + 1, n - 1)
                    rr = r[k] + tt * (r[kk] - r[k])
                    rrv = rv[k] + tt * (rv[kk] - rv[k])
                    rra = ra[k] + tt * (ra[kk] - ra[k])
                    u = m * rra + kp * (rr - xp) + kd * (rrv - vp)
                    u = min(max(u, -u_max), u_max)
                    if i == 0:
                        u_log[k] = u
                u_sub[k * subs + i] = u
                g = Cf + (Fs - Cf) * np.exp(-(vp / vs) ** 2)
                if vp != 0.0:
                    ss = g * np.sign(vp) / s0
                    rate = s0 * abs(vp) / g
                    z_new = ss + (z - ss) * np.exp(-rate * h)
                else:
                    z_new = z
                zdot = (z_new - z) / h
                z = z_new
                f = s0 * z + s1 * zdot + sigma * vp
                acc = (u - f - offset) / m
                xp = xp + h * vp + 0.5 * h * h * acc  # exact for the sub-step's constant acceleration
                vp = vp + h * acc
        return x, u_log, vel, zs, u_sub

    return run


_KERNEL = []


def simulate_axis(spec: dict, reference: tuple | None = None, *, substeps: int = SUBSTEPS) -> dict:
    """The noise-free log of an axis of :data:`AXES`: ``t``, ``x`` (delayed, not quantized), ``force`` [N or N m].

    ``reference``: ``(x_ref, v_ref, a_ref)`` per sample to track instead of the spec's ``moves`` (an
    identification experiment, :func:`obsdesign.data.design_experiment`); the duration is then theirs.

    Also ``state``: the true position, velocity and bristle state ``z`` at each sample (not delayed), and
    ``u_sub``: the force applied in each sub-step (for the Cramer-Rao bound of benchmarks/bench_recovery.py),
    and ``substeps``.

    ``substeps``: sub-steps a sample. The integration is first order: at the default :data:`SUBSTEPS` a
    0.1 s segment of ``linear-1k-hold-d0`` replayed from its true state differs from the same plant
    integrated with 128 sub-steps by 4.4e-7 m (median of the segments' largest difference; 2.2 times the
    position noise), on ``rotary-4k-hold-d2`` by 8.5e-7 rad (0.3 times). An estimator that simulates the
    continuous plant (the segment output-error refinement) sees that as model error; its benchmark rows use
    :data:`FINE_SUBSTEPS`.

    The plant is ``m a = F - (sigma0 z + sigma1 dz/dt + sigma v) - offset`` with LuGre's
    ``dz/dt = v - sigma0 |v| z / g(v)``, ``g = Cf + (Fs - Cf) exp(-(v/vs)^2)``, integrated with
    :data:`SUBSTEPS` sub-steps a sample (``z`` by its exact exponential update at constant ``v``).
    """
    if not _KERNEL:
        _KERNEL.append(_simulate_kernel())
    dt = 1.0 / spec["rate"]
    n = int(round(spec["duration"] / dt)) if reference is None else len(reference[0])
    t = np.arange(n) * dt
    r, rv, ra = _reference(spec, t) if reference is None else (np.asarray(a, dtype=float) for a in reference)
    m = spec["m"]
    wc = 2 * np.pi * spec["rate"] / 40.0  # a crossover a fortieth of the rate
    kp, kd = m * wc**2 / 2.0, 1.4 * m * wc / 2.0
    x, u, vel, z, u_sub = _KERNEL[0](r, rv, ra, n, dt, substeps, spec["timing"] == "hold", spec["delay"], m, spec["sigma"],
                      spec["Cf"], spec["Fs"], spec["vs"], spec["offset"], spec["sigma0"], spec["sigma1"], kp, kd,
                      spec["i_max"] * spec["gain"], spec["step"])
    d = spec["delay"]
    x_log = np.concatenate([np.full(d, x[0]), x[:n - d]]) if d else x
    return {"t": t, "x": x_log, "force": u, "state": (x, vel, z), "u_sub": u_sub, "substeps": substeps}


def noisy_log(spec: dict, clean: dict, seed: int) -> dict:
    """One noise draw: position noise then the encoder's rounding, current noise; ``i`` in A."""
    rng = np.random.default_rng(seed)
    x = np.round((clean["x"] + rng.normal(0.0, spec["noise"], clean["x"].size)) / spec["step"]) * spec["step"]
    i = clean["force"] / spec["gain"] + rng.normal(0.0, spec["i_noise"], clean["x"].size)
    return {"t": clean["t"], "x": x, "i": i}


def axis_trace(spec: dict, log: dict):
    """The :class:`~obsdesign.data.Trace` of a log of :func:`noisy_log` (rad and N m for a rotary axis)."""
    from obsdesign.data import Trace
    from obsdesign.data.units import Units

    rotary = spec["kind"] == "rotary"
    units = Units(position="rad" if rotary else "m", input="A", rotary=rotary)
    return Trace(t=log["t"], position=log["x"], force=log["i"] * spec["gain"], sample_time=1.0 / spec["rate"],
                 input_gain=spec["gain"], units=units, source="simulated")


def pure_inertia_log(*, L: int, rate: float = 1e3, m: float = 0.5, offset: float = 0.3, seed: int = 2) -> dict:
    """A pure inertia under a held random force, no friction, four segments of ``L`` samples: the closed-form
    reference of the segment Cramer-Rao bound (benchmarks/bench_recovery.segment_crb). Returns the axis ``spec``,
    the ``clean`` log in simulate_axis's layout, the acceleration ``acc`` and ``dt``, ``n``."""
    spec = dict(rate=rate, m=m, sigma=0.0, Cf=1e-9, Fs=1e-9, vs=1.0, offset=offset, sigma0=1e3, sigma1=0.0)
    rng = np.random.default_rng(seed)
    n = 4 * L
    u = np.repeat(rng.normal(0.0, 1.0, n // 10), 10)
    dt = 1.0 / rate
    acc = (u - offset) / m
    v = np.concatenate([[0.0], np.cumsum(acc) * dt])[:-1]
    x = np.concatenate([[0.0], np.cumsum(v * dt + 0.5 * acc * dt**2)])[:-1]
    clean = {"state": (x, v, np.zeros(n)), "u_sub": np.repeat(u, SUBSTEPS)}
    return {"spec": spec, "clean": clean, "acc": acc, "dt": dt, "n": n}
