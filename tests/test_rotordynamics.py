"""bearingsim bearings as ROSS bearing elements (issue 34; bearingsim.app.rotordynamics,
docs/rotordynamics.md): the element's stiffness against bearingsim's own single-speed solves, a
rigid rotor's natural frequencies against sqrt(2 k / m), a set as one element, the damping of the
dynamics, the size of what ROSS drops, and ``bearingsim rotor``.

The single bearing is the Harris 218 of cases/harris218_10krpm.toml (22.25 kN thrust) with a free
contact angle of 20 deg (the shipped 218 cases are 40 deg): a 15-25 deg spindle bearing, whose
centrifugal force softens it markedly at speed.  Every single-bearing test shares one batch of 4
speeds (one compiled program, padded to 8 items)."""
import json
import sys

import numpy as np
import pytest

from bearingsim.app import cli
from bearingsim.app import rotordynamics as rd
from bearingsim.app.workflows import solve_case
from bearingsim.case import load_case
from bearingsim.dynamics.model import contact_damping
from bearingsim.errors import InputError, InvalidStateError

try:
    rd.require_ross()    # imports ROSS without CoolProp's REFPROP notice; its Numba function cached on disk
except InputError:
    pass                 # importorskip says why the module is skipped
ross = pytest.importorskip("ross", reason="ROSS (ross-rotordynamics) is not installed: pip install "
                           "'bearingsim[ross]' (the test extra installs it)")

SPEEDS_RPM = np.array([0.0, 5000.0, 10000.0, 15000.0])
#: the stiffness of a batched solve against a single solve: the same Newton to rtol 1e-11, so they
#: agree far below this (measured ~1e-9)
SAME = 1e-6


@pytest.fixture(scope="module")
def acbb():
    return load_case("harris218_10krpm").with_value("bearing.free_contact_angle_deg", 20.0)


@pytest.fixture(scope="module")
def stiffness(acbb):
    return rd.bearing_stiffness(acbb, SPEEDS_RPM)


def test_the_element_follows_the_speed_as_single_solves_do(acbb, stiffness):
    """kxx, kyy, kxy, kyx, kzz of the element are the stiffness of bearingsim's own single-speed
    solve (``solve_case`` of the case at each speed, an independent compiled program) at every
    speed, ROSS's interpolation returns them at the speeds, and the bearing softens with speed:
    the centrifugal force turns the outer contact angle down and unloads the inner contact."""
    el = rd.to_ross(acbb, n=0, stiffness=stiffness)
    assert np.allclose(el.frequency, SPEEDS_RPM * np.pi / 30.0)
    for k, rpm in enumerate(SPEEDS_RPM):
        K = np.asarray(solve_case(acbb.with_value("operation.speed_rpm", float(rpm))).stiffness)
        for name, (i, j) in dict(kxx=(0, 0), kyy=(1, 1), kzz=(2, 2)).items():
            assert getattr(el, name)[k] == pytest.approx(K[i, j], rel=SAME), (name, rpm)
        for name, (i, j) in dict(kxy=(0, 1), kyx=(1, 0)).items():     # pure thrust: no cross coupling
            assert abs(getattr(el, name)[k]) <= 1e-9 * K[0, 0] and abs(K[i, j]) <= 1e-9 * K[0, 0]
        KR = el.K(el.frequency[k])
        assert KR[0, 0] == pytest.approx(K[0, 0], rel=SAME) and KR[2, 2] == pytest.approx(K[2, 2], rel=SAME)
    kxx = np.asarray(el.kxx)
    print("kxx (N/um) at", SPEEDS_RPM, "rpm:", np.round(kxx * 1e-6, 1), "kzz:", np.round(np.asarray(el.kzz) * 1e-6, 1))
    assert np.all(np.diff(kxx) < 0.0)                      # softens at every step
    assert kxx[-1] < 0.8 * kxx[0]                          # measured 620.6 / 890.4 N/um = 0.70
    assert np.allclose(el.kyy, el.kxx, rtol=1e-9)          # axisymmetric under pure thrust


