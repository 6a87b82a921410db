"""Known-truth recovery of ``identify`` (issue 32): bias, coverage, Cramer-Rao bound and efficiency.

Usage: ``python benchmarks/bench_recovery.py [--draws 20] [--axes NAME,...] [--write]`` (``--axes`` a
comma-separated selection of :data:`AXES`). ``--write`` replaces the section ``## Known-truth recovery
(issue 32)`` of benchmarks/RESULTS.md (its ``###`` subsections kept).

``--refine segment [--segment L] [--cache DIR]``: after ``identify``, each draw runs the segment
output-error refinement (:mod:`obsdesign.data.oe_segments`) and the table gives its bias, spread and
coverage, and its efficiency against three bounds of the same L (:data:`REFINE_BOUNDS`); ``--write``
replaces the subsection ``### Segment output-error refinement (issue 32)``. A draw takes minutes:
``--cache`` keeps each one and a rerun reuses it.

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

from _axis_logs import AXES, FINE_SUBSTEPS, SUBSTEPS, axis_trace, noisy_log, simulate_axis  # noqa: E402

from obsdesign.data.timing import TIMING_MARGIN  # noqa: E402

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
                noise_var: float, step: float = 1e-6, force_var: float = 0.0, hold: bool = True) -> dict:
    """Cramer-Rao bound [relative std] of ``names`` from the log's positions, cut into segments.

    Each segment of ``segment`` seconds starts from its own initial state (position, velocity, bristle
    state ``z``): nuisance parameters, projected out by the Schur complement of the Fisher information
    ``J^T J / noise_var`` (``J`` the sensitivity of the segment's sampled positions to the relative
    parameters and the states, by central differences of relative size ``step``). Held known: the
    force (as applied, without its noise), LuGre's ``sigma0``, ``sigma1``, and the parameters not in
    ``names`` (``names`` may include ``sigma0`` and ``sigma1``: then they are not held). White position
    noise of variance ``noise_var``.

    ``force_var`` > 0: the estimator simulates the *logged* force, which carries white noise of that
    variance [N^2 or (N m)^2] per sample. Linearized, a segment's residual at the truth is then
    ``v - G e`` (``G`` the sensitivity of its positions to the force of each sample, by central
    differences; ``hold``: the sample's force held over it, else interpolated to the next sample as
    :mod:`obsdesign.data.oe_segments` does), covariance ``noise_var I + force_var G G^T``, and the
    information is ``J^T Sigma^-1 J``: the bound of an estimator that knows the noise's structure.
    """
    if not _SEG:
        _SEG.append(_segment_kernel())
    run = _SEG[0]
    dt = 1.0 / spec["rate"]
    L = int(round(segment / dt))
    x, v, z = clean["state"]
    n = x.size
    theta = {k: float(spec[k]) for k in ("m", "sigma", "Cf", "Fs", "vs", "offset", "sigma0", "sigma1")}
    scale_state = (max(float(np.std(x)), 1e-9), max(float(np.std(v)), 1e-9), spec["Cf"] / spec["sigma0"])
    p = len(names)
    info = np.zeros((p, p))

    def sim(th, x0, v0, z0, u):
        return run(x0, v0, z0, u, SUBSTEPS, dt, th["m"], th["sigma"], th["Cf"], th["Fs"], th["vs"], th["offset"],
                   th["sigma0"], th["sigma1"])

    # the weight of sample j's logged force in each sub-step of samples j - 1 and j (interpolated) or j (held)
    frac = (np.arange(SUBSTEPS) + 0.5) / SUBSTEPS

    # the bound's own integration: SUBSTEPS a sample (a finer log's sub-step forces taken every k-th)
    every = max(int(clean.get("substeps", SUBSTEPS)) // SUBSTEPS, 1)
    u_all = clean["u_sub"][::every]
    hu = step * max(float(np.max(np.abs(u_all))), 1e-300)
    for k0 in range(0, n - L + 1, L):
        u = u_all[k0 * SUBSTEPS:(k0 + L) * SUBSTEPS]
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
        if force_var > 0.0:
            G = np.empty((L, L))
            for j in range(L):
                du = np.zeros(u.size)
                if hold:
                    du[j * SUBSTEPS:(j + 1) * SUBSTEPS] = hu
                else:
                    du[j * SUBSTEPS:(j + 1) * SUBSTEPS] = hu * (1.0 - frac)
                    if j > 0:
                        du[(j - 1) * SUBSTEPS:j * SUBSTEPS] = hu * frac
                G[:, j] = (sim(theta, *state, u + du) - sim(theta, *state, u - du)) / (2 * hu)
            W = np.linalg.inv(noise_var * np.eye(L) + force_var * G @ G.T)
            F = J.T @ W @ J
        else:
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


#: Heading of the refinement's subsection (``--refine segment``), inside :data:`HEADING`'s section.
REFINE_HEADING = "### Segment output-error refinement (issue 32)"
#: The bounds the refinement is compared with: label -> (bristle parameters free, the logged force's noise in).
REFINE_BOUNDS = {"A": (False, False), "B": (True, False), "C": (True, True)}


def refine_draw(spec: dict, clean: dict, seed: int, *, segment: float = SEGMENT) -> dict:
    """One noise draw: ``identify`` (defaults), then the segment output-error refinement from it
    (:func:`~obsdesign.data.oe_segment_refine.refine_segments`, what ``refine(..., model='lugre')`` runs; the
    bristle parameters fitted, not profiled), JSON-ready. When the refinement says another reading of the
    log's timing fits better, both are rerun with it, as its line tells the user (``rerun``)."""
    from obsdesign.data import identify
    from obsdesign.data.oe_segment_refine import refine_segments

    trace = axis_trace(spec, noisy_log(spec, clean, seed))
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            ident = identify(trace, seed=seed)
        except ValueError as e:
            return {"seed": seed, "refused": f"identify: {e}"}
    t1 = time.perf_counter()
    rerun = ""
    try:
        ref = refine_segments(trace, ident, parameters=(), segment=segment)  # no profile: none asked for
        better = {k: v for k, v in ref.fit.alternatives.items() if v < -TIMING_MARGIN}
        if ref.warning and better:  # as its line says: rerun with the timing that fits better
            rerun = min(better, key=better.get)
            words = rerun.split()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ident = identify(trace, seed=seed, input_timing=words[1], delay_samples=int(words[3]))
            ref = refine_segments(trace, ident, parameters=(), segment=segment)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as e:
        return {"seed": seed, "refused": f"refine: {e}"}
    f = ref.fit
    return {"seed": seed, "timing": [ident.input_timing, int(ident.delay_samples)], "identify_s": t1 - t0,
            "refine_s": time.perf_counter() - t1, "evaluations": f.evaluations, "rms_over_noise": f.rms / f.noise,
            "warning": ref.warning, "rerun": rerun, "alternatives": dict(f.alternatives),
            "segment_samples": f.segment_samples, "segments": f.segments, "substeps": f.substeps,
            "params": {n: {"value": f.values[n], "std": f.std[n], "low": f.intervals[n][0],
                           "high": f.intervals[n][1], "identifiable": bool(f.identifiable[n])} for n in f.names}}


