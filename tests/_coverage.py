"""Monte Carlo coverage of identify's intervals on simulated records (used by a slow test).

The axis of the fidelity review's synthetic check (m 95 kg, sigma 200 N s/m, Cf 20 N, load -3 N,
1 kHz, 25 s): the package's simulator with the paper's friction at a pre-sliding distance of
0.1 um (s = 1e7 1/m, so gross sliding is Coulomb + viscous), white position noise of RMS eta.
Open loop: a band-limited force (RMS 150 N up to 5 Hz); closed loop: the PID tracking a chirp of
peak speed 0.3 m/s with the noise fed back.
"""

from __future__ import annotations

import numpy as np

TRUTH = {"m": 95.0, "sigma": 200.0, "Cf": 20.0}
G = -3.0


def record(loop: str, eta: float, seed: int):
    import obsdesign as od
    from obsdesign.data import Trace
    from obsdesign.sim import Chirp, Excitation

    cfg = od.load_preset("vcm").override(m=95.0, sigma=200.0, Cf=20.0, s=1e7, kappa=1e6, G=G, K=35.0, dt=1e-3,
                                         noise_rms=eta, noise_bandwidth=500.0, quantization=0.0, u_max=1e3,
                                         omega_co=2 * np.pi * 20)
    scenario = Excitation(force_rms=150.0, bandwidth=5.0) if loop == "open" else Chirp(f0=0.05, f1=2.0,
                                                                                       peak_velocity=0.3)
    res = od.simulate(cfg, scenario, duration=25.0, seed=seed)
    return Trace(t=res.t, position=res.x_meas, force=res.u + G, sample_time=1e-3)


def coverage(loop: str, eta: float, seeds: int = 40, n_boot: int = 400) -> dict:
    """Fraction of seeds whose 95 % interval holds the truth, per parameter, and the mean relative bias."""
    from obsdesign.data import identify

    hits = {k: 0 for k in TRUTH}
    bias = {k: [] for k in TRUTH}
    for seed in range(seeds):
        ident = identify(record(loop, eta, seed), stribeck="off", n_boot=n_boot, seed=seed, input_timing="hold")
        for k, truth in TRUTH.items():
            lo, hi = ident.intervals[k]
            hits[k] += lo <= truth <= hi
            bias[k].append(getattr(ident, k) / truth - 1.0)
    return {k: (hits[k] / seeds, float(np.mean(bias[k]))) for k in TRUTH}


if __name__ == "__main__":
    import sys

    loop, eta = sys.argv[1], float(sys.argv[2])
    print(loop, eta, coverage(loop, eta, seeds=int(sys.argv[3]) if len(sys.argv) > 3 else 40))
