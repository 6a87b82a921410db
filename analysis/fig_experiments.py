"""Fig. experror: positioning and tracking on the VCM, PID vs PID + observer (section 4.2).
========================================================================================

Asserts: the observer compensation settles faster after both steps and tracks with a lower
RMS error in every chirp-frequency band. Reports the steady-state error per hold.
"""

from obsdesign import studies as paper
from obsdesign.report.study_figures import experiments_figure

from _common import parse_out, report, require

if __name__ == "__main__":
    out = parse_out(__doc__)
    study = paper.experiments_study()
    report(study.claims, experiments_figure(study), out / "fig_experiments.png")
    for ctrl in ("pid", "pid+observer"):
        p, t = study.positioning[ctrl], study.tracking[ctrl]
        print(f"{ctrl}: settling {p['settling_time']} s, steady-state error {p['steady_state_error']} m, "
              f"tracking RMS {t['rms_error']:.3g} m, per band {t['rms_error_per_band']}")
    require(study.claims, 0, 2)