def run_axis_refine(name: str, draws: int, *, cache: Path | None = None, segment: float = SEGMENT,
                    cached_only: bool = False) -> dict:
    """The segment output-error refinement over ``draws`` noise draws of axis ``name`` and its bounds
    (:data:`REFINE_BOUNDS`); with ``cache`` each draw is kept in ``cache/<axis>_<seed>.json`` and the bounds in
    ``cache/<axis>_bounds_L<segment>.json``, and reused; ``cached_only``: only the draws in the cache (the
    table names their seeds)."""
    import json

    spec = AXES[name]
    t0 = time.perf_counter()
    clean = simulate_axis(spec, substeps=FINE_SUBSTEPS)
    rows = []
    for seed in range(draws):
        path = cache / f"{name}_{seed}.json" if cache is not None else None
        if path is not None and path.exists():
            rows.append(json.loads(path.read_text(encoding="utf-8")))
            continue
        if cached_only:
            continue
        row = refine_draw(spec, clean, seed, segment=segment)
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(".tmp")
            tmp.write_text(json.dumps(row, default=float), encoding="utf-8")
            tmp.replace(path)
        rows.append(row)
        print(f"  {name} draw {seed}: {row.get('refine_s', 0):.0f} s", file=sys.stderr, flush=True)
    base = ("m", "sigma", "Cf", "offset") + (("Fs", "vs") if spec["Fs"] != spec["Cf"] else ())
    noise_var = spec["noise"] ** 2 + spec["step"] ** 2 / 12.0
    force_var = (spec["i_noise"] * spec["gain"]) ** 2
    crbs = {}
    saved = cache / f"{name}_bounds_L{segment:g}.json" if cache is not None else None
    if saved is not None and saved.exists():
        crbs = json.loads(saved.read_text(encoding="utf-8"))
    for label, (bristle, force) in REFINE_BOUNDS.items():
        if label not in crbs:
            crbs[label] = segment_crb(spec, clean, base + (("sigma0", "sigma1") if bristle else ()),
                                      segment=segment, noise_var=noise_var, force_var=force_var if force else 0.0,
                                      hold=spec["timing"] == "hold")
    if saved is not None:
        saved.write_text(json.dumps(crbs), encoding="utf-8")
    return {"name": name, "spec": spec, "rows": rows, "crbs": crbs, "segment": segment,
            "seconds": time.perf_counter() - t0}


