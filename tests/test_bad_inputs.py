"""Every bad input answered in one voice: through the command line entry point
``bearingsim.app.cli.main``, exit code 2, one message naming the file and the key (or what is wrong
with the file), no traceback, and no output file left behind."""

import pytest

from bearingsim.app.cli import main

GOOD = """\
title = "catalogue case"
[bearing]
balls = 9
ball_diameter_mm = 7.94004
pitch_diameter_mm = 39.0398
inner_groove_curvature = 0.52
outer_groove_curvature = 0.52
diametral_clearance_mm = 0.012
[operation]
speed_rpm = 1797
[load]
radial_x_N = 1000
[defect]
center_deg = 0.0
length_mm = 0.5334
depth_mm = 0.2794
profile = "rectangular"
[sweep]
steps = 11
[dynamics]
duration_s = 0.01
sample_rate_Hz = 48000
"""

DATASET = GOOD + """\
[dataset]
count = 4
speed_rpm = [1700, 1800]
radial_N = [500, 1000]
"""


def edit(text, old, new):
    assert old in text, old
    return text.replace(old, new, 1)


def study(parameter, values):
    return GOOD + f'[study]\nparameter = "{parameter}"\nvalues = {values}\n'


#: id -> (command, file content: text or bytes (None: no file), words the message must contain)
CATALOGUE = {
    # the file itself
    "missing file": ("static", None, ["no such case file"]),
    "directory": ("static", "DIR", ["is a directory"]),
    "binary file": ("static", b"\x7fELF\x02\x01\x01\x00\x00\x00" * 20, ["binary file"]),
    "utf-16 with bom": ("info", GOOD.encode("utf-16"), ["UTF-16", "save it as UTF-8"]),
    "utf-16 without bom": ("info", GOOD.encode("utf-16-le"), ["UTF-16"]),
    "latin-1 text": ("info", ("# Lagerprüfung\n" + GOOD).encode("latin-1"), ["not UTF-8", "line 1"]),
    "empty file": ("static", "", ["missing required section [bearing]"]),
    "duplicate key": ("static", edit(GOOD, "speed_rpm = 1797", "speed_rpm = 1797\nspeed_rpm = 1800"),
                      ["duplicate key operation.speed_rpm", "lines 10 and 11"]),
    "duplicate section": ("static", GOOD + "[load]\naxial_N = 5\n", ["section [load] is declared twice"]),
    "key and section": ("static", edit(GOOD, "[bearing]", "load = 5\n[bearing]"),
                        ["load is both a key and a section"]),
    "bad value syntax": ("static", edit(GOOD, "speed_rpm = 1797", "speed_rpm = fast"),
                         ["invalid TOML on line 10", "operation.speed_rpm"]),
    "unterminated string": ("static", GOOD + 'description = "open\n', ["invalid TOML"]),
    "unclosed array": ("static", study("load.axial_N", "[1, 2"), ["invalid TOML", "unclosed"]),
    # keys and values
    "unknown key": ("static", edit(GOOD, "speed_rpm", "sped_rpm"), ["did you mean 'speed_rpm'"]),
    "unknown section": ("static", GOOD + "[defects]\n", ["unknown section [defects]", "did you mean"]),
    "string for a number": ("static", edit(GOOD, "balls = 9", 'balls = "9"'), ["bearing.balls", "wrong type"]),
    "float for an integer": ("static", edit(GOOD, "balls = 9", "balls = 9.5"), ["bearing.balls", "integer"]),
    "boolean for a number": ("static", edit(GOOD, "speed_rpm = 1797", "speed_rpm = true"),
                             ["operation.speed_rpm", "wrong type"]),
    "too few balls": ("static", edit(GOOD, "balls = 9", "balls = 2"), ["bearing.balls = 2", "out of range"]),
    "nan": ("static", edit(GOOD, "speed_rpm = 1797", "speed_rpm = nan"), ["operation.speed_rpm", "finite"]),
    "negative speed": ("static", edit(GOOD, "speed_rpm = 1797", "speed_rpm = -5"), ["operation.speed_rpm"]),
    "choice typo": ("static", edit(GOOD, "[operation]", '[operation]\nraceway_control = "outr"'),
                    ["operation.raceway_control", 'did you mean "outer"']),
    "tilt typo": ("static", edit(GOOD, "[operation]", '[operation]\ntilt = "hold"'),
                  ["operation.tilt", 'did you mean "held"']),
    "held tilt with a moment": ("static", edit(GOOD, "[load]", '[load]\nmoment_y_Nm = 5').replace(
        "[operation]", '[operation]\ntilt = "held"'), ["load.moment_y_Nm = 5", 'operation.tilt = "held"']),
    "held tilt swept": ("sweep", edit(GOOD, "[operation]", '[operation]\ntilt = "held"'),
                        ['operation.tilt = "held" is not supported by the cage-angle sweep']),
    "missing key": ("static", edit(GOOD, "pitch_diameter_mm = 39.0398\n", ""),
                    ["missing required key bearing.pitch_diameter_mm"]),
    "missing section": ("static", edit(GOOD, "[operation]\nspeed_rpm = 1797\n", ""),
                        ["missing required section [operation]"]),
    "angle and clearance": ("static", edit(GOOD, "[operation]", "free_contact_angle_deg = 10\n[operation]"),
                            ["free_contact_angle_deg or bearing.diametral_clearance_mm, not both"]),
    "neither angle nor clearance": ("static", edit(GOOD, "diametral_clearance_mm = 0.012\n", ""),
                                    ["give exactly one of bearing.free_contact_angle_deg"]),
    "pitch below ball": ("static", edit(GOOD, "pitch_diameter_mm = 39.0398", "pitch_diameter_mm = 7"),
                         ["bearing.pitch_diameter_mm = 7"]),
    "balls overlap": ("static", edit(GOOD, "balls = 9", "balls = 20"), ["bearing.balls = 20", "overlap"]),
    "clearance too large": ("static", edit(GOOD, "diametral_clearance_mm = 0.012", "diametral_clearance_mm = 1.0"),
                            ["bearing.diametral_clearance_mm = 1.0", "too large"]),
    "poisson ratio": ("static", GOOD + "[material]\npoisson_ratio = 0.5\n", ["material.poisson_ratio"]),
    "shoulder angle": ("static", GOOD + "[shoulders]\ninner_high_deg = 95\nouter_low_deg = -1\n",
                       ["shoulders.inner_high_deg = 95", "shoulders.outer_low_deg = -1"]),
    "bearing design": ("static", edit(GOOD, "balls = 9", 'balls = 9\ndesign = "deep-groove"'),
                       ["bearing.design", 'did you mean "deep_groove"']),
    "load rating": ("static", edit(GOOD, "balls = 9", "balls = 9\ndynamic_load_rating_kN = 0"),
                    ["bearing.dynamic_load_rating_kN = 0", "> 0 kN"]),
    "friction coefficient": ("static", GOOD + "[limits]\nfriction_coefficient = 0\n", ["limits.friction_coefficient"]),
    "hybrid incomplete": ("static", GOOD + "[material.ball]\ndensity_kg_m3 = 3200\n",
                          ["material.ball.youngs_modulus_GPa"]),
    "spall too deep": ("static", edit(GOOD, "depth_mm = 0.2794", "depth_mm = 9"), ["defect.depth_mm = 9"]),
    "spall too long": ("static", edit(GOOD, "length_mm = 0.5334", "length_mm = 20"),
                       ["defect.length_mm = 20", "ball pitch"]),
    "spall without depth": ("static", edit(GOOD, "depth_mm = 0.2794\n", ""), ["defect.depth_mm"]),
    "value as a table": ("static", GOOD + "[bearing.balls]\n", ["bearing.balls is both a key and a section"]),
    "section as a value": ("static", "bearing = 5\n" + GOOD[GOOD.index("[operation]"):],
                           ["[bearing] must be a table"]),
    "sweep of one angle": ("sweep", edit(GOOD, "steps = 11", "steps = 1"), ["sweep.steps = 1"]),
    "sweep of no width": ("sweep", edit(GOOD, "steps = 11", "steps = 11\nstart_deg = 5\nstop_deg = 5"),
                          ["sweep.stop_deg = 5 must differ from sweep.start_deg"]),
    # studies
    "study of an unknown key": ("study", study("operation.sped_rpm", "[1, 2]"),
                                ["study.parameter", "did you mean 'operation.speed_rpm'"]),
    "study of a string key": ("study", study("operation.raceway_control", "[1, 2]"),
                              ["study.parameter", "numeric key"]),
    "study without values": ("study", study("load.axial_N", "[]"), ["study.values is empty"]),
    "study value out of range": ("study", study("operation.speed_rpm", "[1000, -5]"),
                                 ["study.values[1]", "operation.speed_rpm"]),
    "study of the ball count": ("study", study("bearing.balls", "[8, 9]"),
                                ["study.parameter = 'bearing.balls'", "number of balls"]),
    "study without [study]": ("study", GOOD, ["no [study] section"]),
    # simulations and data sets
    "zero samples": ("simulate", edit(GOOD, "duration_s = 0.01", "duration_s = 0.00001"),
                     ["dynamics.duration_s = 1e-05", "dynamics.sample_rate_Hz = 48000", "0 samples"]),
    "one sample": ("simulate", edit(GOOD, "sample_rate_Hz = 48000", "sample_rate_Hz = 100"),
                   ["dynamics.sample_rate_Hz = 100", "1 samples"]),
    "simulate below nyquist": ("simulate", edit(GOOD, "duration_s = 0.01\nsample_rate_Hz = 48000",
                                                "duration_s = 1.0\nsample_rate_Hz = 200"),
                               ["dynamics.sample_rate_Hz = 200", "BPFI", "need sample_rate_Hz >= 323.3 Hz"]),
    "dataset below nyquist": ("dataset", edit(DATASET, "duration_s = 0.01\nsample_rate_Hz = 48000",
                                              "duration_s = 1.0\nsample_rate_Hz = 100"),
                              ["dynamics.sample_rate_Hz = 100", "dataset.speed_rpm max 1800",
                               "need sample_rate_Hz >="]),
    "dataset of zero samples": ("dataset", edit(DATASET, "count = 4", "count = 4\nduration_s = 0.00001"),
                                ["dataset.duration_s = 1e-05", "dynamics.sample_rate_Hz", "0 samples"]),
    "dataset range reversed": ("dataset", edit(DATASET, "speed_rpm = [1700, 1800]", "speed_rpm = [1800, 1700]"),
                               ["dataset.speed_rpm", "min > max"]),
    "dataset unloaded": ("dataset", edit(DATASET, "radial_N = [500, 1000]", "radial_N = [0, 1000]"),
                         ["dataset.radial_N", "both allow 0"]),
    "dataset without [dataset]": ("dataset", GOOD, ["no [dataset] section"]),
    "compare without [dynamics]": ("compare", edit(GOOD, "[dynamics]\nduration_s = 0.01\nsample_rate_Hz = 48000\n", ""),
                                   ["compare needs a [dynamics] section"]),
    "dynamics tolerance": ("simulate", GOOD + "rtol = 1.5\n", ["dynamics.rtol = 1.5"]),
    # other inputs
    "misspelt shipped case": ("info", "NAME:cwru6205", ["cwru6205", "did you mean 'cwru_6205'"]),
    "spectrum of a text file": ("spectrum", "not an HDF5 file", ["not a bearingsim simulate output"]),
    "spectrum of a directory": ("spectrum", "DIR", ["is a directory"]),
}


