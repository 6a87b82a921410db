"""Known-truth recovery of ``identify`` (issue 32): bias, coverage, Cramer-Rao bound and efficiency.

Usage: ``python benchmarks/bench_recovery.py [--draws 20] [--axes NAME,...] [--write]`` (``--axes`` a
comma-separated selection of :data:`AXES`). ``--write`` replaces the section ``## Known-truth recovery
(issue 32)`` of benchmarks/RESULTS.md.

The axes are those of ``tests/_axis_logs.py`` (:data:`AXES`, a shipped generator: a rigid axis with LuGre
friction and a Stribeck drop in a closed loop, sub-stepped, the position logged ``delay`` samples late
and rounded to the encoder, the current with white noise). Each axis is simulated once; each draw adds
new position and current noise and runs ``identify`` with its defaults (timing found, Stribeck ``auto``,
400 bootstrap replicates).

For each parameter: the mean relative bias and spread over the draws, the mean half-width of the
95 % interval, its coverage (the fraction of draws whose interval holds the truth), and the
Cramer-Rao bound of the log (:func:`segment_crb`) with the estimator's efficiency ``CRB / variance``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from _axis_logs import AXES, SUBSTEPS, axis_trace, noisy_log, simulate_axis  # noqa: E402

PARAMS = ("m", "sigma", "Cf", "offset", "Fs", "vs")
#: Segment length [s] of the Cramer-Rao bound.
SEGMENT = 0.1
HEADING = "## Known-truth recovery (issue 32)"


def _segment_kernel():
    from numba import njit

    @njit(cache=False)
    def positions(x0, v0, z0, u_sub, subs, dt, m, sigma, Cf, Fs, vs, offset, s0, s1):
        """Positions at the samples of a segment from its initial state, under the sub-step forces."""
        n = u_sub.size // subs
        out = np.empty(n)
        h = dt / subs
        xp, vp, z = x0, v0, z0
        for k in range(n):
            out[k] = xp
            for i in range(subs):
                u = u_sub[k * subs + i]
                g = Cf + (Fs - Cf) * np.exp(-(vp / vs) ** 2)
                if vp != 0.0:
                    ss = g * np.sign(vp) / s0
                    z_new = ss + (z - ss) * np.exp(-(s0 * abs(vp) / g) * h)
                else:
                    z_new = z
                zdot = (z_new - z) / h
                z = z_new
                acc = (u - (s0 * z + s1 * zdot + sigma * vp) - offset) / m
                xp = xp + h * vp + 0.5 * h * h * acc  # exact for the sub-step's constant acceleration
                vp = vp + h * acc
        return out

    return positions


_SEG = []


def segment_crb(spec: dict, clean: dict, names: tuple[str, ...], *, segment: float = SEGMENT,
                noise_var: float, step: float = 1e-6) -> dict:
    """Cramer-Rao bound [relative std] of ``names`` from the log's positions, cut into segments.

    Each segment of ``segment`` seconds starts from its own initial state (position, velocity, bristle
    state ``z``): nuisance parameters, projected out by the Schur complement of the Fisher information
    ``J^T J / noise_var`` (``J`` the sensitivity of the segment's sampled positions to the relative
    parameters and the states, by central differences of relative size ``step``). Held known: the
    force (as applied, without its noise), LuGre's ``sigma0``, ``sigma1``, and the parameters not in
    ``names``. White position noise of variance ``noise_var``.
    """
    if not _SEG:
        _SEG.append(_segment_kernel())
    run = _SEG[0]
    dt = 1.0 / spec["rate"]
    L = int(round(segment / dt))
    x, v, z = clean["state"]
    n = x.size
    theta = {k: float(spec[k]) for k in ("m", "sigma", "Cf", "Fs", "vs", "offset")}
    scale_state = (max(float(np.std(x)), 1e-9), max(float(np.std(v)), 1e-9), spec["Cf"] / spec["sigma0"])
    p = len(names)
    info = np.zeros((p, p))

    def sim(th, x0, v0, z0, u):
        return run(x0, v0, z0, u, SUBSTEPS, dt, th["m"], th["sigma"], th["Cf"], th["Fs"], th["vs"], th["offset"],
                   spec["sigma0"], spec["sigma1"])

    for k0 in range(0, n - L + 1, L):
        u = clean["u_sub"][k0 * SUBSTEPS:(k0 + L) * SUBSTEPS]
        state = [x[k0], v[k0], z[k0]]
        cols = []
        for name in names:
            h = step * abs(theta[name])
            up, dn = dict(theta), dict(theta)
            up[name] += h
            dn[name] -= h
            cols.append((sim(up, *state, u) - sim(dn, *state, u)) / (2 * step))  # d x / d ln(theta)
        for j in range(3):
            h = step * scale_state[j]
            sp, sm = list(state), list(state)
            sp[j] += h
            sm[j] -= h
            cols.append((sim(theta, *sp, u) - sim(theta, *sm, u)) / (2 * h) * scale_state[j])
        J = np.column_stack(cols)
        F = J.T @ J / noise_var
        Ftt, Ftn, Fnn = F[:p, :p], F[:p, p:], F[p:, p:]
        info += Ftt - Ftn @ np.linalg.pinv(Fnn, rcond=1e-12) @ Ftn.T
    cov = np.linalg.inv(info)
    return {name: math.sqrt(max(cov[i, i], 0.0)) for i, name in enumerate(names)}


def run_axis(name: str, draws: int) -> dict:
    from obsdesign.data import identify

    spec = AXES[name]
    t0 = time.perf_counter()
    clean = simulate_axis(spec)
    saturated = float(np.mean(np.abs(clean["force"]) >= 0.999 * spec["i_max"] * spec["gain"]))
    rows = []
    for seed in range(draws):
        trace = axis_trace(spec, noisy_log(spec, clean, seed))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                ident = identify(trace, seed=seed)
            except ValueError as e:
                rows.append({"refused": str(e)})
                continue
        rows.append({"values": {k: getattr(ident, k) for k in PARAMS}, "intervals": dict(ident.intervals),
                     "timing": (ident.input_timing, ident.delay_samples), "stribeck": ident.stribeck,
                     "at_bound": dict(ident.at_bound), "notices": ident.notices})
    names = ("m", "sigma", "Cf", "offset") + (("Fs", "vs") if spec["Fs"] != spec["Cf"] else ())
    noise_var = spec["noise"] ** 2 + spec["step"] ** 2 / 12.0
    crb = segment_crb(spec, clean, names, noise_var=noise_var)
    crb4 = segment_crb(spec, clean, ("m", "sigma", "Cf", "offset"), noise_var=noise_var) if len(names) > 4 else crb
    return {"name": name, "spec": spec, "rows": rows, "crb": crb, "crb4": crb4, "saturated": saturated,
            "seconds": time.perf_counter() - t0}


def table(results: list[dict], draws: int) -> str:
    out = ["| axis | parameter | truth | bias | spread (std) | 95 % half-width | coverage | point in interval | "
           "CRB (std) | efficiency CRB/var |", "|---|---|---|---|---|---|---|---|---|---|"]
    notes = []
    for res in results:
        spec, rows = res["spec"], [r for r in res["rows"] if "values" in r]
        refused = len(res["rows"]) - len(rows)
        right = sum(r["timing"] == (spec["timing"], spec["delay"]) for r in rows)
        kept = sum(r["stribeck"] for r in rows)
        notes.append(f"- `{res['name']}`: {spec['kind']}, {spec['rate'] / 1e3:g} kHz, input {spec['timing']}, "
                     f"delay {spec['delay']}, {spec['moves']} moves ({100 * res['saturated']:.1f} % of the samples "
                     f"at the current limit), Fs/Cf {spec['Fs'] / spec['Cf']:.2g}: timing and delay found right in "
                     f"{right} of {len(rows)}; Stribeck kept in {kept}; refused in {refused}; {res['seconds']:.0f} s")
        for k in PARAMS:
            truth = spec[k]
            vals = np.array([r["values"][k] for r in rows if r["values"][k] is not None], dtype=float)
            if vals.size == 0:
                continue
            rel = vals / truth - 1.0
            ivs = [r["intervals"][k] for r in rows if k in r["intervals"]]
            if ivs:
                cover = np.mean([lo <= truth <= hi for lo, hi in ivs])
                inside = np.mean([lo <= r["values"][k] <= hi for r in rows if k in r["intervals"]
                                  for lo, hi in [r["intervals"][k]]])
                half = np.mean([(hi - lo) / 2 / abs(truth) for lo, hi in ivs])
                cov_s, ins_s, half_s = f"{cover:.2f}", f"{inside:.2f}", f"{100 * half:.3g} %"
            else:
                cov_s, ins_s, half_s = "no interval", "-", "-"
            crb = res["crb"].get(k)
            var = float(np.var(rel, ddof=1)) if rel.size > 1 else float("nan")
            eff = f"{crb**2 / var:.2g}" if crb is not None and var > 0 else "-"
            crb_s = f"{100 * crb:.3g} %" if crb is not None else "-"
            out.append(f"| {res['name']} | {k} | {truth:.4g} | {100 * np.mean(rel):+.3g} % | "
                       f"{100 * np.std(rel, ddof=1):.3g} % | {half_s} | {cov_s} ({vals.size}) | {ins_s} | {crb_s} | "
                       f"{eff} |")
    return "\n".join(out + [""] + notes)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=20)
    ap.add_argument("--axes", default=",".join(AXES))
    ap.add_argument("--write", action="store_true")
    args = ap.parse_args(argv)
    results = []
    for name in args.axes.split(","):
        res = run_axis(name, args.draws)
        results.append(res)
        print(f"{name}: {res['seconds']:.0f} s", file=sys.stderr)
    text = table(results, args.draws)
    body = (f"{HEADING}\n\n`python benchmarks/bench_recovery.py --draws {args.draws}`, "
            f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}. Each axis simulated once (tests/_axis_logs.py), "
            f"{args.draws} noise draws, `identify` with its defaults. Coverage: the fraction of draws whose 95 % "
            "interval holds the truth (draws in brackets); point in interval: the fraction whose interval holds its "
            f"own estimate. CRB: the Cramer-Rao bound of the log's positions, segments of L = {SEGMENT:g} s each with "
            "its own initial position, velocity and bristle state (projected out, Schur complement); held known: "
            "the applied force without its noise, LuGre's sigma0 and sigma1 (and Fs, vs on axes without a Stribeck "
            "drop); white position noise of the log's RMS and the encoder's q^2/12. Efficiency = CRB^2 / the variance "
            "over the draws (relative).\n\n" + text + "\n")
    print(body)
    if args.write:
        path = HERE / "RESULTS.md"
        old = path.read_text(encoding="utf-8")
        if HEADING in old:
            start = old.index(HEADING)
            nxt = old.find("\n## ", start + len(HEADING))
            new = old[:start] + body + ("\n" + old[nxt + 1:] if nxt >= 0 else "")
        else:
            new = old.rstrip("\n") + "\n\n" + body
        path.write_text(new, encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