def refine_table(results: list[dict]) -> str:
    """Bias, spread, interval width and coverage of the refinement, its efficiency against each bound."""
    seg = results[0]["segment"] if results else SEGMENT
    out = ["| axis | parameter | truth | bias | spread (std) | mean reported std | 95 % half-width | coverage | "
           "point in interval | CRB A / eff. A | CRB B / eff. B | CRB C / eff. C |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    notes = []
    for res in results:
        spec = res["spec"]
        rows = [r for r in res["rows"] if "params" in r]
        refused = [r for r in res["rows"] if "refused" in r]
        right = sum(tuple(r["timing"]) == (spec["timing"], spec["delay"]) for r in rows)
        secs = [r["refine_s"] for r in rows]
        rms = [r["rms_over_noise"] for r in rows]
        warned = sum(bool(r["warning"]) for r in rows)
        reran = sum(bool(r.get("rerun")) for r in rows)
        notes.append(f"- `{res['name']}`: {len(rows)} draws (seeds {', '.join(str(r['seed']) for r in rows)}), "
                     f"refused {len(refused)}; timing right in {right} (in {reran} after the rerun the refine's "
                     f"timing check asked for); a timing warning left in {warned}; "
                     f"L = {rows[0]['segment_samples'] if rows else '-'} samples, {rows[0]['segments'] if rows else '-'} "
                     f"segments; RMS residual {min(rms, default=0):.2f} to {max(rms, default=0):.2f} x the noise; "
                     f"refine {np.median(secs) if secs else 0:.0f} s a draw (median; {min(secs, default=0):.0f} to "
                     f"{max(secs, default=0):.0f} s), {int(np.median([r['evaluations'] for r in rows])) if rows else 0} "
                     "simulations")
        for k in ("m", "sigma", "Cf", "offset", "Fs", "vs", "sigma0", "sigma1"):
            got = [r["params"][k] for r in rows if k in r["params"]]
            if not got:
                continue
            truth = spec[k]
            vals = np.array([g["value"] for g in got])
            rel = vals / truth - 1.0
            cover = np.mean([g["low"] <= truth <= g["high"] for g in got])
            inside = np.mean([g["low"] <= g["value"] <= g["high"] for g in got])
            half = np.mean([(g["high"] - g["low"]) / 2 / abs(truth) for g in got])
            sd = np.mean([g["std"] / abs(truth) for g in got])
            var = float(np.var(rel, ddof=1)) if rel.size > 1 else float("nan")
            cells = []
            for label in REFINE_BOUNDS:
                crb = res["crbs"][label].get(k)
                cells.append("-" if crb is None else f"{100 * crb:.3g} % / {crb**2 / var:.2g}" if var > 0 else
                             f"{100 * crb:.3g} % / -")
            out.append(f"| {res['name']} | {k} | {truth:.4g} | {100 * np.mean(rel):+.3g} % | "
                       f"{100 * np.std(rel, ddof=1):.3g} % | {100 * sd:.3g} % | {100 * half:.3g} % | "
                       f"{cover:.2f} ({vals.size}) | {inside:.2f} | " + " | ".join(cells) + " |")
    legend = (f"Bounds (each of the log's positions, segments of L = {seg:g} s, each with its own initial position, "
              "velocity and bristle state projected out; white position noise of the log's RMS and q^2/12): "
              "**A** held known: the applied force without its noise, sigma0 and sigma1 (and Fs, vs on axes without "
              "a Stribeck drop): the bound of the table above. **B** as A, sigma0 and sigma1 not held (the "
              "refinement fits them). **C** as B, and the force the estimator knows is the *logged* one, with the "
              "current's white noise (the linearized response to it in each segment's noise covariance). "
              "Efficiency = CRB^2 / the variance over the draws (relative).")
    return "\n".join([legend, ""] + out + [""] + notes)


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
    ap.add_argument("--refine", choices=("segment",), default=None,
                    help="run `refine` by segment output error after `identify` on each draw and tabulate it")
    ap.add_argument("--segment", type=float, default=SEGMENT, help="L [s] of the refinement and its bounds")
    ap.add_argument("--cache", type=Path, default=None, help="keep each refined draw here and reuse it")
    ap.add_argument("--cached-only", action="store_true", help="with --cache: tabulate the draws kept there only")
    args = ap.parse_args(argv)
    if args.refine:
        return _main_refine(args)
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
        _write_section(HEADING, body, ("\n### ", "\n## "))
    return 0


def _write_section(heading: str, body: str, ends: tuple[str, ...]) -> None:
    """Replace ``heading``'s text in RESULTS.md up to the first of ``ends`` (or append it to the recovery
    section, or the file)."""
    path = HERE / "RESULTS.md"
    old = path.read_text(encoding="utf-8")
    if heading in old:
        start = old.index(heading)
        stops = [i for i in (old.find(e, start + len(heading)) for e in ends) if i >= 0]
        nxt = min(stops) if stops else -1
        new = old[:start] + body + ("\n" + old[nxt + 1:] if nxt >= 0 else "")
    elif heading != HEADING and HEADING in old:
        nxt = old.find("\n## ", old.index(HEADING) + len(HEADING))
        new = (old[:nxt].rstrip("\n") + "\n\n" + body + "\n" + old[nxt + 1:]) if nxt >= 0 else \
            old.rstrip("\n") + "\n\n" + body
    else:
        new = old.rstrip("\n") + "\n\n" + body
    path.write_text(new, encoding="utf-8")


def _main_refine(args) -> int:
    results = []
    for name in args.axes.split(","):
        res = run_axis_refine(name, args.draws, cache=args.cache, segment=args.segment,
                              cached_only=args.cached_only and args.cache is not None)
        results.append(res)
        print(f"{name}: {res['seconds']:.0f} s", file=sys.stderr)
    body = (f"{REFINE_HEADING}\n\n`python benchmarks/bench_recovery.py --refine segment --draws {args.draws} "
            f"--axes {args.axes}{' --cached-only' if args.cached_only else ''}`, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}. Each draw: `identify` "
            "with its defaults, then `refine_segments(trace, ident, parameters=())` (what `refine(..., model='lugre')` runs: segment output error, "
            f"L = {args.segment:g} s, three damping starts, the timing check; the bristle parameters fitted, not "
            "profiled). Same axes, noise draws and seeds as the table above.\n\n" + refine_table(results) + "\n")
    print(body)
    if args.write:
        _write_section(REFINE_HEADING, body, ("\n### ", "\n## "))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
