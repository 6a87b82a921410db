"""The circle (ballbar) test of the compensation modes on the vcm axis: the numbers of docs/compensation-modes.md.
===============================================================================================================

vcm preset with sensor noise (``noise_rms`` 0.2 um on the 1 um encoder), radius 5 mm, feeds 2, 6.3 and
20 mm/s, 10 kHz, both directions, seeds 0-4: the quadrant-glitch peak of PID only and of each
compensation mode (mean, min-max over the seeds and directions), on the preset's plant (Coulomb with
pre-sliding memory, s = 3000 1/m) and on a plant with no pre-sliding to speak of (s = 1e7 1/m: Coulomb +
viscous). The feed-forward modes run with the config's defaults (the Coulomb term on the model's
pre-sliding curve of s = 3000 along the reference), as a velocity function (``ff_presliding`` off: a
drive's table) and as a velocity function with a build-up distance of 1/s (the drives' approximation of
the pre-sliding turn-over).

Usage: ``python analysis/circle_modes.py [--seeds N]`` (prints Markdown tables).
"""

from __future__ import annotations

import argparse

import numpy as np

import obsdesign as od
from obsdesign.report.circle_section import FEEDS
from obsdesign.sim.circle import circle_modes


def print_rows(rows, feeds, name, prefix=""):
    """One Markdown row per mode: the glitch peak [um] per feed, mean (min-max) over the runs."""
    for mode in dict.fromkeys(r["mode"] for r in rows):
        cells = []
        for f in feeds:
            g = np.array([r["glitch_peak"] for r in rows if r["mode"] == mode and r["feed"] == f]) * 1e6
            cells.append(f"{g.mean():.2f} ({g.min():.2f}-{g.max():.2f})")
        tag = mode if name is None else f"{mode}, {name}"
        print(f"| {prefix}{tag} | " + " | ".join(cells) + " |")


def table(cfg, plant, seeds, label):
    variants = [(None, cfg, None)]
    ff = ("feedforward", "blend")
    variants.append(("velocity function", cfg.override(ff_presliding=False), ff))
    variants.append((f"velocity function, build-up {1e3 / cfg.friction.s:.2g} mm",
                     cfg.override(ff_presliding=False, buildup=1.0 / cfg.friction.s), ff))
    print(f"\n#### {label}\n")
    print("| mode | " + " | ".join(f"{f * 1e3:g} mm/s" for f in FEEDS) + " |")
    print("|---|" + "---|" * len(FEEDS))
    for name, c, modes in variants:
        rows = circle_modes(c, modes=modes, feeds=FEEDS, directions=("ccw", "cw"), seeds=seeds, plant=plant)
        print_rows(rows, FEEDS, name)


def mismatch(cfg, seeds=(0, 1)):
    """The modes on the LuGre and GMS plants (defaults of obsdesign.friction, levels of [friction]), ccw."""
    import dataclasses

    from obsdesign.plant_spec import PlantFrictionSpec

    feeds = (2e-3, 2e-2)
    print("\n#### LuGre / GMS plants (observer and feed-forward designed for the paper's model), ccw, seeds", seeds)
    print("\n| plant | mode | " + " | ".join(f"{f * 1e3:g} mm/s" for f in feeds) + " |\n|---|---|---|---|")
    for model in ("lugre", "gms"):
        plant = dataclasses.replace(cfg, plant_friction=PlantFrictionSpec(model=model))
        for name, c, modes in ((None, cfg, None),
                               ("velocity function", cfg.override(ff_presliding=False), ("feedforward", "blend"))):
            rows = circle_modes(c, modes=modes, feeds=feeds, seeds=seeds, plant=plant)
            print_rows(rows, feeds, name, prefix=f"{model} | ")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    seeds = tuple(range(ap.parse_args().seeds))
    cfg = od.load_preset("vcm").override(noise_rms=2e-7)
    print("glitch peak [um]: mean (min-max) over seeds", seeds, "and both directions")
    table(cfg, "physical", seeds, "vcm plant (pre-sliding s = 3000 1/m)")
    table(cfg, cfg.override(s=1e7), seeds, "plant without pre-sliding (s = 1e7 1/m: Coulomb + viscous)")
    mismatch(cfg)


if __name__ == "__main__":
    main()