def test_a_rigid_rotor_on_two_bearings_bounces_at_sqrt_2k_over_m(acbb, stiffness):
    """A rigid, nearly massless shaft (a material 1000 times stiffer than steel, 1 kg/m^3) with a
    50 kg disk at mid-span on two identical bearings: its translational modes are sqrt(2 kxx / m)
    (x and y) and sqrt(2 kzz / m) (axial) with bearingsim's k, at rest and at 15 000 rpm (the disk
    at mid-span does not tilt in these modes, so the gyroscopic moment leaves them alone).
    Tolerance 0.1 %: the shaft's bending stiffness 48 E I / L^3 = 4.1e12 N/m is in series with
    2 k = 1.8e9 N/m, which lowers the frequency by ~2 k / (2 k_shaft) = 2e-4, and the shaft's
    mass (0.0013 kg) adds 1e-5; the damping is off (damping=0)."""
    rigid = ross.Material(name="rigid_light", rho=1.0, E=211e12, G_s=81.2e12)
    shaft = [ross.ShaftElement(L=0.1, idl=0.0, odl=0.09, material=rigid) for _ in range(2)]
    disk = ross.DiskElement(n=1, m=50.0, Id=0.5, Ip=1.0)
    bearings = [rd.to_ross(acbb, n=n, damping=0.0, stiffness=stiffness, tag=f"b{n}") for n in (0, 2)]
    rotor = ross.Rotor(shaft, [disk], bearings)
    m = rotor.m
    assert m == pytest.approx(50.0, rel=1e-4)
    for k in (0, len(SPEEDS_RPM) - 1):
        w = SPEEDS_RPM[k] * np.pi / 30.0
        wn = np.asarray(rotor.run_modal(speed=w, num_modes=16).wn)
        K = stiffness.stiffness[k]
        for what, kk in (("radial", K[0, 0]), ("axial", K[2, 2])):
            expected = np.sqrt(2.0 * kk / m)
            got = wn[np.argmin(np.abs(wn - expected))]
            print(f"{SPEEDS_RPM[k]:.0f} rpm {what}: k = {kk * 1e-6:.2f} N/um, ROSS {got / (2 * np.pi):.2f} Hz, "
                  f"sqrt(2k/m) {expected / (2 * np.pi):.2f} Hz, error {got / expected - 1:+.2e}")
            assert got == pytest.approx(expected, rel=1e-3), (what, SPEEDS_RPM[k])


def test_the_element_carries_the_contact_damping_of_the_dynamics(acbb, stiffness):
    """c = 2 zeta sqrt(k m) on xx, yy, zz: by default the case's [dynamics] contact_damping_ratio
    (0.05) and shaft_mass_kg (2 kg), the numbers bearingsim.dynamics.model.contact_damping gives
    the time-domain model; damping and mass_kg override them; no cross damping."""
    el = rd.to_ross(acbb, n=0, stiffness=stiffness)
    K = stiffness.stiffness
    dyn = np.asarray(contact_damping(K[:, :3, :3], np.full(len(K), 0.05), np.full(len(K), 2.0)))
    assert np.allclose(np.stack([el.cxx, el.cyy, el.czz], -1), dyn, rtol=1e-12)
    assert not np.any(el.cxy) and not np.any(el.cyx)
    el = rd.to_ross(acbb, n=0, damping=0.1, mass_kg=30.0, stiffness=stiffness)
    assert np.allclose(el.cxx, 2 * 0.1 * np.sqrt(K[:, 0, 0] * 30.0), rtol=1e-12)
    assert not np.any(rd.to_ross(acbb, n=0, damping=0.0, stiffness=stiffness).cxx)
    with pytest.raises(InputError, match="damping"):
        rd.to_ross(acbb, damping=-0.1, stiffness=stiffness)


def test_what_ross_drops_is_reported_with_its_size(acbb, stiffness):
    """ROSS's bearing has no tilt stiffness and no translation-tilt coupling: for an angular
    contact bearing the radial force acts at its pressure centre, ~ (d_m / 2) tan(alpha) from its
    plane along the axis (the contact lines meet the axis there), so its stiffness centre is found
    within 5 % of that with alpha the mean of the inner and outer contact angles (measured 2 %:
    the stiffness also weighs how the angles change with the displacement); under pure thrust the
    radial and axial translations do not couple."""
    d = rd.dropped_terms(stiffness)
    sol = stiffness.solution
    alpha = 0.5 * (np.asarray(sol.alpha_inner).mean(-1) + np.asarray(sol.alpha_outer).mean(-1))
    centre = 0.5 * float(acbb.bearing().pitch_diameter) * np.tan(alpha)
    print("stiffness centre (mm):", np.round(d.centre_offset[:, 0] * 1e3, 2), "(d_m/2) tan(alpha):",
          np.round(centre * 1e3, 2), "tilt stiffness there (N m/mrad):",
          np.round(d.tilt_stiffness_at_centre[:, 0] * 1e-3, 1), "tilt coupling:", np.round(d.tilt_coupling, 3))
    assert np.allclose(np.abs(d.centre_offset), centre[:, None], rtol=0.05)
    assert np.allclose(d.centre_offset[:, 0], d.centre_offset[:, 1], rtol=1e-6)   # axisymmetric
    assert np.all(d.radial_axial_coupling < 1e-9)
    assert np.all((d.tilt_coupling > 0.5) & (d.tilt_coupling < 1.0))              # large at the plane ...
    assert np.all(d.tilt_stiffness_at_centre < 0.3 * d.tilt_stiffness)           # ... mostly the offset
    assert np.all(d.tilt_fraction(0.7) < 0.01)          # two such bearings 0.7 m apart: < 1 % of the rotor's
    text = d.text(span=0.7)
    assert "N m/mrad" in text and "mm along the shaft axis" in text and "%" in text


