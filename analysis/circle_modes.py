"""The circle (ballbar) test of the compensation modes on the vcm axis: the numbers of docs/compensation-modes.md.
===============================================================================================================

vcm preset with sensor noise (``noise_rms`` 0.2 um on the 1 um encoder), radius 5 mm, feeds 2, 6.3 and
20 mm/s, 10 kHz, both directions, seeds 0-4: the quadrant-glitch peak of PID only and of each
compensation mode (mean, min-max over the seeds and directions), on the preset's plant (Coulomb with
pre-sliding memory, s = 3000 1/m) and on a plant whose friction is exactly the feed-forward model
(s = 1e7 1/m: no pre-sliding to speak of). The feed-forward modes run once with the config's defaults
and once with a build-up distance of 1/s (the pre-sliding scale of the preset).

Usage: ``python analysis/circle_modes.py [--seeds N]`` (prints Markdown tables).
"""

from __future__ import annotations

import argparse

import numpy as np

import obsdesign as od
from obsdesign.report.circle_section import FEEDS
from obsdesign.sim.circle import circle_modes


def table(cfg, plant, seeds, label):
    variants = [("pid / observer / feedforward / blend", cfg, None)]
    variants.append(("build-up 1/s", cfg.override(buildup=1.0 / cfg.friction.s), ("feedforward", "blend")))
    print(f"\n#### {label}\n")
    print("| mode | " + " | ".join(f"{f * 1e3:g} mm/s" for f in FEEDS) + " |")
    print("|---|" + "---|" * len(FEEDS))
    for name, c, modes in variants:
        rows = circle_modes(c, modes=modes, feeds=FEEDS, directions=("ccw", "cw"), seeds=seeds, plant=plant)
        for mode in dict.fromkeys(r["mode"] for r in rows):
            cells = []
            for f in FEEDS:
                g = np.array([r["glitch_peak"] for r in rows if r["mode"] == mode and r["feed"] == f]) * 1e6
                cells.append(f"{g.mean():.2f} ({g.min():.2f}-{g.max():.2f})")
            tag = mode if modes is None else f"{mode}, build-up {1e3 / cfg.friction.s:.2g} mm"
            print(f"| {tag} | " + " | ".join(cells) + " |")


def mismatch(cfg, seeds=(0, 1)):
    """The modes on the LuGre and GMS plants (defaults of obsdesign.friction, levels of [friction]), ccw."""
    import dataclasses

    from obsdesign.plant_spec import PlantFrictionSpec

    feeds = (2e-3, 2e-2)
    print("\n#### LuGre / GMS plants (observer and feed-forward designed for the paper's model), ccw, seeds", seeds)
    print("\n| plant | mode | " + " | ".join(f"{f * 1e3:g} mm/s" for f in feeds) + " |\n|---|---|---|---|")
    for model in ("lugre", "gms"):
        plant = dataclasses.replace(cfg, plant_friction=PlantFrictionSpec(model=model))
        rows = circle_modes(cfg, feeds=feeds, seeds=seeds, plant=plant)
        for mode in dict.fromkeys(r["mode"] for r in rows):
            cells = []
            for f in feeds:
                g = np.array([r["glitch_peak"] for r in rows if r["mode"] == mode and r["feed"] == f]) * 1e6
                cells.append(f"{g.mean():.2f} ({g.min():.2f}-{g.max():.2f})")
            print(f"| {model} | {mode} | " + " | ".join(cells) + " |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    seeds = tuple(range(ap.parse_args().seeds))
    cfg = od.load_preset("vcm").override(noise_rms=2e-7)
    print("glitch peak [um]: mean (min-max) over seeds", seeds, "and both directions")
    table(cfg, "physical", seeds, "vcm plant (pre-sliding s = 3000 1/m)")
    table(cfg, cfg.override(s=1e7), seeds, "plant = the feed-forward model (s = 1e7 1/m)")
    mismatch(cfg)


if __name__ == "__main__":
    main()
