"""Independent plain numpy/scipy reference for docs/model.md sections 2-5.

This module is deliberately written from docs/model.md alone (it does not use or import the
JAX package ``bearingsim``).  It serves two purposes:

1. the "plain scipy baseline" that ``benchmarks/bench_static.py`` times against;
2. an independent cross-check of the JAX Jones solver (``tests/test_reference_crosscheck.py``).

Contents
--------
* :class:`Geometry` -- section 2 (SI units, radians).
* :func:`hertz_constant` -- section 3, exact elliptic integrals (``scipy.special.ellipk`` /
  ``ellipe`` with parameter m = 1 - 1/kappa^2); kappa from a vectorised Newton iteration
  (safeguarded by ``scipy.optimize.brentq``).  K is evaluated at each contact's own angle.
* :func:`kinematics` -- section 4, raceway control "outer" / "inner" / "equal".
* :func:`depth_profile` -- section 5, "rectangular" and "ball-path" spall profiles.
* :func:`solve` -- Jones quasi-static model, 2Z + 5 unknowns, ``scipy.optimize.root(hybr)``.
* :func:`solve_sweep` -- loop over cage angles with warm starts (the scipy loop baseline).

Conventions (adopted project-wide)
----------------------------------
(a) Q = K delta^1.5 for delta > 0 and a contact normal that points into its raceway
    (cos alpha > 0), else 0 (docs/model.md section 3: a ball pushed past the inner groove-curvature
    centre has lost its inner contact; it never acts as a tie).
(b) The friction / gyroscopic terms lambda (M_g / D) act exactly as docs/model.md writes them, for
    every ball.  (A gate "only at a loaded contact" was tried first: under inner control it
    leaves the model without a solution when a ball leaves its inner raceway, see below.)
(c) At omega = 0 a ball with no contact (total approach s - BD - H <= 0) is indeterminate; it is
    put at the collinear mid-gap position (delta_o = delta_i = half the negative total) and its
    two equations are replaced by that closed form (residual = X - X_mid, in micrometres).
(d) Spall: delta_o = L_o - (f_o - 1/2) D - H(psi_j), R_o = (d_m + D cos alpha0)/2.  A ball over
    the spall (H > 0) that has lost its inner contact (rule (a): delta_i <= 0 or cos alpha_i <= 0)
    takes, for F_c and M_g, the orbital speed of its UNDROPPED position (same ball, same q,
    ball problem solved with H = 0);
    F_c and M_g are evaluated at that orbital speed with the ball's own alpha_o and beta
    (M_g = J omega_R omega_m sin beta, omega_R / omega_m = n_o / (g c_o)), which equals its
    own-angle values times (omega_m_undropped / omega_m_own)^2 wherever its own omega_m is
    finite; its reported omega_m (and omega_R) are the undropped ones.  Its own omega_m is never
    used: a ball pushed past the inner groove centre has alpha_i near 180 deg, and exactly on the
    line of the groove centres (the collinear static start) it is 0/0.
(e) Outputs per ball: alpha_i, alpha_o, Q_i, Q_o, delta_i, delta_o, F_c, M_g, omega_m (and more);
    q = [dx, dy, dz, theta_x, theta_y]; cage speed = mean omega_m.

Numerics
--------
Unknowns are scaled to micrometres: each ball's centre (X1, X2) (measured from the fixed outer
groove-curvature centre) is stored as its offset from the unloaded position
(f_o - 1/2) D (sin alpha0, cos alpha0) in um, translations in um, tilts as um at R_i.  Residuals
are in kN (moments divided by R_i).  The rigid-ring static solution (omega = 0, collinear balls,
delta_i/delta_o = (K_o/K_i)^(2/3)) is solved first on the 5 ring unknowns from an axial shift
at which every healthy ball touches; the full 2Z + 5 system at speed is then solved from it
(balls that do not touch at the static solution are first pushed onto the outer race).  If hybr
fails, the fallbacks are: (1) every ball pre-equilibrated (its own 2x2 problem) at the static
q; (2) continuation in speed (8, then 32 steps) with re-equilibration at a failing step; (3) with
a spall, continuation in the depth profile (H scaled 0 -> 1) from the healthy solution at speed.
``converged`` is reported False when none reaches the tolerance (1e-9 of the largest load, N).

Known limits of the model as specified (found with this code, see the cross-check tests)
---------------------------------------------------------------------------------------
* Inner raceway control with balls that lose inner contact at speed: docs/model.md keeps the inner
  friction term lambda_i M_g/D for such a ball (no normal load under it).  Gating it at unloaded
  contacts makes the inner force jump by lambda_i M_g/D when the contact closes, and the system
  then generally has no solution (hybr stalls; with a smoothed gate the balls settle at
  delta_i -> 0+ with a fraction of the friction on), so the literal form is kept.  Outer and
  "equal" control hardly care (a ball with outer contact only has alpha_o = 0, hence M_g = 0).
* omega_m and omega_R are evaluated as omega n_i c_o / (n_i c_o + n_o c_i) and
  omega n_i n_o / ((n_i c_o + n_o c_i) g) (n = 1 -/+ g cos alpha, c = cos(alpha - beta)): the
  docs/model.md expressions with the denominators cleared, regular when alpha_i - beta crosses 90 deg.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize, special

UM = 1.0e-6          # unknowns in micrometres
KN = 1.0e3           # residuals in kN
CONTROLS = {"outer": (0.0, 2.0), "inner": (2.0, 0.0), "equal": (1.0, 1.0)}
PROFILES = ("rectangular", "ball-path")


# --------------------------------------------------------------------------------------------
# Section 2: geometry
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Geometry:
    """Bearing geometry and materials, SI units, alpha0 in rad."""

    Z: int
    D: float
    dm: float
    fi: float
    fo: float
    alpha0: float
    E_ball: float = 207.5e9
    nu_ball: float = 0.3
    E_ring: float = 207.5e9
    nu_ring: float = 0.3
    rho_ball: float = 7850.0

    @classmethod
    def from_clearance(cls, Z, D, dm, fi, fo, Pd, **materials):
        """cos alpha0 = 1 - P_d / (2 B D)."""
        B = fi + fo - 1.0
        alpha0 = math.acos(min(1.0, max(-1.0, 1.0 - Pd / (2.0 * B * D))))
        return cls(Z, D, dm, fi, fo, alpha0, **materials)

    @property
    def B(self):
        return self.fi + self.fo - 1.0

    @property
    def A(self):
        return self.B * self.D

    @property
    def Ri(self):
        """Radius of the inner groove-curvature-centre locus."""
        return 0.5 * self.dm + (self.fi - 0.5) * self.D * math.cos(self.alpha0)

    @property
    def Ro(self):
        """Outer raceway radius used for the spall arc length."""
        return 0.5 * (self.dm + self.D * math.cos(self.alpha0))

    @property
    def g(self):
        return self.D / self.dm

    @property
    def mass(self):
        return self.rho_ball * math.pi * self.D ** 3 / 6.0

    @property
    def inertia(self):
        return self.mass * self.D ** 2 / 10.0

    @property
    def E_eff(self):
        """E' = 2 / [(1 - nu_b^2)/E_b + (1 - nu_r^2)/E_r]."""
        return 2.0 / ((1.0 - self.nu_ball ** 2) / self.E_ball + (1.0 - self.nu_ring ** 2) / self.E_ring)


