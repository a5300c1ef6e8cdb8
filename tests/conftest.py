"""Shared fixtures and independent checks (numpy re-derivations of docs/model.md section 4)."""
import os

import numpy as np
import pytest
from hypothesis import settings

import bearingsim as bs

# Hypothesis draws the same examples on every run (CI must never turn red at random): the
# "ci" profile is derandomized and keeps no example database.  HYPOTHESIS_PROFILE=explore draws
# fresh examples, for a person hunting new failures on purpose.
settings.register_profile("ci", derandomize=True, database=None, deadline=None, print_blob=True)
settings.register_profile("explore", derandomize=False, deadline=None, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

DEG = np.pi / 180


def pytest_configure(config):
    """One bank cache for the whole session, made by the controller before the xdist workers
    start (they and the notebooks' kernels inherit the variable): an identification bank that
    tests/test_identify.py builds is read by notebook 09, and never a bank of an earlier run.
    A ``BEARINGSIM_CACHE`` the caller set is kept."""
    if hasattr(config, "workerinput") or os.environ.get("BEARINGSIM_CACHE"):
        return
    import tempfile

    config._bearingsim_cache = tempfile.mkdtemp(prefix="bearingsim-test-cache-")
    os.environ["BEARINGSIM_CACHE"] = config._bearingsim_cache


def pytest_unconfigure(config):
    d = getattr(config, "_bearingsim_cache", None)
    if d:
        import shutil

        shutil.rmtree(d, ignore_errors=True)
        os.environ.pop("BEARINGSIM_CACHE", None)

# Longest first (make test: pytest-xdist, one file per worker at a time, `--dist loadfile
# --no-loadscope-reorder`): the files below go to the workers first, heaviest first, so the two
# workers finish together instead of one of them running notebook 02 or test_identify alone at the
# end (xdist's own reorder puts files with the most test ids first, which sends these few-but-long
# files and every notebook last).  Seconds: the `--durations` totals of a contended full run
# (issue 27, fulltest_durations.log); only their order matters, the rest keeps collection order.
# Notebook 07 is not here on purpose: it reads the training sets test_transfer.py simulates into the
# session's data cache (bearingsim.datasets.cached), so it runs last, after them.
HEAVY_FIRST = {
    "tests/test_shaft.py": 219, "tests/test_chunk_program.py": 208, "tests/test_dynamics.py": 184,
    "tests/test_identify.py": 153, "tests/test_defect.py": 115, "tests/test_fault_classes.py": 114,
    "tests/test_workflows.py": 112, "notebooks/02_spall_and_sweep.ipynb": 103,
    "tests/test_sweep.py": 101, "tests/test_verdicts.py": 75, "tests/test_transfer.py": 120, "tests/test_rotordynamics.py": 90,
    "tests/test_distributed.py": 67, "tests/test_cli.py": 65, "tests/test_packaging.py": 61,
    "tests/test_jones.py": 55, "tests/test_chord.py": 52,
    "tests/test_dataset.py": 46, "notebooks/01_quasi_static.ipynb": 44,
    "tests/test_set_limits.py": 40, "tests/validation/test_set_reference.py": 40,
    "notebooks/09_identify.ipynb": 36, "tests/test_dataset_engine.py": 36,
    "tests/test_signal_stage.py": 35, "notebooks/06_four_fault_classes.ipynb": 34,
}


def pytest_collection_modifyitems(config, items):
    """Stable-sort the session's items: HEAVY_FIRST files first (longest first), then the rest in
    collection order; the tests of one file keep their order."""
    def weight(item):
        return -HEAVY_FIRST.get(item.nodeid.split("::")[0], 0)
    items.sort(key=weight)


def harris218(n_balls=16, **kw):
    """Harris & Kotzalas' 218 angular contact ball bearing (docs/reference-data.md)."""
    return bs.Bearing(n_balls, 22.225e-3, 125.26e-3, 0.5232, 0.5232, np.deg2rad(40.0), **kw)


@pytest.fixture(scope="session")
def b218():
    return harris218()


def _ball_forces(b, sol, op):
    """(G, H, m, r1, r2) per ball, re-derived in numpy from the reported angles and loads."""
    lam_i, lam_o = op.factors
    D = float(b.ball_diameter)
    ai, ao, Qi, Qo, Mg, Fc = (np.asarray(x) for x in (sol.alpha_inner, sol.alpha_outer, sol.Q_inner,
                                                         sol.Q_outer, sol.gyroscopic_moment, sol.centrifugal))
    G = Qi * np.sin(ai) + lam_i * Mg / D * np.cos(ai)
    H = Qi * np.cos(ai) - lam_i * Mg / D * np.sin(ai)
    m = float(b.inner_groove_radius) * G - lam_i * float(b.f_inner) * Mg
    r1 = G - Qo * np.sin(ao) - lam_o * Mg / D * np.cos(ao)
    r2 = H - Qo * np.cos(ao) + lam_o * Mg / D * np.sin(ao) + Fc
    return G, H, m, r1, r2


def equilibrium_error(b, sol, op):
    """Ring equilibrium from the reported per-ball values, relative to the largest applied load
    (moments divided by R_i) or contact load (or 1 N, for a bearing with no load at all)."""
    G, H, m, _, _ = _ball_forces(b, sol, op)
    psi = np.asarray(sol.azimuth)
    R = np.array([np.sum(H * np.cos(psi)), np.sum(H * np.sin(psi)), np.sum(G),
                  np.sum(m * np.sin(psi)), -np.sum(m * np.cos(psi))])
    F = np.asarray(sol.loads)
    scale = np.array([1, 1, 1, 1 / float(b.inner_groove_radius), 1 / float(b.inner_groove_radius)])
    ref = max(np.max(np.abs(F * scale)), float(np.max(np.asarray(sol.Q_outer))), 1.0)
    return np.max(np.abs((R - F) * scale)) / ref


def ball_equilibrium_error(b, sol, op):
    """Largest ball equilibrium residual relative to the largest outer contact load."""
    _, _, _, r1, r2 = _ball_forces(b, sol, op)
    return max(np.max(np.abs(r1)), np.max(np.abs(r2))) / max(float(np.max(np.asarray(sol.Q_outer))), 1.0)


def beyond_low_shoulder(b, sol):
    """True when a loaded contact of an angular contact bearing lies at or beyond its low shoulder
    (docs/model.md section 11), from the reported per-ball angles alone."""
    sh = np.asarray(b.shoulders)
    Qi, Qo = np.asarray(sol.Q_inner), np.asarray(sol.Q_outer)
    ai, ao = np.asarray(sol.alpha_inner), np.asarray(sol.alpha_outer)
    return bool(np.any((Qi > 0) & (np.sin(ai) <= -np.sin(sh[1]))) or np.any((Qo > 0) & (np.sin(ao) <= -np.sin(sh[3]))))


def at_groove_bottom(b, sol, loads):
    """True when a single angular contact bearing with a side load (radial or moment) carries it
    at the bottom of its groove: its most loaded inner contact below 1 deg (tan alpha ~ F_z / F_r
    with one or two balls loaded; docs/model.md section 11, the second reason of result 7), from the reported
    per-ball angles and the loads alone."""
    F = np.asarray(loads, float)
    Qi, ai = np.asarray(sol.Q_inner), np.asarray(sol.alpha_inner)
    k = int(np.argmax(Qi))
    side = bool(np.any(F[[0, 1, 3, 4]] != 0.0))
    return bool(b.angular_contact) and side and F[2] > 0.0 and Qi[k] > 0.0 and ai[k] < np.radians(1.0)


def beyond_high_shoulder(b, sol):
    """True when a loaded contact lies at or beyond a high shoulder's edge (docs/model.md section 11), from the
    reported per-ball angles alone (the ball rides on the shoulder: result ``over_shoulder``)."""
    sh = np.asarray(b.shoulders)
    Qi, Qo = np.asarray(sol.Q_inner), np.asarray(sol.Q_outer)
    ai, ao = np.asarray(sol.alpha_inner), np.asarray(sol.alpha_outer)
    return bool(np.any((Qi > 0) & (ai >= sh[0])) or np.any((Qo > 0) & (ao >= sh[2])))


def inverted_contacts(sol):
    """Number of loaded contacts whose normal points out of the raceway (docs/model.md section 3)."""
    ai, ao = np.asarray(sol.alpha_inner), np.asarray(sol.alpha_outer)
    Qi, Qo = np.asarray(sol.Q_inner), np.asarray(sol.Q_outer)
    return int(np.sum((Qi > 0) & (np.cos(ai) <= 0)) + np.sum((Qo > 0) & (np.cos(ao) <= 0)))
