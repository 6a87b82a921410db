"""
A design sweep: the observer's rho against the stability verdict
================================================================

:func:`obsdesign.sweep` runs the positioning scenario of the ``vcm`` preset over a grid of the
observer's design factor ``rho`` with two uniform draws of the Coulomb friction per grid point
(``obsdesign sweep --vary rho=0.5:6:12 --uncertain Cf=0.25:0.45 --samples 2``), and records the
design verdict of ``obsdesign check`` beside the simulated metrics of each run.

Asserts: the verdict is "stable" exactly where ``rho > 1``, the paper's condition on the
designed eigenvalues (section 3.3).
"""

import tempfile

import matplotlib.pyplot as plt

import obsdesign as od

with tempfile.TemporaryDirectory() as tmp:
    res = od.sweep(od.load_preset("vcm"), "positioning", vary={"rho": (0.5, 6.0, 12)},
                   uncertain={"Cf": (0.25, 0.45)}, samples=2, workers=1, out_dir=tmp)
print(f"{len(res.rows)} runs")
for r in res.rows:
    assert r["stable"] == (r["rho"] > 1), r

# %%
# The observer's friction error over the grid (runs the design check calls unstable in red).
fig, ax = plt.subplots(figsize=(7, 4), constrained_layout=True)
for stable, colour in ((True, "tab:blue"), (False, "tab:red")):
    rows = [r for r in res.rows if r["stable"] == stable and r["status"] == "ok"]
    ax.semilogy([r["rho"] for r in rows], [r["observer_rms_error_f"] for r in rows], "o", color=colour,
                label="stable by check" if stable else "not stable by check")
ax.axvline(1.0, color="grey", lw=0.8)
ax.set_xlabel("rho")
ax.set_ylabel("observer friction RMS error [N]")
ax.legend()
