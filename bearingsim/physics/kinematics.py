"""Ball kinematics under raceway control and defect frequencies (docs/model.md sections 4 and 8).

Outer ring fixed, inner ring turning at omega = 2 pi n / 60 (rad/s).
"""
from __future__ import annotations

from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp

from ..errors import InputError
from ..hostarrays import f64, xp
from ..fastmath import recip, rsqrt

#: Raceway-control factors (lambda_i, lambda_o) of docs/model.md section 4.
CONTROL_FACTORS = {"outer": (0.0, 2.0), "inner": (2.0, 0.0), "equal": (1.0, 1.0)}
_DEN_FLOOR = 0.05


_f64 = f64             # bearingsim.hostarrays: NumPy unless traced


class Operation(eqx.Module):
    """Operating condition of the bearing.

    ``speed``: inner-ring speed omega (rad/s, >= 0; outer ring fixed).
    ``control``: raceway control hypothesis, "outer" | "inner" | "equal" (static).
    ``centrifugal``, ``gyroscopic``: 1.0 to include the ball's centrifugal force / gyroscopic
    moment, 0.0 to leave it out (floats so that they can be vmapped).
    """

    speed: jnp.ndarray = eqx.field(converter=_f64)
    control: str = eqx.field(static=True, default="outer")
    centrifugal: jnp.ndarray = eqx.field(converter=_f64, default=1.0)
    gyroscopic: jnp.ndarray = eqx.field(converter=_f64, default=1.0)

    def __check_init__(self):
        if self.control not in CONTROL_FACTORS:
            raise InputError(f"raceway control must be one of {sorted(CONTROL_FACTORS)}, got {self.control!r}",
                             "the raceway control hypothesis: 'outer' (default), 'inner' or 'equal'")

    @classmethod
    def from_rpm(cls, speed_rpm, control="outer", centrifugal=True, gyroscopic=True):
        return cls(2.0 * jnp.pi * f64(speed_rpm) / 60.0, control,
                   float(centrifugal), float(gyroscopic))

    @property
    def speed_rpm(self):
        return self.speed * 60.0 / (2.0 * jnp.pi)

    @property
    def factors(self):
        """(lambda_i, lambda_o)."""
        return CONTROL_FACTORS[self.control]


class BallKinematics(NamedTuple):
    beta: jnp.ndarray            # ball spin-axis pitch angle (rad)
    orbital_speed: jnp.ndarray   # omega_m, ball orbital (cage) speed (rad/s)
    spin_speed: jnp.ndarray      # omega_R, ball spin magnitude (rad/s)
    centrifugal: jnp.ndarray     # F_c (N)
    gyroscopic: jnp.ndarray      # M_g (N m)


def ball_kinematics_cs(bearing, op: Operation, sin_i, cos_i, sin_o, cos_o):
    """:func:`ball_kinematics` from the sines and cosines of the contact angles, free of
    transcendental functions (the solvers' inner loop): ``(sin b, cos b, omega_m, omega_R, F_c,
    M_g)``."""
    g = bearing.g
    if op.control == "inner":
        num, den_b = sin_i, cos_i - g
    else:
        num, den_b = sin_o, cos_o + g
    hyp2 = num * num + den_b * den_b
    ok = hyp2 > 0.0
    ih = rsqrt(jnp.where(ok, hyp2, 1.0))
    sb = jnp.where(ok, num * ih, 0.0)
    cb = jnp.where(ok, den_b * ih, 1.0)
    # omega_m = omega k_i/(k_i+k_o), omega_R = omega k_i k_o/((k_i+k_o) g) with the denominators
    # cos(alpha - beta) cleared: regular through alpha - beta = 90 deg.  The remaining
    # denominator n_i c_o + n_o c_i vanishes only for a ball far off both raceways (a geometric
    # "inner angle" near 180 deg); a floor there keeps the speeds finite and is never active
    # for a ball in, or near, contact.
    n_i = 1.0 - g * cos_i
    n_o = 1.0 + g * cos_o
    c_i = cos_i * cb + sin_i * sb          # cos(alpha_i - beta)
    c_o = cos_o * cb + sin_o * sb          # cos(alpha_o - beta)
    den = n_i * c_o + n_o * c_i
    iden = recip(jnp.where(den > _DEN_FLOOR, den, _DEN_FLOOR))     # (a max's derivative divides)
    w = op.speed
    w_m = w * n_i * c_o * iden
    w_R = (w / g) * n_i * n_o * iden
    Fc = op.centrifugal * 0.5 * bearing.ball_mass * bearing.pitch_diameter * w_m * w_m
    Mg = op.gyroscopic * bearing.ball_inertia * w_R * w_m * sb
    return sb, cb, w_m, w_R, Fc, Mg


def ball_kinematics(bearing, op: Operation, alpha_i, alpha_o) -> BallKinematics:
    """Pitch angle, orbital and spin speeds, centrifugal force and gyroscopic moment of a ball.

    Raceway control decides beta: outer (and "equal") tan(beta) = sin(a_o)/(cos(a_o) + g);
    inner tan(beta) = sin(a_i)/(cos(a_i) - g).  Switches in ``op`` scale F_c and M_g.
    """
    sb, cb, w_m, w_R, Fc, Mg = ball_kinematics_cs(bearing, op, jnp.sin(alpha_i), jnp.cos(alpha_i),
                                                  jnp.sin(alpha_o), jnp.cos(alpha_o))
    return BallKinematics(jnp.arctan2(sb, cb), w_m, w_R, Fc, Mg)


class DefectFrequencies(NamedTuple):
    """Characteristic defect frequencies (Hz), outer ring fixed: the one frequency type of every
    result that reports them.  ``bsf`` is once per ball revolution; ``two_bsf`` = 2 BSF is what
    some tables (CWRU) list as "rolling element".  Scalars, or arrays with a leading item axis.
    :meth:`hz` / :meth:`from_hz`: the ``shaft_Hz, ftf_Hz, bpfo_Hz, bpfi_Hz, bsf_Hz`` fields of
    the results files and data set labels."""

    shaft: jnp.ndarray
    ftf: jnp.ndarray
    bpfo: jnp.ndarray
    bpfi: jnp.ndarray
    bsf: jnp.ndarray

    @property
    def two_bsf(self):
        return 2.0 * self.bsf

    def hz(self) -> dict:
        """``{"shaft_Hz": ..., "ftf_Hz": ..., "bpfo_Hz": ..., "bpfi_Hz": ..., "bsf_Hz": ...}``."""
        return {f"{k}_Hz": v for k, v in self._asdict().items()}

    @classmethod
    def from_hz(cls, d) -> "DefectFrequencies":
        """From a mapping with the ``*_Hz`` keys of :meth:`hz`."""
        return cls(*(d[f"{k}_Hz"] for k in cls._fields))


def defect_frequencies(bearing, shaft_hz, alpha=None) -> DefectFrequencies:
    """FTF, BPFO, BPFI, BSF (docs/model.md section 8) at contact angle ``alpha`` (rad, default alpha_0)."""
    alpha = bearing.free_contact_angle if alpha is None else alpha
    f = f64(shaft_hz)
    gc = bearing.g * xp(f, alpha).cos(alpha)
    Z = bearing.n_balls
    ftf = 0.5 * f * (1.0 - gc)
    bsf = f * (1.0 - gc ** 2) / (2.0 * bearing.g)
    return DefectFrequencies(f, ftf, Z * ftf, 0.5 * Z * f * (1.0 + gc), bsf)
