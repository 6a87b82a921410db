"""Section 3.4: measurement noise in the friction estimate, with and without the low-pass.
=======================================================================================

Asserts: the simulated RMS of the noise in the raw and filtered estimates matches the design
prediction (obsdesign noise) within 5 % and 15 % for Table 1 and the VCM.
"""

import control as ct
import matplotlib.pyplot as plt
import numpy as np

import obsdesign as od
from obsdesign import studies as paper

from _common import parse_out, report, require

if __name__ == "__main__":
    out = parse_out(__doc__)
    study = paper.noise_study()
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    w = np.logspace(-1, 4.5, 400)
    for name in ("table1", "vcm"):
        na = od.noise_analysis(od.load_preset(name).override(variant="static"))
        ax.loglog(w, np.abs(ct.frequency_response(na.G_friction, w).complex.ravel()), label=f"{name}: raw")
        ax.loglog(w, np.abs(ct.frequency_response(na.lowpass * na.G_friction, w).complex.ravel()), "--",
                  label=f"{name}: low-pass filtered")
    ax.set_xlabel("frequency [rad/s]")
    ax.set_ylabel("|noise -> friction estimate| [N/m]")
    ax.legend(loc="best")
    report(study.claims, fig, out / "fig_noise.png")
    for name, row in study.rows.items():
        print(f"{name}: {row}")
    require(study.claims, 0, 1)