def command(name, arg, out):
    return {"info": ["info", arg], "static": ["static", arg, "--json", str(out / "s.json"), "--plot", str(out / "s.png")],
            "sweep": ["sweep", arg, "-o", str(out / "r.h5"), "--plot", str(out / "plots")],
            "study": ["study", arg, "-o", str(out / "r.h5"), "--plot", str(out / "plots")],
            "simulate": ["simulate", arg, "-o", str(out / "r.h5"), "--plot", str(out / "plots")],
            "dataset": ["dataset", arg, "-o", str(out / "r.h5")],
            "compare": ["compare", arg, "--plot", str(out / "plots")],
            "spectrum": ["spectrum", arg, "--plot", str(out / "s.png")]}[name]


def test_the_catalogue_is_large():
    assert len(CATALOGUE) >= 40


@pytest.mark.parametrize("name", list(CATALOGUE))
def test_bad_input_exit_2_named_nothing_written(name, tmp_path, capsys):
    cmd, content, words = CATALOGUE[name]
    out = tmp_path / "out"
    if isinstance(content, str) and content.startswith("NAME:"):
        arg = content[5:]
    else:
        path = tmp_path / ("case" if cmd != "spectrum" else "sim.h5")
        if content == "DIR":
            path.mkdir()
        elif isinstance(content, bytes):
            path.write_bytes(content)
        elif content is not None:
            path.write_text(content)
        arg = str(path)
    before = sorted(tmp_path.rglob("*"))
    assert main(command(cmd, arg, out)) == 2
    err = capsys.readouterr().err
    assert err.startswith("bearingsim: error: ") and "Traceback" not in err
    assert arg in err, f"the message does not name {arg}:\n{err}"
    for w in words:
        assert w in err, f"{w!r} not in:\n{err}"
    assert sorted(tmp_path.rglob("*")) == before, "something was written"


