"""Parameters of a dynamic simulation: result codes, the structural parameters
(:class:`DynamicsParameters`) and the seeded realism ingredients (:class:`Realism`)."""
from __future__ import annotations

from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp

from ..errors import InputError, NotConvergedError, ResultCode
from ..hostarrays import f64, xp

__all__ = ["RESULTS", "DynamicsError", "DynamicsParameters", "Realism"]


_f64 = f64             # bearingsim.hostarrays: NumPy unless traced


def _vec(x):
    return xp(x).atleast_1d(f64(x))


class RESULTS(ResultCode):
    """Result codes of a dynamic simulation (``DynamicsResult.result``)."""

    successful = (0, "successful", "")
    nonfinite = (1, "the state became non-finite (the integration is unstable)",
                 "use more substeps (a smaller step than the fastest mode needs), or check the "
                 "structural parameters")
    initial_state = (2, "the quasi-static initial state did not converge or is not valid",
                     "check the loads and the spall (the quasi-static result code says why)")
    initial_equilibrium = (3, "the dynamic model's own equilibrium at t = 0 was not found from "
                           "the quasi-static state", "raise ball_iterations; report the case")
    ball_solver = (4, "the lean ball solver does not reach the required accuracy with at most "
                   "16 Newton steps", "pass ball_iterations explicitly, or report the case")
    fixed_size = (5, "the run's slip walk or defect passes exceed the fixed sizes of the compiled chunk "
                  "program", "raise max_speed_rpm of the chunk program (it sizes them), or report the case")


class DynamicsError(NotConvergedError):
    """A dynamic simulation failed (``code``: a :class:`RESULTS` member)."""



class DynamicsParameters(eqx.Module):
    """Structural parameters (SI).  Defaults are those of the case schema ([dynamics]).

    The sensor modes are ``resonance_frequency`` (Hz), ``resonance_damping_ratio`` and
    ``resonance_gain``: scalars (one mode) or equal-length arrays (several modes).
    ``resonator_mass`` only enters the adaptive reference with ``sensor_coupling=True`` (the
    back-coupling the exact sensor filter neglects)."""

    shaft_mass: jnp.ndarray = eqx.field(converter=_f64, default=2.0)            # kg
    housing_mass: jnp.ndarray = eqx.field(converter=_f64, default=5.0)          # kg
    housing_stiffness: jnp.ndarray = eqx.field(converter=_f64, default=5e7)     # N/m
    housing_damping: jnp.ndarray = eqx.field(converter=_f64, default=2000.0)    # N s/m
    resonance_frequency: jnp.ndarray = eqx.field(converter=_vec, default=3000.0)  # Hz
    resonance_damping_ratio: jnp.ndarray = eqx.field(converter=_vec, default=0.05)
    resonance_gain: jnp.ndarray = eqx.field(converter=_vec, default=1.0)
    resonator_mass: jnp.ndarray = eqx.field(converter=_f64, default=0.05)       # kg
    contact_damping_ratio: jnp.ndarray = eqx.field(converter=_f64, default=0.05)
    unbalance: jnp.ndarray = eqx.field(converter=_f64, default=0.0)             # kg m

    def __check_init__(self):
        n = self.resonance_frequency.shape[-1]
        if self.resonance_damping_ratio.shape[-1] not in (1, n) or \
                self.resonance_gain.shape[-1] not in (1, n):
            raise InputError("resonance_damping_ratio and resonance_gain need one value per "
                             f"resonance frequency ({n})")

    def modes(self):
        """(frequencies, damping ratios, gains) broadcast to one shape (..., M)."""
        f = self.resonance_frequency
        x = xp(f, self.resonance_damping_ratio, self.resonance_gain)
        return f, x.broadcast_to(self.resonance_damping_ratio, f.shape), x.broadcast_to(self.resonance_gain, f.shape)

    @classmethod
    def from_settings(cls, d: dict) -> "DynamicsParameters":
        """From ``Case.dynamics_settings()`` (SI keys without unit suffix).  The list keys
        ``resonance_frequencies`` / ``resonance_damping_ratios`` / ``resonance_gains``, when
        present, override the single-mode ``resonance_frequency`` / ``resonance_damping_ratio``."""
        names = [f.name for f in cls.__dataclass_fields__.values()]
        kw = {k: d[k] for k in names if k in d}
        for key, name in (("resonance_frequencies", "resonance_frequency"),
                          ("resonance_damping_ratios", "resonance_damping_ratio"),
                          ("resonance_gains", "resonance_gain")):
            if d.get(key) is not None:
                kw[name] = d[key]
        return cls(**kw)


class Realism(NamedTuple):
    """Seeded ingredients of real records (all off by default).  ``noise_rms`` in m/s^2 (the
    CWRU normal drive-end baseline is 0.07 g = 0.686 m/s^2); ``noise_band`` (lo, hi) Hz or None
    (white).  ``pass_amplitude_cv_max_percent`` / ``pass_delay_sd_max_percent``: pass-to-pass
    variability of a pit's impacts (coefficient of variation of a per-pass factor; standard
    deviation of a per-pass delay, % of the pass interval) where the contact cannot bridge the
    pit at all; a run scales both by the pit's unbridged fraction
    (:func:`bearingsim.physics.pit.pit_unbridged_fraction`)."""

    slip_percent: float = 0.0
    speed_fluctuation_percent: float = 0.0
    speed_fluctuation_bandwidth_Hz: float = 5.0
    noise_rms: float = 0.0
    noise_band: tuple | None = None
    pass_amplitude_cv_max_percent: float = 0.0
    pass_delay_sd_max_percent: float = 0.0

    @property
    def pass_variation(self) -> bool:
        """True when the pass-to-pass variability is on."""
        return self.pass_amplitude_cv_max_percent > 0.0 or self.pass_delay_sd_max_percent > 0.0

    @classmethod
    def from_settings(cls, d: dict) -> "Realism":
        """From ``Case.dynamics_settings()`` (missing keys: off)."""
        band = d.get("noise_band")
        return cls(float(d.get("slip_percent", 0.0)), float(d.get("speed_fluctuation_percent", 0.0)),
                   float(d.get("speed_fluctuation_bandwidth", 5.0)), float(d.get("noise_rms", 0.0)),
                   None if band is None else tuple(float(v) for v in band),
                   float(d.get("pass_amplitude_cv_max_percent", 0.0)),
                   float(d.get("pass_delay_sd_max_percent", 0.0)))
