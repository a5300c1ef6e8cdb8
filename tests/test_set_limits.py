"""The limits diagram of a set study (issue 21 item 2): its values against the solution's own
per-ball output, and the figure."""
import numpy as np

from bearingsim.case import load_case
from bearingsim.sets import plot_set_limits, study_limits, study_set_case


def test_limits_over_speed_of_a_db_pair(tmp_path):
    case = load_case("harris218_db_light")
    study = study_set_case(case, throw=False)
    lim = study_limits(case, study)
    n, nb = study.values.size, len(study.solution.bearings)
    assert all(np.shape(lim[k]) == (n, nb) for k in ("pressure", "friction", "edge_deg", "lift_off"))
    pl = case.limits_settings()["pressure_limit"]
    for k, b in enumerate(study.solution.bearings):
        p = np.maximum(np.asarray(b.p_max_inner), np.asarray(b.p_max_outer)).max(axis=-1) / pl
        np.testing.assert_allclose(lim["pressure"][:, k], p, rtol=1e-12)
    # at rest raceway control needs no friction (no gyroscopic moment); a rigid DB preload grows
    # with speed (the balls' centrifugal forces), so the lift-off margin does too
    assert np.all(lim["friction"][0] == 0.0)
    assert np.all(np.diff(lim["lift_off"], axis=0) > 0.0)
    out = plot_set_limits(case, study, title=case.title, path=tmp_path / "limits.png")
    assert out == tmp_path / "limits.png" and out.stat().st_size > 10_000
