"""Fig. frictionloops: friction estimate vs displacement against the model's f and Fc.
===================================================================================

Asserts: the filtered estimate stays within 10 % of Cf (RMS) of the plant's Coulomb friction.
"""

from obsdesign import studies as paper
from obsdesign.report.study_figures import friction_loops_figure

from _common import parse_out, report, require

if __name__ == "__main__":
    out = parse_out(__doc__)
    study = paper.friction_loops_study()
    report(study.claims, friction_loops_figure(study), out / "fig_friction_loops.png")
    require(study.claims, 0)
