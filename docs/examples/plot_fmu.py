"""
The controller as an FMU, run in FMPy beside ``simulate``
=========================================================

``obsdesign export --what controller --format fmu`` writes an FMI 2.0 co-simulation FMU of the
sampled controller, built from the same generated C as ``--format c`` (see :doc:`/fmu-export`).
Here FMPy, the importer the tests use, runs it on the set-point and the measurement that
:func:`obsdesign.simulate` recorded on the ``vcm`` tracking scenario, one communication step per
sample.

Asserts: FMPy's validation reports nothing, and the FMU's commands give the simulator's net force
``u = K command - G`` bit for bit; the same holds for the FMI 3.0 FMU of the same C
(``--fmi-version 3``), run at the end.
"""

import pathlib
import tempfile

import fmpy
import matplotlib.pyplot as plt
import numpy as np
from fmpy.validation import validate_fmu

import obsdesign as od
from obsdesign.export.fmu import fmu_archive

cfg = od.load_preset("vcm")
res = od.simulate(cfg, "tracking", duration=0.3)
path = pathlib.Path(tempfile.mkdtemp()) / "obsdesign_controller.fmu"
path.write_bytes(fmu_archive(cfg))
assert validate_fmu(str(path)) == []

# %%
# The recorded inputs drive the FMU; its output after the step from t_n is the command of sample n.
n, dt = len(res.t), cfg.observer.dt
signals = np.zeros(n, dtype=[("time", float), ("x_ref", float), ("x_meas", float)])
signals["time"], signals["x_ref"], signals["x_meas"] = np.arange(n) * dt, res.x_ref, res.x_meas
out = fmpy.simulate_fmu(str(path), stop_time=n * dt, step_size=dt, output_interval=dt, input=signals,
                        output=["command", "f_hat_filtered"])
command = out["command"][1:n + 1]
u = cfg.plant.K * command - cfg.plant.G
assert np.array_equal(u, res.u)
print(f"{n} steps; largest |u_fmu - u_simulate| = {np.max(np.abs(u - res.u)):g} N")

fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
ax1.plot(res.t * 1e3, res.u, lw=2.5, color="0.75", label="simulate: u")
ax1.plot(res.t * 1e3, u, lw=0.8, color="C0", label="FMU in FMPy: K command - G")
ax1.set_ylabel("net force [N]")
ax1.legend(loc="upper right")
ax2.plot(res.t * 1e3, (u - res.u) * 1e15, color="C3")
ax2.set_ylabel("difference [fN]")
ax2.set_xlabel("time [ms]")
fig.suptitle("The exported FMU against the simulator (vcm, tracking)")
fig.tight_layout()

# %%
# The FMI 3.0 FMU (``fmi_version="3"``) wraps the same C: FMPy runs it the same way, with the same commands.
path3 = path.with_name("obsdesign_controller_fmi3.fmu")
path3.write_bytes(fmu_archive(cfg, fmi_version="3"))
assert validate_fmu(str(path3)) == []
out3 = fmpy.simulate_fmu(str(path3), stop_time=n * dt, step_size=dt, output_interval=dt, input=signals,
                         output=["command"])
assert np.array_equal(out3["command"][1:n + 1], command)
print(f"FMI {fmpy.read_model_description(str(path3)).fmiVersion}: the same {n} commands, bit for bit")
