"""The machine's own vibration, in healthy and faulty records alike (docs/realism.md).

A real accelerometer on a bearing housing does not record the bearing alone: the shaft's
unbalance and misalignment (lines at the shaft frequency and its harmonics), the motor's
electromagnetic forces (lines at the supply frequency and its harmonics; twice the supply
frequency for an induction motor), and the broadband vibration of the rig (flow, gears, the fan,
the coupling, electrical noise), shaped by the structure's resonances and partly modulated by the
shaft's rotation, plus occasional knocks that repeat at no bearing frequency.  A classifier that
has only seen clean simulated records learns that *any* structure means a fault; with this
background in every class it has to learn the fault's own signature.

:class:`Background` describes one machine's background (all amplitudes in m/s^2, frequencies in
Hz); :mod:`bearingsim.signals.signal_stage` draws one (``draw_background``, from the ranges of
:data:`BACKGROUND_DEFAULTS`: domain randomisation) and synthesizes its record
(``background_record``) from an item's key:

``shaft_amplitudes``  (K,) amplitudes of the lines at k f_r, k = 1..K (random phases)
``line_frequency``, ``line_amplitudes``  (L,) amplitudes at l x the supply frequency
``noise_rms``  RMS of the broadband part
``psd_frequencies``, ``psd_levels_db``  its spectral shape: the power spectral density's
    level (dB, any reference: only the shape counts; the RMS sets the level) at these
    frequencies, interpolated linearly in dB over log-frequency and held flat outside them;
    empty: white
``modulation_depths``  (K,) amplitude modulation of the broadband part at k f_r (0-1)
``line_modulation_depths``  (L,) its modulation at l x the supply frequency (an induction
    motor's magnetic forces pulse at twice the supply frequency)
``knock_rate``, ``knock_amplitude``, ``knock_frequency``, ``knock_damping``  Poisson knocks
    (per second; peak amplitude; the ringing resonance and its damping ratio)

The NumPy synthesis of the same (seeded by a generator) is the tests' independent oracle
(tests/oracles/background_numpy.py).
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["Background", "BACKGROUND_DEFAULTS"]


class Background(NamedTuple):
    """One machine's background vibration (see the module docstring)."""

    shaft_amplitudes: tuple = ()
    line_frequency: float = 60.0
    line_amplitudes: tuple = ()
    noise_rms: float = 0.0
    psd_frequencies: tuple = ()
    psd_levels_db: tuple = ()
    modulation_depths: tuple = ()
    knock_rate: float = 0.0
    knock_amplitude: float = 0.0
    knock_frequency: float = 3000.0
    knock_damping: float = 0.05
    line_modulation_depths: tuple = ()

    def as_labels(self) -> dict:
        """Scalar summaries for a data set's labels."""
        sa = np.asarray(self.shaft_amplitudes, float)
        la = np.asarray(self.line_amplitudes, float)
        return {"background_noise_rms_m_s2": float(self.noise_rms),
                "background_shaft_rms_m_s2": float(np.sqrt(0.5 * np.sum(sa * sa))),
                "background_line_rms_m_s2": float(np.sqrt(0.5 * np.sum(la * la))),
                "background_knock_rate_Hz": float(self.knock_rate)}


BACKGROUND_DEFAULTS = {
    "noise_rms_m_s2": (0.2, 2.0),              # m/s^2: 0.02-0.2 g (the CWRU baseline is 0.07 g)
    "shaft_harmonics": 6,                      # lines at k f_r, k = 1..6
    "shaft_relative": (0.01, 1.0),             # each line's amplitude / noise RMS (log-uniform)
    "line_frequency_Hz": (50.0, 60.0),         # one of the two supply frequencies
    "line_harmonics": 4,
    "line_relative": (0.003, 0.3),
    "psd_bumps": (1, 4),                       # resonances shaping the broadband part
    "psd_bump_Hz": (300.0, 5500.0),
    "psd_bump_db": (0.0, 25.0),
    "psd_bump_octaves": (0.1, 0.7),
    "psd_tilt_db_per_octave": (-6.0, 3.0),
    "modulation_harmonics": 8,                 # shaft-synchronous modulation at k f_r, k = 1..8
    "modulation_depth": (0.0, 0.4),            # a harmonic's depth where it is strong ...
    "modulation_strong": 0.4,                  # ... with this probability; else up to 0.03
    "line_modulation_harmonics": 2,            # at the supply frequency and twice it
    "knock_rate_Hz": (0.0, 20.0),
    "knock_relative": (0.5, 8.0),              # knock peak / noise RMS
    "knock_Hz": (1000.0, 5500.0),
    "knock_damping": (0.01, 0.08),
}
