"""bearingsim spectrum RECORD: a real record's envelope spectrum with the bearing's fault lines,
an overlaid simulation, the record formats (.npz, .npy, .csv, .wav), and one clear message for a
file that is not a record.  The real record is skipped, saying why, when ../shared/realdata is absent."""
from pathlib import Path

import h5py
import numpy as np
import pytest

from bearingsim.case import load_case
from bearingsim.app.cli import main
from bearingsim.errors import InputError
from bearingsim.realism.record_spectrum import fault_line_table, record_spectrum

REPO = Path(__file__).resolve().parents[1]
OR007 = REPO / ".." / "shared" / "realdata" / "cwru_OR007_6_0hp_12k.npz"
needs_record = pytest.mark.skipif(not OR007.is_file(), reason=f"real CWRU record {OR007.resolve()} not found "
                                  "(never committed: see ../shared/realdata/README.md)")


def synthetic(fs=12000.0, seconds=2.0, shaft_hz=29.9, bpfo_order=3.5848, seed=0):
    """Impacts at BPFO ringing a 4 kHz resonance, plus a shaft line and noise (m/s^2)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(fs * seconds)) / fs
    x = 0.05 * rng.standard_normal(t.size) + 0.2 * np.sin(2 * np.pi * shaft_hz * t)
    ring = np.exp(-t[:200] * 800.0) * np.sin(2 * np.pi * 4000.0 * t[:200])
    for t0 in np.arange(0.01, seconds - 0.02, 1.0 / (bpfo_order * shaft_hz)):
        k = int(t0 * fs)
        x[k:k + 200] += ring
    return x


def test_fault_lines_follow_the_bearing_kinematics():
    """The 6205's fault orders (reference-data.md: BPFO 3.5848, BPFI 5.4152, BSF 2.357, FTF 0.3983
    x shaft, SKF/CWRU tables) within 0.5 % (free contact angle 0, the published geometry)."""
    L = fault_line_table(load_case("cwru_6205").bearing(), 1.0)
    assert L["BPFO"] == pytest.approx(3.5848, rel=5e-3) and L["BPFI"] == pytest.approx(5.4152, rel=5e-3)
    assert L["2BSF"] == pytest.approx(2 * 2.357, rel=5e-3) and L["FTF"] == pytest.approx(0.3983, rel=5e-3)
    assert L["BPFI+fr"] - L["BPFI"] == pytest.approx(1.0) and L["BPFO"] + L["BPFI"] == pytest.approx(9.0)  # Z


@needs_record
def test_spectrum_of_a_real_outer_race_record(tmp_path, capsys):
    png = tmp_path / "or007.png"
    assert main(["spectrum", str(OR007), "-o", str(png)]) == 0
    out = capsys.readouterr().out
    assert png.stat().st_size > 20_000 and "BPFO" in out and "cwru_6205" in out
    rs = record_spectrum(OR007, load_case("cwru_6205"))
    # the shaft found within 0.5 % of the file's nominal 1796 rpm; the outer-race fault's line
    # is the strongest of the fault lines and stands > 20 dB over the envelope floor
    assert 60 * rs.shaft_hz == pytest.approx(1796, rel=5e-3) and rs.shaft_source.startswith("found")
    db = {k: v[1] for k, v in rs.strengths.items()}
    assert db["BPFO"] > 20 and db["BPFO"] == max(db[k] for k in ("BPFO", "BPFI", "2BSF", "FTF"))
    assert rs.strengths["BPFO"][0] == pytest.approx(rs.lines["BPFO"], rel=0.015)
    # a given speed is used as given
    given = record_spectrum(OR007, load_case("cwru_6205"), rpm=1750.0)
    assert given.shaft_hz == pytest.approx(1750 / 60) and given.lines["BPFO"] == pytest.approx(
        1750 / 60 * rs.lines["BPFO"] / rs.shaft_hz)


def test_record_formats_and_overlay(tmp_path, capsys):
    x = synthetic()
    np.save(tmp_path / "r.npy", x)
    np.savetxt(tmp_path / "r.csv", x)
    from scipy.io import wavfile
    wavfile.write(tmp_path / "r.wav", 12000, (x / np.abs(x).max() * 30000).astype(np.int16))
    ds = tmp_path / "sim.h5"                         # a data set file's layout (two items)
    with h5py.File(ds, "w") as f:
        f.attrs["sample_rate_Hz"] = 12000.0
        f["signals"] = np.stack([synthetic(seconds=0.5, seed=1), synthetic(seconds=0.5, seed=2)]).astype(np.float32)
        f["labels"] = np.array([(29.9, 0), (29.9, 0)], dtype=[("shaft_Hz", "<f8"), ("result", "<i4")])
    case = load_case("cwru_6205")
    for name in ("r.npy", "r.csv", "r.wav"):
        rs = record_spectrum(tmp_path / name, case, sample_rate=None if name.endswith(".wav") else 12000.0,
                             rpm=1794.0)
        assert rs.strengths["BPFO"][1] > 20, name               # the impacts' line
        db = {k: v[1] for k, v in rs.strengths.items()}
        assert db["BPFO"] == max(db[k] for k in ("BPFO", "BPFI", "2BSF", "FTF")), name
    png = tmp_path / "o.png"
    assert main(["spectrum", str(tmp_path / "r.npy"), "--sample-rate-Hz", "12000", "--rpm", "1794",
                 "--overlay", str(ds), "--item", "1", "-o", str(png)]) == 0
    assert "overlay: sim.h5 item 1" in capsys.readouterr().out and png.is_file()
    assert main(["spectrum", str(tmp_path / "r.npy"), "--sample-rate-Hz", "12000", "--overlay", str(ds),
                 "--item", "5"]) == 2
    assert "--item 5" in capsys.readouterr().err


@pytest.mark.parametrize("name, content, message", [
    ("notes.txt", "hello\nworld\n", "not a column of numbers"),
    ("image.png", "\x89PNG", "not a record file"),
    ("empty.npy", None, "too short"),
    ("missing.npz", False, "no such record file"),
])
def test_a_file_that_is_not_a_record_gets_one_message(tmp_path, capsys, name, content, message):
    p = tmp_path / name
    if content is None:
        np.save(p, np.zeros(10))
    elif content is not False:
        p.write_text(content)
    assert main(["spectrum", str(p), "--sample-rate-Hz", "12000"]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    with pytest.raises(InputError):
        record_spectrum(p, load_case("cwru_6205"), sample_rate=12000.0)


def test_record_flags_are_refused_for_a_simulate_output(tmp_path, capsys):
    assert main(["spectrum", str(tmp_path / "sim.h5"), "--rpm", "1800"]) == 2
    assert "--rpm apply to a record file" in capsys.readouterr().err