HARRIS_218 = Geometry(16, 22.225e-3, 125.26e-3, 0.5232, 0.5232, math.radians(40.0))


# --------------------------------------------------------------------------------------------
# Section 3: Hertz point contact
# --------------------------------------------------------------------------------------------
def _F_of_kappa(kappa):
    """F(kappa) = [(k^2+1) E - 2 K] / [(k^2-1) E] and dF/dkappa; m = 1 - 1/k^2."""
    k2 = kappa * kappa
    m = 1.0 - 1.0 / k2
    K = special.ellipk(m)
    E = special.ellipe(m)
    num = (k2 + 1.0) * E - 2.0 * K
    den = (k2 - 1.0) * E
    # dK/dm = (E - (1-m) K) / (2 m (1-m)) = (k^2 E - K)/(2 m);  dE/dm = (E - K)/(2 m)
    dm_dk = 2.0 / (kappa * k2)
    dK = (k2 * E - K) / (2.0 * m) * dm_dk
    dE = (E - K) / (2.0 * m) * dm_dk
    dnum = 2.0 * kappa * E + (k2 + 1.0) * dE - 2.0 * dK
    dden = 2.0 * kappa * E + (k2 - 1.0) * dE
    return num / den, (dnum * den - num * dden) / (den * den)


def ellipticity(F):
    """kappa = a/b solving F(rho) = [(k^2+1)E - 2K]/[(k^2-1)E] exactly (array-valued).

    Vectorised Newton on ln(kappa) from the Brewe-Hamrock estimate (stops when a step is
    below 1e-13 relative, i.e. the error is at round-off), with a
    per-element brentq fallback.  F <= 0 gives kappa = 1 (circular contact).
    """
    F = np.asarray(F, dtype=float)
    scalar = F.ndim == 0
    F = np.atleast_1d(F)
    out = np.ones_like(F)
    idx = np.nonzero(F > 1e-12)[0]
    if idx.size:
        f = F[idx]
        kap = np.maximum(1.0339 * ((1.0 + f) / (1.0 - f)) ** 0.636, 1.0 + 1e-6)
        ok = np.zeros(f.shape, dtype=bool)
        for _ in range(40):
            val, der = _F_of_kappa(kap)
            step = (val - f) / (der * kap)               # Newton step in t = ln(kappa)
            step = np.clip(step, -0.5, 0.5)
            kap_new = kap * np.exp(-step)
            kap_new = np.where(np.isfinite(kap_new) & (kap_new > 1.0), kap_new, 0.5 * (kap + 1.0))
            done = np.abs(kap_new - kap) <= 1e-13 * kap   # quadratic: error now ~1e-26
            kap = kap_new
            if np.all(done):
                ok[:] = True
                break
            ok = done
        val, _ = _F_of_kappa(kap)
        bad = ~ok | ~(np.abs(val - f) <= 1e-12)
        for n in np.nonzero(bad)[0]:
            fn = f[n]
            kap[n] = optimize.brentq(lambda k: _F_of_kappa(k)[0] - fn, 1.0 + 1e-12, 1e6,
                                     xtol=1e-300, rtol=1e-15, maxiter=500)
        out[idx] = kap
    return out[0] if scalar else out


def curvature(geom: Geometry, alpha, inner: bool):
    """(sum rho, F(rho)) at contact angle alpha (gamma = D cos alpha / d_m)."""
    gam = geom.D * np.cos(alpha) / geom.dm
    if inner:
        t = 2.0 * gam / (1.0 - gam)
        srho = (4.0 - 1.0 / geom.fi + t) / geom.D
        F = (1.0 / geom.fi + t) / (geom.D * srho)
    else:
        t = 2.0 * gam / (1.0 + gam)
        srho = (4.0 - 1.0 / geom.fo - t) / geom.D
        F = (1.0 / geom.fo - t) / (geom.D * srho)
    return srho, F


def hertz_constant(geom: Geometry, alpha, inner: bool, return_all=False):
    """Load-deflection constant K (N/m^1.5) at contact angle(s) alpha: Q = K delta^1.5.

    K = pi kappa E' sqrt(2 E R / (9 K^3)), R = 1 / sum rho.
    """
    srho, F = curvature(geom, alpha, inner)
    kap = ellipticity(F)
    m = 1.0 - 1.0 / (kap * kap)
    eK = special.ellipk(m)
    eE = special.ellipe(m)
    R = 1.0 / srho
    Kc = np.pi * kap * geom.E_eff * np.sqrt(2.0 * eE * R / (9.0 * eK ** 3))
    if return_all:
        return dict(K=Kc, kappa=kap, F=F, sum_rho=srho, ellK=eK, ellE=eE)
    return Kc