def test_a_set_is_one_element_with_the_sets_stiffness():
    """A DB pair (cases/harris218_db_medium.toml) gives one element whose translational terms are
    the set's stiffness (SetSolution.stiffness: both bearings through the shaft, 40 mm apart, one
    node for a rotor), as the set's own single-speed solve gives it."""
    case = load_case("harris218_db_medium")
    speeds = [0.0, 6000.0, 12000.0]
    el = rd.to_ross(case, n=3, speeds_rpm=speeds)
    assert el.n == 3 and el.tag.startswith("set ")
    for k in (0, 2):
        K = np.asarray(solve_case(case.with_value("operation.speed_rpm", speeds[k])).stiffness)
        for name, (i, j) in dict(kxx=(0, 0), kyy=(1, 1), kxy=(0, 1), kyx=(1, 0), kzz=(2, 2)).items():
            assert getattr(el, name)[k] == pytest.approx(K[i, j], rel=SAME, abs=1e-9 * K[0, 0]), (name, speeds[k])
    print("DB pair kxx (N/um):", np.round(np.asarray(el.kxx) * 1e-6, 1), "kzz:", np.round(np.asarray(el.kzz) * 1e-6, 1))
    assert el.kxx[-1] < el.kxx[0]


def test_bearingsim_rotor_writes_the_campbell_diagram_and_the_critical_speeds(acbb, tmp_path, capsys):
    case_file = tmp_path / "acbb20.toml"
    case_file.write_text(acbb.text)
    out = tmp_path / "rotor"
    assert cli.main(["rotor", str(case_file), "--out", str(out), "--speeds-rpm", "0:15000:4"]) == 0
    said = capsys.readouterr().out
    assert "not in the ROSS element" in said and "campbell.png" in said
    png = out / "campbell.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    data = json.loads((out / "critical_speeds.json").read_text())
    assert data["speeds_rpm"] == [0.0, 5000.0, 10000.0, 15000.0]
    assert set(data["bearing"]) >= {"kxx_N_per_m", "kzz_N_per_m", "damping_mass_kg"}
    assert set(data["dropped"]) >= {"tilt_stiffness_Nm_per_rad", "centre_offset_m", "rotor_tilt_stiffness_fraction"}
    for c in data["critical_speeds"]:
        assert 0.0 < c["speed_rpm"] <= 15000.0 and c["frequency_Hz"] == pytest.approx(c["speed_rpm"] / 60.0)
    print("critical speeds (rpm):", [round(c["speed_rpm"]) for c in data["critical_speeds"]])
    assert data["critical_speeds"], "the default rotor's first bending mode (~195 Hz) lies below 15 000 rpm"


def test_without_ross_the_command_says_how_to_install_it(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "ross", None)          # import ross -> ImportError
    assert cli.main(["rotor", "demo", "--out", str(tmp_path / "r")]) == 2
    err = capsys.readouterr().err
    assert "pip install 'bearingsim[ross]'" in err and err.count("\n") <= 2
    assert not (tmp_path / "r").exists()
    with pytest.raises(InputError, match=r"bearingsim\[ross\]"):
        rd.to_ross("demo")


def test_bad_speeds_are_refused_naming_the_argument(capsys):
    with pytest.raises(InputError, match="speeds_rpm.*>= 0 rpm"):
        rd.bearing_stiffness("demo", [0.0, -100.0])
    with pytest.raises(InputError, match="speeds_rpm"):
        rd.bearing_stiffness("demo", [])
    with pytest.raises(InputError, match="--speeds-rpm '0:100'.*START:STOP:COUNT"):
        rd.parse_speeds("0:100")
    assert cli.main(["rotor", "demo", "--speeds-rpm", "5000:1000:3"]) == 2
    assert "--speeds-rpm" in capsys.readouterr().err


def test_a_speed_that_fails_is_named_with_the_speeds_that_solve(acbb):
    """Without axial load the bearing holds nothing at speed (result no_load): the first failed
    speed is named, how many failed, and the speeds below it to keep (the same compiled batch as
    the other tests: only the loads differ)."""
    with pytest.raises(InvalidStateError, match=r"at 5000 rpm .*3 of 4 speeds failed") as e:
        rd.bearing_stiffness(acbb.with_value("load.axial_N", 0.0), SPEEDS_RPM)
    assert "keep the speeds (speeds_rpm) below 5000 rpm" in str(e.value)