# ------------------------------------------------------------------ bearingsim calibrate
def _rec(n=24000, fs=12000.0, bad=None, shape=None):
    """A healthy-looking record (noise and a shaft line) of n samples."""
    import numpy as np

    x = np.random.default_rng(0).standard_normal(n) * 0.07 + 0.01 * np.sin(2 * np.pi * 29.9 * np.arange(n) / fs)
    if bad is not None:
        x[n // 2] = bad
    return x if shape is None else np.resize(x, shape)


#: id -> (file name, writer(path) or bytes / text, extra arguments, words the message must contain)
CALIBRATE = {
    "missing record": ("r.npz", None, [], ["no such record file"]),
    "record is a directory": ("r.npz", "DIR", [], ["is a directory"]),
    "unreadable record": ("r.npy", b"\x00garbage\xff" * 40, ["--sample-rate-Hz", "12000", "--unit", "g"],
                          ["cannot read the record"]),
    "unknown record format": ("r.flac", b"fLaC\x00\x00", [], ["unknown record format", ".npz"]),
    "truncated wav": ("r.wav", b"RIFF....WAVE", [], ["cannot read the record"]),
    "csv of words": ("r.csv", "time,acc\n0,1\n", ["--sample-rate-Hz", "12000", "--unit", "g"],
                     ["not a column of numbers"]),
    "no sample rate": ("r.npy", lambda p: __import__("numpy").save(p, _rec()), ["--unit", "g"],
                       ["no sample rate", "--sample-rate-Hz"]),
    "zero sample rate": ("r.npy", lambda p: __import__("numpy").save(p, _rec()),
                         ["--unit", "g", "--sample-rate-Hz", "0"], ["sample rate 0.0 Hz", "finite sample rate > 0"]),
    "negative sample rate": ("r.npy", lambda p: __import__("numpy").save(p, _rec()),
                             ["--unit", "g", "--sample-rate-Hz", "-12000"], ["finite sample rate > 0"]),
    "sample rate too low": ("r.npz", lambda p: __import__("numpy").savez(p, DE=_rec(), fs=2000.0, units="g"), [],
                            ["sample rate 2000 Hz is too low", "at least 2400 Hz"]),
    "sample rate disagrees with the file": ("r.npz", lambda p: __import__("numpy").savez(p, DE=_rec(), fs=12000.0,
                                                                                     units="g"),
                                            ["--sample-rate-Hz", "48000"], ["disagrees with the file's fs"]),
    "too short": ("r.npy", lambda p: __import__("numpy").save(p, _rec(6000)),
                  ["--unit", "g", "--sample-rate-Hz", "12000"], ["0.5 s", "too short", "at least 1 s"]),
    "nan sample": ("r.npy", lambda p: __import__("numpy").save(p, _rec(bad=float("nan"))),
                   ["--unit", "g", "--sample-rate-Hz", "12000"], ["1 of 24000 samples are NaN or infinite"]),
    "infinite sample": ("r.csv", lambda p: p.write_text("\n".join(str(v) for v in _rec(bad=float("inf")))),
                        ["--unit", "g", "--sample-rate-Hz", "12000"], ["NaN or infinite"]),
    "two columns": ("r.npy", lambda p: __import__("numpy").save(p, _rec(shape=(12000, 2))),
                    ["--unit", "g", "--sample-rate-Hz", "12000"], ["shape (12000, 2)", "one channel"]),
    "empty record": ("r.npy", lambda p: __import__("numpy").save(p, _rec()[:0]),
                     ["--unit", "g", "--sample-rate-Hz", "12000"], ["empty"]),
    "constant record": ("r.npy", lambda p: __import__("numpy").save(p, _rec() * 0 + 1.0),
                        ["--unit", "g", "--sample-rate-Hz", "12000"], ["all samples are equal"]),
    "unknown channel": ("r.npz", lambda p: __import__("numpy").savez(p, DE=_rec(), FE=_rec(), fs=12000.0, units="g"),
                        ["--channel", "BA"], ["no channel 'BA'", "DE, FE"]),
    "no unit": ("r.npy", lambda p: __import__("numpy").save(p, _rec()), ["--sample-rate-Hz", "12000"],
                ["does not say its unit", "--unit g or --unit m/s^2"]),
    "fault without class": ("r.npz", lambda p: __import__("numpy").savez(p, DE=_rec(), fs=12000.0, units="g"),
                            ["--fault", "FILE"], ["needs its class", "--fault-class"]),
    "class without fault": ("r.npz", lambda p: __import__("numpy").savez(p, DE=_rec(), fs=12000.0, units="g"),
                            ["--fault-class", "outer"], ["without a fault record"]),
    "bad item count": ("r.npz", lambda p: __import__("numpy").savez(p, DE=_rec(), fs=12000.0, units="g"),
                       ["--count", "0"], ["dataset.count"]),
}


@pytest.mark.parametrize("name", list(CALIBRATE))
def test_calibrate_bad_input_exit_2_named_nothing_written(name, tmp_path, capsys):
    fname, content, extra, words = CALIBRATE[name]
    path = tmp_path / fname
    if content == "DIR":
        path.mkdir()
    elif isinstance(content, bytes):
        path.write_bytes(content)
    elif isinstance(content, str):
        path.write_text(content)
    elif content is not None:
        content(path)
    extra = [str(path) if a == "FILE" else a for a in extra]
    before = sorted(tmp_path.rglob("*"))
    assert main(["calibrate", str(path), "-o", str(tmp_path / "out" / "spec.toml"), *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith("bearingsim: error: ") and "Traceback" not in err
    if name not in ("bad item count", "class without fault"):      # arguments, not the file
        assert str(path) in err, f"the message does not name {path}:\n{err}"
    for w in words:
        assert w in err, f"{w!r} not in:\n{err}"
    assert sorted(tmp_path.rglob("*")) == before, "something was written"