def contact_ellipse(geom: Geometry, alpha, Q, inner: bool):
    """Semi-axes a, b (m) and p_max (Pa) for load Q (N) at contact angle alpha."""
    h = hertz_constant(geom, alpha, inner, return_all=True)
    R = 1.0 / h["sum_rho"]
    k, E = h["kappa"], h["ellE"]
    Qp = np.maximum(Q, 0.0)
    a = (6.0 * k * k * E * Qp * R / (np.pi * geom.E_eff)) ** (1.0 / 3.0)
    b = (6.0 * E * Qp * R / (np.pi * k * geom.E_eff)) ** (1.0 / 3.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        p = np.where(Qp > 0, 3.0 * Qp / (2.0 * np.pi * a * b), 0.0)
    return a, b, p


# --------------------------------------------------------------------------------------------
# Section 4: kinematics
# --------------------------------------------------------------------------------------------
def kinematics(geom: Geometry, alpha_i, alpha_o, omega, control="outer"):
    """beta, omega_m (orbital), omega_R (ball spin magnitude) per docs/model.md section 4."""
    g = geom.g
    if control in ("outer", "equal"):
        beta = np.arctan2(np.sin(alpha_o), np.cos(alpha_o) + g)
    elif control == "inner":
        beta = np.arctan2(np.sin(alpha_i), np.cos(alpha_i) - g)
    else:
        raise ValueError(f"control must be one of {tuple(CONTROLS)}, got {control!r}")
    # k_i = n_i / c_i, k_o = n_o / c_o; omega_m = omega k_i/(k_i+k_o) and
    # omega_R = omega k_i k_o/((k_i+k_o) g) are written with c_i c_o cleared, which is the same
    # expression but stays regular when alpha_i - beta passes 90 deg (c_i = 0, k_i infinite)
    n_i = 1.0 - g * np.cos(alpha_i)
    n_o = 1.0 + g * np.cos(alpha_o)
    c_i = np.cos(alpha_i - beta)
    c_o = np.cos(alpha_o - beta)
    den = n_i * c_o + n_o * c_i
    om_m = omega * n_i * c_o / den
    om_R = omega * n_i * n_o / (den * g)
    return beta, om_m, om_R


# --------------------------------------------------------------------------------------------
# Section 5: spall depth profile
# --------------------------------------------------------------------------------------------
def _wrap(x):
    """Wrap to (-pi, pi]."""
    return np.pi - np.mod(np.pi - x, 2.0 * np.pi)


def _sag(D, x):
    return 0.5 * D - np.sqrt(np.maximum(0.0, 0.25 * D * D - x * x))


def depth_profile(geom: Geometry, spall, psi):
    """H(psi) (m) for spall = dict(center, extent, depth, profile) or None."""
    psi = np.asarray(psi, dtype=float)
    if spall is None or spall.get("depth", 0.0) <= 0.0 or spall.get("extent", 0.0) <= 0.0:
        return np.zeros_like(psi)
    profile = spall.get("profile", "ball-path")
    if profile not in PROFILES:
        raise ValueError(f"profile must be one of {PROFILES}, got {profile!r}")
    d, ext = float(spall["depth"]), float(spall["extent"])
    u = _wrap(psi - float(spall["center"]))
    inside = np.abs(u) <= 0.5 * ext
    b = geom.Ro * ext
    if profile == "rectangular":
        h = np.full_like(psi, min(d, _sag(geom.D, 0.5 * b)))
    else:
        s = geom.Ro * (u + 0.5 * ext)
        h = np.minimum(d, _sag(geom.D, np.minimum(s, b - s)))
    return np.where(inside, np.maximum(h, 0.0), 0.0)


# --------------------------------------------------------------------------------------------
# Jones model
# --------------------------------------------------------------------------------------------
def _q_from_scaled(v, Ri):
    return np.array([v[0] * UM, v[1] * UM, v[2] * UM, v[3] * UM / Ri, v[4] * UM / Ri])


def _q_to_scaled(q, Ri):
    q = np.asarray(q, dtype=float)
    return np.array([q[0] / UM, q[1] / UM, q[2] / UM, q[3] * Ri / UM, q[4] * Ri / UM])


def groove_centres(geom: Geometry, q, psi):
    """(A1, A2): inner groove-curvature centre relative to the outer one, per ball."""
    dx, dy, dz, tx, ty = q
    A1 = geom.A * math.sin(geom.alpha0) + dz + geom.Ri * (tx * np.sin(psi) - ty * np.cos(psi))
    A2 = geom.A * math.cos(geom.alpha0) + dx * np.cos(psi) + dy * np.sin(psi)
    return A1, A2


def static_balls(geom: Geometry, q, psi, H):
    """Rigid-ring static (omega = 0) ball state: collinear contacts, closed form."""
    A1, A2 = groove_centres(geom, q, psi)
    s = np.hypot(A1, A2)
    alpha = np.arctan2(A1, A2)
    dtot = s - geom.A - H
    Ki = hertz_constant(geom, alpha, True)
    Ko = hertz_constant(geom, alpha, False)
    r = (Ko / Ki) ** (2.0 / 3.0)                        # delta_i / delta_o
    touch = dtot > 0.0
    do = np.where(touch, dtot / (1.0 + r), 0.5 * dtot)
    di = dtot - do
    Q = np.where(touch, Ko * np.maximum(do, 0.0) ** 1.5, 0.0)
    Lo = (geom.fo - 0.5) * geom.D + H + do
    return dict(A1=A1, A2=A2, alpha=alpha, dtot=dtot, delta_i=di, delta_o=do, Q=Q,
                X1=Lo * np.sin(alpha), X2=Lo * np.cos(alpha), Ki=Ki, Ko=Ko,
                G=Q * np.sin(alpha), Hf=Q * np.cos(alpha), m=geom.Ri * Q * np.sin(alpha))


def ring_residual(geom, psi, G, Hf, mom, loads):
    """Ring equilibrium residual (N; moments divided by R_i)."""
    Fx, Fy, Fz, Mx, My = loads
    c, s = np.cos(psi), np.sin(psi)
    return np.array([
        np.sum(Hf * c) - Fx,
        np.sum(Hf * s) - Fy,
        np.sum(G) - Fz,
        (np.sum(mom * s) - Mx) / geom.Ri,
        (-np.sum(mom * c) - My) / geom.Ri,
    ])


@dataclass
class _Ctx:
    geom: Geometry
    psi: np.ndarray
    H: np.ndarray
    loads: np.ndarray
    omega: float
    control: str
    cf: float
    gy: float
    X1ref: float
    X2ref: float
    jacobian: str = "structured"
    undropped_cache: dict = field(default_factory=dict)


def _ball_state(ctx: _Ctx, X1, X2, A1, A2, H, omega, om_override=None):
    """Per-ball forces and residual for ball-centre positions (X1, X2); vectorised."""
    geom = ctx.geom
    D = geom.D
    Lo = np.hypot(X1, X2)
    Li = np.hypot(A1 - X1, A2 - X2)
    do = Lo - (geom.fo - 0.5) * D - H
    di = Li - (geom.fi - 0.5) * D
    ao = np.arctan2(X1, X2)
    ai = np.arctan2(A1 - X1, A2 - X2)
    sao, cao = X1 / Lo, X2 / Lo
    sai, cai = (A1 - X1) / Li, (A2 - X2) / Li
    Ki = hertz_constant(geom, ai, True)
    Ko = hertz_constant(geom, ao, False)
    Qi = np.where((di > 0.0) & (cai > 0.0), Ki * np.maximum(di, 0.0) ** 1.5, 0.0)
    Qo = np.where((do > 0.0) & (cao > 0.0), Ko * np.maximum(do, 0.0) ** 1.5, 0.0)
    use = np.zeros(np.shape(ai), dtype=bool) if om_override is None else np.isfinite(om_override)
    with np.errstate(invalid="ignore", divide="ignore"):
        # a ball without inner contact deep in a spall can sit exactly past the inner groove
        # centre on the line of the groove centres (alpha_i = alpha_o - 180 deg): its own
        # omega_m is then 0/0 and is not used (convention (d)); keep it out of the arithmetic
        beta, om_m, om_R = kinematics(geom, ai, ao, omega, ctx.control)
    om_m = np.where(use, 0.0, om_m)
    om_R = np.where(use, 0.0, om_R)
    Fc = ctx.cf * 0.5 * geom.mass * geom.dm * om_m ** 2
    Mg = ctx.gy * geom.inertia * om_R * om_m * np.sin(beta)
    if om_override is not None:
        # convention (d): omega_m is the undropped one; F_c and M_g as docs/model.md writes them at
        # that orbital speed and the ball's own angles.  M_g = J omega_R omega_m sin(beta) with
        # omega_R / omega_m = n_o / (g c_o) (independent of alpha_i; = own-angle values times
        # (omega_m_undropped / omega_m_own)^2 wherever the latter is finite)
        ov = np.where(use, om_override, 0.0)
        n_o = 1.0 + geom.g * np.cos(ao)
        c_o = np.cos(ao - beta)
        with np.errstate(invalid="ignore", divide="ignore"):
            spin = np.where(use, n_o / (geom.g * np.where(c_o != 0.0, c_o, 1.0)), 0.0)
        Fc = np.where(use, ctx.cf * 0.5 * geom.mass * geom.dm * ov ** 2, Fc)
        Mg = np.where(use, ctx.gy * geom.inertia * ov ** 2 * spin * np.sin(beta), Mg)
        om_R = np.where(use, ov * spin, om_R)
        om_m = np.where(use, ov, om_m)
    lam_i, lam_o = CONTROLS[ctx.control]
    li = lam_i   # docs/model.md section 4 as written: the friction terms act for every ball
    lo = lam_o
    G = Qi * sai + li * (Mg / D) * cai
    Hf = Qi * cai - li * (Mg / D) * sai
    r1 = G - Qo * sao - lo * (Mg / D) * cao
    r2 = Hf - Qo * cao + lo * (Mg / D) * sao + Fc
    mom = geom.Ri * G - li * geom.fi * Mg
    return dict(X1=X1, X2=X2, A1=A1, A2=A2, H=H, alpha_i=ai, alpha_o=ao, delta_i=di, delta_o=do,
                Q_i=Qi, Q_o=Qo, K_i=Ki, K_o=Ko, beta=beta, omega_m=om_m, omega_R=om_R, F_c=Fc,
                M_g=Mg, G=G, Hf=Hf, m=mom, r1=r1, r2=r2)


def _single_ball_starts(ctx: _Ctx, A1, A2, H, omega):
    """Starting points (scaled) for one ball: the collinear static split (pushed onto the outer
    race at speed), and at speed also the outer-contact-only equilibrium alpha_o = 0, Q_o = F_c."""
    geom = ctx.geom
    Xr = np.array([ctx.X1ref, ctx.X2ref])
    s = math.hypot(A1, A2)
    al = math.atan2(A1, A2)
    dtot = s - geom.A - H
    Ki = float(hertz_constant(geom, al, True))
    Ko = float(hertz_constant(geom, al, False))
    do = dtot / (1.0 + (Ko / Ki) ** (2.0 / 3.0)) if dtot > 0 else 0.5 * dtot
    starts = []
    if omega > 0.0:
        om0 = 0.5 * omega * (1.0 - geom.g * math.cos(al))
        Fc = max(ctx.cf * 0.5 * geom.mass * geom.dm * om0 ** 2, 1e-6)
        do = max(do, (Fc / Ko) ** (2.0 / 3.0))
        do0 = (Fc / float(hertz_constant(geom, 0.0, False))) ** (2.0 / 3.0)
        Lo = (geom.fo - 0.5) * geom.D + H + do
        starts.append((np.array([Lo * math.sin(al), Lo * math.cos(al)]) - Xr) / UM)
        starts.append((np.array([0.0, (geom.fo - 0.5) * geom.D + H + do0]) - Xr) / UM)
    else:
        Lo = (geom.fo - 0.5) * geom.D + H + do
        starts.append((np.array([Lo * math.sin(al), Lo * math.cos(al)]) - Xr) / UM)
    return starts


def _solve_single_ball(ctx: _Ctx, A1, A2, H, omega, x_start=None, override=False):
    """Equilibrium of one ball for fixed groove centres (scipy root, hybr, several starts).

    ``override``: apply convention (d) (used for the pre-equilibrated start of the full
    system); False for the undropped position itself."""
    Xr = np.array([ctx.X1ref, ctx.X2ref])
    a1, a2, h = np.array([A1]), np.array([A2]), np.array([H])

    def f(u):
        X = Xr + u * UM
        ov = _override(ctx, X[:1], X[1:], a1, a2, h) if override else None
        st = _ball_state(ctx, X[:1], X[1:], a1, a2, h, omega, ov)
        return np.array([st["r1"][0], st["r2"][0]]) / KN

    starts = ([] if x_start is None else [np.asarray(x_start, dtype=float)])
    starts += _single_ball_starts(ctx, A1, A2, H, omega)
    best = None
    for x0 in starts:
        sol = optimize.root(f, x0, method="hybr", options=dict(xtol=1e-14, maxfev=2000))
        err = float(np.abs(f(sol.x)).max())
        if best is None or err < best[1]:
            best = (sol, err)
        if err * KN <= 1e-10 * max(1.0, float(np.abs(ctx.loads).max())):
            break
    sol = best[0]
    X = Xr + sol.x * UM
    return X, sol


def _undropped_omega_m(ctx: _Ctx, A1, A2):
    """omega_m of the ball at the same q with H = 0 (convention (d))."""
    key = (float(A1), float(A2))
    hit = ctx.undropped_cache.get(key)
    if hit is not None:
        return hit
    # warm start from the last undropped solve, then the cold starts (see _solve_single_ball)
    X, sol = _solve_single_ball(ctx, A1, A2, 0.0, ctx.omega, ctx.undropped_cache.get("last"))
    ctx.undropped_cache["last"] = sol.x
    st = _ball_state(ctx, X[:1], X[1:], np.array([A1]), np.array([A2]), np.zeros(1), ctx.omega)
    val = float(st["omega_m"][0])
    if len(ctx.undropped_cache) > 10000:
        ctx.undropped_cache.clear()
        ctx.undropped_cache["last"] = sol.x
    ctx.undropped_cache[key] = val
    return val


def _override(ctx: _Ctx, X1, X2, A1, A2, H):
    """Convention (d): balls over the spall (H > 0) without inner contact take the orbital
    speed of their undropped position; returns that speed per ball (NaN: own), or None."""
    if ctx.omega == 0.0 or not np.any(H > 0.0):
        return None
    di = np.hypot(A1 - X1, A2 - X2) - (ctx.geom.fi - 0.5) * ctx.geom.D
    drop = (H > 0.0) & ~((di > 0.0) & (A2 - X2 > 0.0))      # no inner contact (rule (a))
    if not np.any(drop):
        return None
    override = np.full(np.shape(X1), np.nan)
    for j in np.nonzero(drop)[0]:
        override[j] = _undropped_omega_m(ctx, A1[j], A2[j])
    return override


def _evaluate(u, ctx: _Ctx):
    """Full state and scaled residual (2Z+5,) for the scaled unknown vector u."""
    geom = ctx.geom
    Z = geom.Z
    X1 = ctx.X1ref + u[0:2 * Z:2] * UM
    X2 = ctx.X2ref + u[1:2 * Z:2] * UM
    q = _q_from_scaled(u[2 * Z:], geom.Ri)
    A1, A2 = groove_centres(geom, q, ctx.psi)
    H = ctx.H
    override = None
    idle = np.zeros(Z, dtype=bool)
    if ctx.omega == 0.0:
        # convention (c): non-touching balls at the collinear mid-gap position
        s = np.hypot(A1, A2)
        dtot = s - geom.A - H
        idle = dtot <= 0.0
    else:
        override = _override(ctx, X1, X2, A1, A2, H)
    st = _ball_state(ctx, X1, X2, A1, A2, H, ctx.omega, override)
    r_ball = np.empty(2 * Z)
    r_ball[0::2] = st["r1"] / KN
    r_ball[1::2] = st["r2"] / KN
    G, Hf, mom = st["G"], st["Hf"], st["m"]
    if np.any(idle):
        s = np.hypot(A1, A2)
        dtot = s - geom.A - H
        Lo = (geom.fo - 0.5) * geom.D + H + 0.5 * dtot
        Xm1, Xm2 = Lo * A1 / s, Lo * A2 / s
        r_ball[0::2] = np.where(idle, (X1 - Xm1) / UM, r_ball[0::2])
        r_ball[1::2] = np.where(idle, (X2 - Xm2) / UM, r_ball[1::2])
        G = np.where(idle, 0.0, G)
        Hf = np.where(idle, 0.0, Hf)
        mom = np.where(idle, 0.0, mom)
    r_ring = ring_residual(geom, ctx.psi, G, Hf, mom, ctx.loads) / KN
    st.update(G=G, Hf=Hf, m=mom, idle=idle, q=q)
    return np.concatenate([r_ball, r_ring]), st


def _residual_N(r, st, Z):
    """Max-norm residual in N (idle balls' closed-form rows excluded)."""
    rb = np.abs(r[:2 * Z]).reshape(Z, 2)[~st["idle"]]
    vals = [np.abs(r[2 * Z:]).max()]
    if rb.size:
        vals.append(rb.max())
    return float(max(vals) * KN)


def _static_solve(geom, psi, H, loads, q_start=None):
    """Rigid-ring static solution on the 5 ring unknowns (scipy root, hybr)."""
    def f(v):
        q = _q_from_scaled(v, geom.Ri)
        sb = static_balls(geom, q, psi, H)
        return ring_residual(geom, psi, sb["G"], sb["Hf"], sb["m"], loads) / KN

    starts = []
    if q_start is not None:
        starts.append(_q_to_scaled(q_start, geom.Ri))
    Fx, Fy, Fz, Mx, My = loads
    a0 = max(geom.alpha0, math.radians(1.0))
    Ki = float(hertz_constant(geom, a0, True))
    Ko = float(hertz_constant(geom, a0, False))
    Kn = (Ki ** (-2.0 / 3.0) + Ko ** (-2.0 / 3.0)) ** -1.5
    P = max(Fz, 0.0) + math.hypot(Fx, Fy) * math.tan(a0) + math.hypot(Mx, My) / geom.Ri * math.tan(a0)
    P = max(P, 1.0)
    dt0 = (P / (geom.Z * Kn * math.sin(a0))) ** (2.0 / 3.0)
    for fac in (1.0, 3.0, 0.3, 10.0, 0.1):
        dt = fac * dt0
        cA = geom.A * math.cos(geom.alpha0)
        dz = math.sqrt((geom.A + dt) ** 2 - cA ** 2) - geom.A * math.sin(geom.alpha0)
        starts.append(np.array([0.0, 0.0, dz / UM, 0.0, 0.0]))
    best = None
    for v0 in starts:
        sol = optimize.root(f, v0, method="hybr", options=dict(xtol=1e-13, maxfev=5000))
        res = float(np.abs(f(sol.x)).max() * KN)
        if best is None or res < best[1]:
            best = (sol, res)
        if res <= 1e-7 * max(P, 1.0):
            break
    sol, res = best
    q = _q_from_scaled(sol.x, geom.Ri)
    return q, res


def _full_start_from_static(ctx: _Ctx, q_static):
    """Scaled full unknown vector from the rigid-ring static state; non-touching balls are put
    on the outer race at speed (where F_c pushes them)."""
    geom = ctx.geom
    sb = static_balls(geom, q_static, ctx.psi, ctx.H)
    X1, X2 = sb["X1"].copy(), sb["X2"].copy()
    if ctx.omega > 0.0:
        al = sb["alpha"]
        om0 = 0.5 * ctx.omega * (1.0 - geom.g * np.cos(al))
        Fc = np.maximum(ctx.cf * 0.5 * geom.mass * geom.dm * om0 ** 2, 1e-6)
        do_min = (Fc / sb["Ko"]) ** (2.0 / 3.0)
        lift = sb["delta_o"] < do_min
        Lo = (geom.fo - 0.5) * geom.D + ctx.H + np.maximum(sb["delta_o"], do_min)
        X1 = np.where(lift, Lo * np.sin(al), X1)
        X2 = np.where(lift, Lo * np.cos(al), X2)
    u = np.empty(2 * geom.Z + 5)
    u[0:2 * geom.Z:2] = (X1 - ctx.X1ref) / UM
    u[1:2 * geom.Z:2] = (X2 - ctx.X2ref) / UM
    u[2 * geom.Z:] = _q_to_scaled(q_static, geom.Ri)
    return u


def _equilibrated_start(ctx: _Ctx, q):
    """Scaled full unknown vector at ring displacement q with every ball individually in
    equilibrium (its 2x2 problem solved for fixed q): a robust start for the full system."""
    geom = ctx.geom
    A1, A2 = groove_centres(geom, q, ctx.psi)
    u = np.empty(2 * geom.Z + 5)
    for j in range(geom.Z):
        X, _ = _solve_single_ball(ctx, A1[j], A2[j], ctx.H[j], ctx.omega, override=True)
        u[2 * j:2 * j + 2] = (X - np.array([ctx.X1ref, ctx.X2ref])) / UM
    u[2 * geom.Z:] = _q_to_scaled(q, geom.Ri)
    return u


def _per_ball(u, ctx: _Ctx):
    """Residual and the per-ball outputs (Z, 5): ball rows r1, r2 and (G, H, m/R_i) in kN."""
    r, st = _evaluate(u, ctx)
    Z = ctx.geom.Z
    P = np.stack([r[0:2 * Z:2], r[1:2 * Z:2], st["G"] / KN, st["Hf"] / KN,
                  st["m"] / (KN * ctx.geom.Ri)], axis=1)
    return r, P


def _jacobian(u, ctx: _Ctx):
    """Forward-difference Jacobian of the scaled residual exploiting the model's structure.

    Ball j's outputs depend only on its own (X1_j, X2_j) and on q, and the ring rows are sums
    of per-ball contributions, so perturbing every ball's X1 at once (then X2, then each of the
    5 ring unknowns) gives the whole (2Z+5)^2 Jacobian from 8 vectorised evaluations instead of
    2Z+6.  The ring rows are linear in the per-ball (G, H, m).
    """
    Z = ctx.geom.Z
    n = 2 * Z + 5
    c, s = np.cos(ctx.psi), np.sin(ctx.psi)
    _, P0 = _per_ball(u, ctx)
    J = np.zeros((n, n))
    rows = np.arange(Z)
    for comp in (0, 1):
        cols = 2 * rows + comp
        h = 1e-6 * np.maximum(1.0, np.abs(u[cols]))
        du = np.zeros(n)
        du[cols] = h
        _, P1 = _per_ball(u + du, ctx)
        dP = (P1 - P0) / h[:, None]
        J[2 * rows, cols] = dP[:, 0]
        J[2 * rows + 1, cols] = dP[:, 1]
        J[2 * Z + 0, cols] = dP[:, 3] * c
        J[2 * Z + 1, cols] = dP[:, 3] * s
        J[2 * Z + 2, cols] = dP[:, 2]
        J[2 * Z + 3, cols] = dP[:, 4] * s
        J[2 * Z + 4, cols] = -dP[:, 4] * c
    for k in range(5):
        col = 2 * Z + k
        h = 1e-6 * max(1.0, abs(u[col]))
        du = np.zeros(n)
        du[col] = h
        _, P1 = _per_ball(u + du, ctx)
        dP = (P1 - P0) / h
        J[0:2 * Z:2, col] = dP[:, 0]
        J[1:2 * Z:2, col] = dP[:, 1]
        J[2 * Z:, col] = [np.sum(dP[:, 3] * c), np.sum(dP[:, 3] * s), np.sum(dP[:, 2]),
                          np.sum(dP[:, 4] * s), -np.sum(dP[:, 4] * c)]
    return J


def _root(ctx: _Ctx, u0):
    """scipy.optimize.root(method="hybr") on the full 2Z+5 system (structured FD Jacobian)."""
    jac = (lambda u: _jacobian(u, ctx)) if ctx.jacobian == "structured" else None
    sol = optimize.root(lambda u: _evaluate(u, ctx)[0], u0, method="hybr", jac=jac,
                        options=dict(xtol=1e-13, maxfev=200 * (2 * ctx.geom.Z + 5)))
    r, st = _evaluate(sol.x, ctx)
    res = _residual_N(r, st, ctx.geom.Z)
    if not np.isfinite(res):
        res = np.inf        # a NaN would make every later "better than" test of the fallbacks False
    return sol.x, res, int(sol.nfev) + 8 * int(getattr(sol, "njev", 0))


def solve(geom: Geometry, loads, speed_rpm=0.0, control="outer", centrifugal=True,
          gyroscopic=True, cage_angle=0.0, spall=None, x0=None, tol=None,
          jacobian="structured"):
    """Jones quasi-static solution for one load case.

    loads = [Fx, Fy, Fz, Mx, My] (N, N m) on the inner ring; spall = dict(center=rad,
    extent=rad, depth=m, profile="rectangular"|"ball-path") or None; x0: a previous result
    (dict from this function) or its scaled unknown vector ``x``, used as the starting point.
    jacobian: "structured" (default; forward differences in 8 vectorised evaluations using the
    per-ball structure, see :func:`_jacobian`) or "hybr" (MINPACK's own dense forward-difference
    Jacobian, 2Z+5 evaluations) -- same solution, the latter is the naive baseline.
    Returns a dict (SI units, per-ball arrays of length Z).
    """
    if jacobian not in ("structured", "hybr"):
        raise ValueError("jacobian must be 'structured' or 'hybr'")
    if control not in CONTROLS:
        raise ValueError(f"control must be one of {tuple(CONTROLS)}, got {control!r}")
    loads = np.asarray(loads, dtype=float).reshape(5)
    Z = geom.Z
    psi = cage_angle + 2.0 * np.pi * np.arange(Z) / Z
    H = depth_profile(geom, spall, psi)
    omega = 2.0 * np.pi * float(speed_rpm) / 60.0
    c0 = (geom.fo - 0.5) * geom.D
    ctx = _Ctx(geom, psi, H, loads, omega, control, float(bool(centrifugal)),
               float(bool(gyroscopic)), c0 * math.sin(geom.alpha0), c0 * math.cos(geom.alpha0),
               jacobian)
    Fscale = max(1.0, np.abs(loads[:3]).max(), np.abs(loads[3:]).max() / geom.Ri)
    if tol is None:
        tol = 1e-9 * Fscale
    nfev = 0
    u = None
    res = np.inf
    q_static, static_res = None, None
    if x0 is not None:
        u0 = np.asarray(x0["x"] if isinstance(x0, dict) else x0, dtype=float)
        u, res, n = _root(ctx, u0)
        nfev += n
    if not res <= tol:
        q_static, static_res = _static_solve(geom, psi, H, loads)
        u0 = _full_start_from_static(ctx, q_static)
        u, res, n = _root(ctx, u0)
        nfev += n
        if not res <= tol and omega > 0.0:
            # fallback: every ball pre-equilibrated (2x2 solves) at the static q.  Balls that
            # have lost inner contact at speed must roll round to alpha_o ~ 0 on the outer race
            # against a tiny tangential stiffness, which stalls hybr from the collinear start.
            u_eq = _equilibrated_start(ctx, q_static)
            ue, re_, n = _root(ctx, u_eq)
            nfev += n
            if re_ < res:
                u, res = ue, re_
        if not res <= tol and omega > 0.0:
            # fallback: continuation in speed; at a step where hybr fails from the previous
            # step, the balls are re-equilibrated at that step's q and hybr is retried (a
            # failed intermediate step does not stop the ramp, only the final step counts)
            for nsteps in (8, 32):
                ub = None
                for k in range(1, nsteps + 1):
                    ck = _Ctx(geom, psi, H, loads, omega * k / nsteps, control, ctx.cf, ctx.gy,
                              ctx.X1ref, ctx.X2ref, jacobian)
                    if ub is None:
                        ub = _equilibrated_start(ck, q_static)
                    u1, r1, n = _root(ck, ub)
                    nfev += n
                    if not r1 <= tol:
                        ue = _equilibrated_start(ck, _q_from_scaled(u1[2 * Z:], geom.Ri))
                        u2, r2, n = _root(ck, ue)
                        nfev += n
                        if r2 < r1:
                            u1, r1 = u2, r2
                    ub = u1
                if r1 < res:
                    u, res = ub, r1
                if res <= tol:
                    break
        if not res <= tol and np.any(H > 0.0):
            # fallback: continuation in the spall depth profile (H scaled from 0 to 1) from the
            # healthy solution at the same speed; the gates of conventions (b)-(d) make the
            # residual discontinuous, and a ball partly dropped into the spall can leave hybr
            # stuck on a switching surface when started from the dropped position.
            healthy = solve(geom, loads, speed_rpm, control, centrifugal, gyroscopic, cage_angle,
                            None, None, tol, jacobian)
            nfev += healthy["nfev"]
            for nsteps in (4, 16):
                ok = healthy["converged"]
                ub = healthy["x"]
                for k in range(1, nsteps + 1):
                    ck = _Ctx(geom, psi, H * k / nsteps, loads, omega, control, ctx.cf, ctx.gy,
                              ctx.X1ref, ctx.X2ref, jacobian)
                    ub, rk, n = _root(ck, ub)
                    nfev += n
                    if not rk <= tol:
                        ok = False
                        break
                if ok:
                    u, res = ub, rk
                    break
    r, st = _evaluate(u, ctx)
    res = _residual_N(r, st, Z)
    a_i, b_i, p_i = contact_ellipse(geom, st["alpha_i"], st["Q_i"], True)
    a_o, b_o, p_o = contact_ellipse(geom, st["alpha_o"], st["Q_o"], False)
    return dict(
        converged=bool(res <= tol), residual=res, tol=tol, nfev=nfev, x=u,
        q=st["q"], psi=psi, spall_depth=H, cage_angle=float(cage_angle), omega=omega,
        X1=st["X1"], X2=st["X2"],
        alpha_i=st["alpha_i"], alpha_o=st["alpha_o"], Q_i=st["Q_i"], Q_o=st["Q_o"],
        delta_i=st["delta_i"], delta_o=st["delta_o"], K_i=st["K_i"], K_o=st["K_o"],
        F_c=st["F_c"], M_g=st["M_g"], omega_m=st["omega_m"], omega_R=st["omega_R"],
        beta=st["beta"], ball_G=st["G"], ball_H=st["Hf"], ball_m=st["m"], idle=st["idle"],
        cage_speed=float(np.mean(st["omega_m"])),
        a_i=a_i, b_i=b_i, p_max_i=p_i, a_o=a_o, b_o=b_o, p_max_o=p_o,
        q_static=q_static, static_residual=static_res,
    )


def solve_sweep(geom: Geometry, loads, cage_angles, speed_rpm=0.0, control="outer",
                centrifugal=True, gyroscopic=True, spall=None, x0=None, jacobian="structured"):
    """Loop over cage angles, each solve warm-started from the previous solution.

    Returns a dict of stacked arrays (leading axis = cage angle) plus ``solutions`` (list).
    """
    sols = []
    prev = x0
    for th in np.asarray(cage_angles, dtype=float):
        s = solve(geom, loads, speed_rpm, control, centrifugal, gyroscopic, float(th), spall, prev,
                  jacobian=jacobian)
        sols.append(s)
        prev = s
    keys = ("q", "psi", "alpha_i", "alpha_o", "Q_i", "Q_o", "delta_i", "delta_o", "F_c", "M_g",
            "omega_m", "spall_depth", "residual", "converged", "cage_speed")
    out = {k: np.array([s[k] for s in sols]) for k in keys}
    out["cage_angle"] = np.asarray(cage_angles, dtype=float)
    out["solutions"] = sols
    return out


def thrust_closed_form(geom: Geometry, Fa):
    """Pure thrust at omega = 0 with K at the loaded angle: solve
    Fa = Z K_n(alpha) (BD)^1.5 sin(alpha) (cos a0/cos alpha - 1)^1.5 for alpha (brentq).
    Returns (alpha, Q, axial deflection)."""
    a0 = geom.alpha0

    def f(al):
        Ki = hertz_constant(geom, al, True)
        Ko = hertz_constant(geom, al, False)
        Kn = (Ki ** (-2.0 / 3.0) + Ko ** (-2.0 / 3.0)) ** -1.5
        return geom.Z * Kn * geom.A ** 1.5 * math.sin(al) * (math.cos(a0) / math.cos(al) - 1.0) ** 1.5 - Fa

    al = optimize.brentq(f, a0 + 1e-12, math.radians(89.0), xtol=1e-15)
    Q = Fa / (geom.Z * math.sin(al))
    dz = geom.A * math.sin(al) / math.cos(al) * math.cos(a0) - geom.A * math.sin(a0)
    return al, Q, dz


# --------------------------------------------------------------------------------------------
# A rigid shaft on N bearings (docs/model.md section 10)
# --------------------------------------------------------------------------------------------
def _set_frames(z, s):
    """(G, L) = (M T, T^T M) of a bearing at axial position z with facing s."""
    M = np.diag([1.0, s, s, 1.0, s])
    T = np.eye(5)
    T[0, 4] = z
    T[1, 3] = -z
    return M @ T, T.T @ M


def solve_set(geoms, positions, facings, preloads, springs, loads, speed_rpm=0.0, control="outer",
              cage_angle=0.0, offsets=None, tol=None):
    """Shaft on N bearings, docs/model.md section 10, written from the page alone: bearing k at z_k with
    facing s_k, q_k = M_k T_k q_s + [0, 0, e_k, 0, 0] (rigid; e_k from the closed-form thrust
    at P_k, :func:`thrust_closed_form`, unless ``offsets`` are given) or, for a spring bearing,
    with its axial component replaced by its own approach v_k (one more unknown; u_k = (M T q)_z
    - v_k, one more equation R_k,z = P_k).  Unknowns: every ball of every bearing, q_s, v;
    scipy.optimize.root(hybr) with MINPACK's dense forward-difference Jacobian, from the
    rigid-ring static solution (closed-form balls, hybr on the shaft unknowns).  Ball j of
    bearing k sits at s_k (cage_angle + 2 pi j / Z) in its own frame.

    Returns dict(q, v, u, e, R (N, 5) own-frame loads each bearing carries, per-bearing dicts
    ``bearings`` (alpha_i, alpha_o, Q_i, Q_o), converged, residual (N), nfev)."""
    N = len(geoms)
    loads = np.asarray(loads, float).reshape(5)
    springs = [bool(x) for x in springs]
    P = np.asarray(preloads, float)
    if offsets is None:
        e = np.array([0.0 if (springs[k] or P[k] <= 0) else thrust_closed_form(geoms[k], P[k])[2]
                      for k in range(N)])
    else:
        e = np.where(springs, 0.0, np.asarray(offsets, float))
    fr = [_set_frames(positions[k], facings[k]) for k in range(N)]
    sp_idx = [k for k in range(N) if springs[k]]
    Lr = max(max(g.Ri for g in geoms), max(abs(z) for z in positions))
    omega = 2.0 * np.pi * float(speed_rpm) / 60.0
    psis = [facings[k] * (cage_angle + 2.0 * np.pi * np.arange(g.Z) / g.Z) for k, g in enumerate(geoms)]
    Fscale = max(1.0, np.abs(loads[:3]).max(), np.abs(loads[3:]).max() / Lr, P.max(initial=0.0))
    tol = 1e-9 * Fscale if tol is None else tol

    def shaft_q(w):
        return np.array([w[0] * UM, w[1] * UM, w[2] * UM, w[3] * UM / Lr, w[4] * UM / Lr])

    def bearing_q(w):
        qs = shaft_q(w)
        out = []
        for k in range(N):
            q = fr[k][0] @ qs
            if springs[k]:
                q[2] = w[5 + sp_idx.index(k)] * UM
            else:
                q[2] += e[k]
            out.append(q)
        return out

    def shaft_residual(Rs):
        r = -loads.copy()
        for k in range(N):
            r += fr[k][1] @ Rs[k]
        r[3:] /= Lr
        extra = [Rs[k][2] - P[k] for k in sp_idx]
        return np.concatenate([r, extra]) / KN

    def reactions(geom, G, Hf, mom, psi):
        R = ring_residual(geom, psi, G, Hf, mom, np.zeros(5))
        R[3:] *= geom.Ri
        return R

    def static_f(w):
        Rs = []
        for k, q in enumerate(bearing_q(w)):
            sb = static_balls(geoms[k], q, psis[k], np.zeros(geoms[k].Z))
            Rs.append(reactions(geoms[k], sb["G"], sb["Hf"], sb["m"], psis[k]))
        return shaft_residual(Rs)

    n_w = 5 + len(sp_idx)
    v0 = [thrust_closed_form(geoms[k], P[k])[2] / UM if P[k] > 0 else 0.0 for k in sp_idx]
    starts = [np.concatenate([np.zeros(5), v0])]
    for dz in (1e-6, 1e-5, -1e-5):
        starts.append(np.concatenate([[0.0, 0.0, dz / UM, 0.0, 0.0], v0]))
    best = None
    for w0 in starts:
        sol = optimize.root(static_f, w0, method="hybr", options=dict(xtol=1e-14, maxfev=5000))
        res = float(np.abs(static_f(sol.x)).max() * KN)
        if best is None or res < best[1]:
            best = (sol.x, res)
        if res <= tol:
            break
    w_static = best[0]

    ctxs = []
    for k, g in enumerate(geoms):
        c0 = (g.fo - 0.5) * g.D
        ctxs.append(_Ctx(g, psis[k], np.zeros(g.Z), np.zeros(5), omega, control, 1.0, 1.0,
                         c0 * math.sin(g.alpha0), c0 * math.cos(g.alpha0), "hybr"))
    nb = [2 * g.Z for g in geoms]
    off = np.concatenate([[0], np.cumsum(nb)])

    def full(u, cs):
        w = u[off[-1]:]
        r_all, Rs, sts = [], [], []
        for k, q in enumerate(bearing_q(w)):
            uk = np.concatenate([u[off[k]:off[k + 1]], _q_to_scaled(q, geoms[k].Ri)])
            r, st = _evaluate(uk, cs[k])
            r_all.append(r[:nb[k]])
            R = r[nb[k]:] * KN
            R[3:] *= geoms[k].Ri
            Rs.append(R)
            sts.append(st)
        return np.concatenate(r_all + [shaft_residual(Rs)]), Rs, sts

    def start_from(w, cs):
        parts = []
        for k, q in enumerate(bearing_q(w)):
            parts.append(_full_start_from_static(cs[k], q)[:nb[k]])
        return np.concatenate(parts + [w])

    def root(u0, cs):
        sol = optimize.root(lambda u: full(u, cs)[0], u0, method="hybr",
                            options=dict(xtol=1e-13, maxfev=200 * (off[-1] + n_w)))
        r = full(sol.x, cs)[0]
        return sol.x, float(np.abs(r).max() * KN), int(sol.nfev)

    u, res, nfev = root(start_from(w_static, ctxs), ctxs)
    if not res <= tol and omega > 0.0:
        for nsteps in (8, 32):
            ub = None
            for i in range(1, nsteps + 1):
                cs = [_Ctx(c.geom, c.psi, c.H, c.loads, omega * i / nsteps, control, 1.0, 1.0,
                           c.X1ref, c.X2ref, "hybr") for c in ctxs]
                ub = start_from(w_static, cs) if ub is None else ub
                ub, r1, n = root(ub, cs)
                nfev += n
            if r1 < res:
                u, res = ub, r1
            if res <= tol:
                break
    _, Rs, sts = full(u, ctxs)
    w = u[off[-1]:]
    qs = shaft_q(w)
    v = np.zeros(N)
    uu = np.zeros(N)
    for j, k in enumerate(sp_idx):
        v[k] = w[5 + j] * UM
        uu[k] = (fr[k][0] @ qs)[2] - v[k]
    return dict(q=qs, v=v, u=uu, e=e, R=np.array(Rs), converged=bool(res <= tol), residual=res,
                nfev=nfev, bearings=[dict(alpha_i=st["alpha_i"], alpha_o=st["alpha_o"], Q_i=st["Q_i"],
                                          Q_o=st["Q_o"]) for st in sts])


if __name__ == "__main__":  # quick self-check against docs/reference-data.md
    g = HARRIS_218
    hi = hertz_constant(g, g.alpha0, True, return_all=True)
    ho = hertz_constant(g, g.alpha0, False, return_all=True)
    print("K_i = %.4e N/mm^1.5 (F %.4f, kappa %.3f)" % (hi["K"] / 1e3 ** 1.5, hi["F"], hi["kappa"]))
    print("K_o = %.4e N/mm^1.5 (F %.4f, kappa %.3f)" % (ho["K"] / 1e3 ** 1.5, ho["F"], ho["kappa"]))
    for Fa in (22250.0, 17800.0):
        s = solve(g, [0, 0, Fa, 0, 0])
        print("Fa %.0f N: alpha %.3f deg  Q %.1f N  dz %.4f mm  conv %s res %.2e N nfev %d"
              % (Fa, np.degrees(s["alpha_i"][0]), s["Q_i"][0], s["q"][2] * 1e3, s["converged"],
                 s["residual"], s["nfev"]))
