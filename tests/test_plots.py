"""bearingsim.output.plots: report figures of quasi-static states, studies, simulations and comparisons
(labelled axes with units, saved when given a path)."""
from pathlib import Path
from types import SimpleNamespace

import jax
import jax.numpy as jnp
import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

from bearingsim.output import plots
from bearingsim.physics.kinematics import DefectFrequencies
from bearingsim.app import signal_workflows, workflows  # noqa: E402
from bearingsim.case import parse_case  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def case():
    return parse_case((ROOT / "tests" / "data" / "small_sweep.toml").read_text(), "small.toml")


@pytest.fixture(scope="module")
def sweep(case):
    return workflows.sweep_case(case)


def labels(fig):
    return [ax.get_xlabel() + " | " + ax.get_ylabel() for ax in fig.axes]


def test_static(case, sweep, tmp_path):
    one = jax.tree_util.tree_map(lambda a: a[30], sweep)          # ball 0 over the spall centre
    fig = plots.plot_static(one, title="static", spall=case.spall())
    assert "ball azimuth ψ (deg) | contact angle (deg)" in labels(fig)
    assert fig.axes[0].get_title().startswith("Ball loads (N)") and "rpm" in fig.axes[1].get_title()
    assert fig.get_suptitle() == "static"
    plt.close(fig)
    plots.plot_static(one, spall=case.spall(), path=tmp_path / "s.png")
    assert (tmp_path / "s.png").stat().st_size > 10_000
    assert not plt.get_fignums()                                   # closed once saved


def test_sweep_follows_the_ball_over_the_spall(case, sweep, tmp_path):
    u, traces, ok = plots.spall_traces(sweep, center=float(case.spall().center))
    assert u.shape == (61,) and np.all(np.diff(u) >= 0) and ok.all()
    assert traces["Q_outer"].shape == (61, 3)
    at_centre = int(np.argmin(np.abs(u)))
    assert traces["Q_outer"][at_centre, 1] < traces["Q_outer"][at_centre, 0]   # unloaded over the spall
    plots.plot_sweep(sweep, title="sweep", spall=case.spall(), path=tmp_path / "sweep.png")
    assert (tmp_path / "sweep.png").stat().st_size > 30_000


def test_study(case, sweep, tmp_path):
    stacked = jax.tree_util.tree_map(lambda a: jnp.stack([a, a]), sweep)
    fig = plots.plot_study(stacked, [0.1, 0.3], "defect.depth_mm", "mm", spall=case.spall())
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["0.1 mm", "0.3 mm"]
    assert "ball azimuth ψ (deg) | $\\alpha_i$ (deg)" in labels(fig)
    plt.close(fig)


def fake_run(sweep):
    """A dynamic run whose samples are the sweep's states (one per cage angle)."""
    n = np.asarray(sweep.cage_angle).size
    t = np.arange(n) * 1e-4
    return SimpleNamespace(time=t, cage_angle=np.asarray(sweep.cage_angle), Q_outer=np.asarray(sweep.Q_outer),
                           Q_inner=np.asarray(sweep.Q_inner), alpha_outer=np.asarray(sweep.alpha_outer),
                           ring_displacement=np.asarray(sweep.displacement)[:, :3],
                           sensor_acceleration=np.sin(2 * np.pi * 1000 * t), pass_times=t[[20, 40]],
                           frequencies=DefectFrequencies(shaft=166.7, ftf=70.0, bpfo=1120.0, bpfi=1500.0,
                                            bsf=400.0))


def test_simulation_figures(case, sweep, tmp_path):
    res = fake_run(sweep)
    written = plots.plot_simulation(res, tmp_path / "sim", title="run", bearing=case.bearing(), spall=case.spall())
    assert [p.name for p in written] == ["sensor_acceleration.png", "sensor_acceleration_zoom.png", "ball_loads.png"]
    assert all(p.stat().st_size > 5_000 for p in written) and not plt.get_fignums()


def test_compare(case, sweep, tmp_path):
    res = fake_run(sweep)
    cmp = signal_workflows.Comparison(res, np.arange(0, 61, 2), jax.tree_util.tree_map(lambda a: a[::2], sweep), [])
    fig = plots.plot_compare(cmp, title="small")
    assert "cage angle θ_c (deg) | $Q_o$ (N)" in labels(fig) and "cage angle θ_c (deg) | ring displacement (µm)" in labels(fig)
    ax = fig.axes[0]
    dyn, qs = ax.lines[0].get_ydata(), ax.lines[1].get_ydata()
    np.testing.assert_allclose(dyn[::2], qs)                      # the same states, drawn twice
    assert fig.get_suptitle() == "small: static vs swept vs dynamic"
    plt.close(fig)
