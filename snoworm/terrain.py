"""Wheel-terrain laws of the SnoWorm terrain model (paper section 3, docs/model.md section 2).

Every function here is a pure NumPy kernel, vectorised over any array shape (wheels, axles,
segments, batch members).  They are the single implementation of each law: the chain dynamics,
the steady-state solver, the terrain-curve plots and the calibration all call them.  Parameter
values live in :mod:`snoworm.config.params` (named parameter sets); this module holds no defaults.

Sign conventions: forward is positive.  ``V`` is the wheel's longitudinal ground speed [m/s],
``omega`` its spin rate [rad/s] (positive rolling forward), ``F_n`` its normal load [N].
Forces returned are per wheel, positive forward on the vehicle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "TerrainParams",
    "smooth_sign",
    "slip",
    "STANDSTILL_LAWS",
    "shear_slip",
    "shear_displacement_rate",
    "SINKAGE_LAWS",
    "SINKAGE_KEYS",
    "sinkage_rate",
    "sinkage_resistance_factor",
    "traction_force",
    "resistance_force",
    "resistance_torque",
    "wheel_reaction_torque",
    "normal_load_N",
    "gravity_force_N",
    "sled_force_N",
    "traction_coefficients",
    "traction_from_coefficients",
    "resistance_coefficients",
    "resistance_from_coefficients",
    "torque_coefficient",
    "torque_from_coefficient",
    "free_rolling_coefficient",
    "free_rolling_torque",
    "TerrainProfile",
    "STEP_WIDTH_M",
    "patch_profile",
    "random_profile",
    "gaussian_field",
]


@dataclass(frozen=True)
class TerrainParams:
    """Coefficients of the terrain model (paper Table 3 and docs/model.md section 2).

    Parameters
    ----------
    b_tF : float
        Slip-to-tractive-force coefficient of Eq. 2 (unitless).
    b_trF : float
        Terrain resistance force coefficient of Eq. 3 (unitless).
    A : float
        Terrain coefficient exponent of Eq. 3 (unitless).
    peak_exponent_d : float
        Exponent ``d`` of X_t in the peak factor of Eq. 2 (``X_t**d``).  The paper's OCR is
        illegible there; ``d = 2`` satisfies every claim of the paper, ``d = 1`` is the
        literal reading (docs/model.md section 2).
    tau0, tau1 : float
        Resistance-torque law ``T_rr = F_n R_w (tau0 + tau1 (1 - X)) sgn(omega)``, fitted to
        Table 2 (docs/model.md section 2; the paper names the torque but never writes it out).
    slip_eps_mps : float
        Regularisation speed ``v_eps`` of the slip denominator (Eq. 1 made finite at
        ``omega = 0``).  Steady results do not depend on it.
    sign_eps_mps : float
        Speed scale ``v_s`` of the smooth sign ``tanh(V / v_s)`` used in Eq. 3 and in the
        resistance torque.
    torque_balance : {"contact", "traction"}
        ``"contact"``: ``J dw/dt = T_m - R_w (F_t - F_tr) - T_rr`` (docs/model.md default).
        ``"traction"``: ``J dw/dt = T_m - R_w F_t - T_rrB`` with
        ``T_rrB = 1.601 F_n R_w (1 - X) sgn(omega)``; same chassis motion and steady slips.
    standstill : {"regularised", "shear"}
        Law of the slip near rest (docs/model.md section 2, "Standstill").  ``"regularised"``:
        Eq. 1 with the denominator floored at ``slip_eps_mps`` (:func:`slip`), a viscous law at
        rest.  ``"shear"``: a Janosi-Hanamoto shear-displacement state ``j`` per axle
        (:func:`shear_displacement_rate`), slip ``clip(j / K, -1, 1)`` (:func:`shear_slip`), a
        spring at rest: a stopped wheel holds until its peak traction is exceeded.
    shear_modulus_K_m : float or None
        Shear deformation modulus ``K`` [m] of the ``"shear"`` law (None with ``"regularised"``,
        which does not use it).
    sinkage : {"off", "slip"}
        ``"slip"``: a slip-sinkage state ``z`` per axle (:func:`sinkage_rate`) that raises the
        resistance of Eq. 3 by ``1 + z / z_ref`` (docs/model.md section 2, "Slip-sinkage").
    sinkage_rate, sinkage_onset_slip, sinkage_relax_length_m, sinkage_max_m, sinkage_ref_m : float or None
        ``c_z`` (m of sinkage per m of slip displacement beyond the onset), ``i_0``, ``L_relax`` [m],
        ``z_max`` [m] and ``z_ref`` [m] of the ``"slip"`` sinkage law (None with ``"off"``).
    """

    b_tF: float
    b_trF: float
    A: float
    peak_exponent_d: float
    tau0: float
    tau1: float
    slip_eps_mps: float
    sign_eps_mps: float
    torque_balance: str = "contact"
    standstill: str = "regularised"
    shear_modulus_K_m: float | None = None
    sinkage: str = "off"
    sinkage_rate: float | None = None
    sinkage_onset_slip: float | None = None
    sinkage_relax_length_m: float | None = None
    sinkage_max_m: float | None = None
    sinkage_ref_m: float | None = None

    def __post_init__(self):
        if self.standstill not in STANDSTILL_LAWS:
            raise ValueError(f"standstill must be one of {STANDSTILL_LAWS}, got {self.standstill!r}")
        if self.standstill == "shear" and self.shear_modulus_K_m is None:
            raise ValueError("standstill 'shear' needs shear_modulus_K_m (the shear deformation modulus K, m)")
        if self.sinkage not in SINKAGE_LAWS:
            raise ValueError(f"sinkage must be one of {SINKAGE_LAWS}, got {self.sinkage!r}")
        missing = [k for k in SINKAGE_KEYS if getattr(self, k) is None]
        if self.sinkage == "slip" and missing:
            raise ValueError(f"sinkage 'slip' needs {', '.join(missing)}")


#: The laws of the slip near rest (:attr:`TerrainParams.standstill`).
STANDSTILL_LAWS = ("regularised", "shear")

#: The sinkage laws (:attr:`TerrainParams.sinkage`) and the coefficients of ``"slip"``.
SINKAGE_LAWS = ("off", "slip")
SINKAGE_KEYS = ("sinkage_rate", "sinkage_onset_slip", "sinkage_relax_length_m", "sinkage_max_m", "sinkage_ref_m")

#: Coefficient of the "traction" torque-balance convention (docs/model.md section 2).
TRACTION_BALANCE_TAU = 1.601

# literal constants of the laws as 0-d arrays: NumPy multiplies an array by a 0-d array ~2x
# faster than by a Python float (same IEEE result)
_ONE, _MINUS_ONE, _C28, _C4 = np.array(1.0), np.array(-1.0), np.array(2.8), np.array(4.0)


def smooth_sign(u, scale):
    """Smooth sign ``tanh(u / scale)``, used in place of ``sgn`` in Eq. 3 and ``T_rr``."""
    return np.tanh(u / scale)


def slip(wheel_speed_mps, V, eps_mps):
    """Regularised longitudinal slip, Eq. 1.

    ``i = (R_w w - V) / max(|R_w w|, |V|, v_eps)``, which equals Eq. 1 whenever the wheel
    drives forward faster than both the ground speed and ``v_eps``; it is finite for a
    locked (``R_w w = 0``) or stopped wheel and is ``+1`` for a locked wheel sliding backward.
    A wheel spinning against its ground speed would exceed 1 in magnitude; slip is clipped
    to [-1, 1] (full spin or full skid).

    Parameters
    ----------
    wheel_speed_mps : array_like
        Wheel circumferential speed ``R_w * omega`` [m/s].
    V : array_like
        Longitudinal ground speed of the wheel [m/s].
    eps_mps : float
        Regularisation speed ``v_eps`` [m/s].

    Returns
    -------
    ndarray
        Slip, in [-1, 1].
    """
    den = np.maximum(np.maximum(np.abs(wheel_speed_mps), np.abs(V)), eps_mps)
    return np.minimum(np.maximum((wheel_speed_mps - V) / den, _MINUS_ONE), _ONE)


def shear_displacement_rate(wheel_speed_mps, V, j_m, K_m):
    """Rate of the shear displacement ``j`` under a wheel [m/s] (docs/model.md section 2, "Standstill").

    ``dj/dt = (R_w w - V) - max(|R_w w|, |V|) j / K``

    The first term is the slip velocity of the contact: at rest it integrates into the shear
    displacement of the snow under the wheel (Janosi & Hanamoto 1961: the shear stress builds
    with the displacement ``j`` on the scale ``K``).  The second relaxes ``j`` over a rolling
    distance ``K``: at any steady rolling with ``R_w w`` or ``V`` non-zero, ``j / K`` tends to
    ``(R_w w - V) / max(|R_w w|, |V|)``, Eq. 1's slip (unclipped), whatever ``K``: the
    steady-state results do not depend on ``K``.  At rest (``R_w w = V = 0``) ``j`` stays put,
    so the traction it sets, Eq. 2 at ``i = clip(j / K, -1, 1)`` (:func:`shear_slip`), holds
    like a spring.

    Parameters
    ----------
    wheel_speed_mps : array_like
        Wheel circumferential speed ``R_w * omega`` [m/s].
    V : array_like
        Longitudinal ground speed of the wheel [m/s].
    j_m : array_like
        Shear displacement [m].
    K_m : float
        Shear deformation modulus ``K`` [m].

    Returns
    -------
    ndarray
        ``dj/dt`` [m/s].
    """
    return (wheel_speed_mps - V) - np.maximum(np.abs(wheel_speed_mps), np.abs(V)) * j_m / K_m


def shear_slip(j_m, K_m):
    """The slip of the shear-displacement law: ``i = clip(j / K, -1, 1)`` (Eq. 1 at steady rolling).

    Used in Eq. 2 in place of :func:`slip` when ``TerrainParams.standstill == "shear"``.
    """
    return np.minimum(np.maximum(j_m / K_m, _MINUS_ONE), _ONE)


def sinkage_rate(wheel_speed_mps, V, i, z_m, p: TerrainParams):
    """Rate of the slip-sinkage ``z`` of an axle [m/s] (docs/model.md section 2, "Slip-sinkage"; assumed law).

    ``dz/dt = c_z |R_w w - V| max(0, |i| - i_0) (1 - z / z_max) - z |V| / L_relax``

    A wheel that slips beyond the onset ``i_0`` digs in, in proportion to the slip displacement
    (the form of the slip-sinkage models of Lyasko 2010 and Ding et al. 2011, where sinkage grows
    with slip); the dug-in depth saturates at ``z_max`` and is left behind as the wheel rolls on,
    over a ground distance ``L_relax``.  Below the onset a rolling wheel keeps ``z = 0``: steady
    states at ``|i| <= i_0`` are those without the law.

    Parameters
    ----------
    wheel_speed_mps, V : array_like
        Wheel circumferential speed ``R_w w`` and ground speed [m/s].
    i : array_like
        Slip (Eq. 1, or the shear law's).
    z_m : array_like
        Sinkage [m].
    p : TerrainParams
        Uses ``sinkage_rate`` (``c_z``), ``sinkage_onset_slip`` (``i_0``), ``sinkage_max_m`` and
        ``sinkage_relax_length_m``.
    """
    dig = p.sinkage_rate * np.abs(wheel_speed_mps - V) * np.maximum(np.abs(i) - p.sinkage_onset_slip, 0.0)
    return dig * (1.0 - z_m / p.sinkage_max_m) - z_m * np.abs(V) / p.sinkage_relax_length_m


def sinkage_resistance_factor(z_m, p: TerrainParams):
    """Factor ``1 + z / z_ref`` on the resistance of Eq. 3 of a wheel sunk by ``z`` (assumed law)."""
    return 1.0 + z_m / p.sinkage_ref_m


def traction_force(i, F_n, X, p: TerrainParams):
    """Magic-Formula tractive force per wheel, Eq. 2 (as read in docs/model.md section 2).

    ``F_t = F_n X^d b_tF sin(2.8 X atan(atan(4 X^2 i)))`` -- the OCR's "cot" read as atan, E = 1.
    Odd in slip, bounded by ``F_n X^d b_tF``.

    Parameters
    ----------
    i : array_like
        Slip (Eq. 1).
    F_n : array_like
        Normal load on the wheel [N].
    X : array_like
        Terrain coefficient X_t (> 0).
    p : TerrainParams
        Terrain coefficients (uses ``b_tF`` and ``peak_exponent_d``).

    Returns
    -------
    ndarray
        Tractive force [N], positive forward.
    """
    return traction_from_coefficients(i, traction_coefficients(F_n, X, p))


def traction_coefficients(F_n, X, p: TerrainParams):
    """The slip-independent factors of Eq. 2: ``(F_n X^d b_tF, 2.8 X, 4 X^2)``.

    :func:`traction_force` is ``traction_from_coefficients(i, traction_coefficients(F_n, X, p))``;
    the chain kernel computes these factors once when X_t does not depend on position (a constant
    profile), which is the same law evaluated in two stages (identical floating-point operations).
    """
    return F_n * X**p.peak_exponent_d * p.b_tF, _C28 * X, _C4 * X * X


def traction_from_coefficients(i, coef):
    """Eq. 2 from the factors of :func:`traction_coefficients`: ``peak sin(a atan(atan(b i)))``."""
    peak, a, b = coef
    return peak * np.sin(a * np.arctan(np.arctan(b * i)))


def resistance_force(V, F_n, X, p: TerrainParams):
    """Terrain resistance force per wheel, Eq. 3: ``F_tr = b_trF F_n sgn(V) / X^A``.

    ``sgn`` is smoothed as ``tanh(V / v_s)``.  Returned with the sign of ``V`` (it opposes the
    motion: the chassis sees ``F_t - F_tr``).
    """
    return resistance_from_coefficients(V, resistance_coefficients(F_n, X, p), p)


def resistance_coefficients(F_n, X, p: TerrainParams):
    """The speed-independent factors of Eq. 3: ``(b_trF F_n, X^A)`` (see :func:`traction_coefficients`)."""
    return p.b_trF * F_n, X**p.A


def resistance_from_coefficients(V, coef, p: TerrainParams):
    """Eq. 3 from the factors of :func:`resistance_coefficients`."""
    bF, XA = coef
    return bF * smooth_sign(V, p.sign_eps_mps) / XA


def resistance_torque(omega_mps, F_n, X, R_w, p: TerrainParams):
    """Terrain resistance torque per wheel [N m], fitted law of docs/model.md section 2.

    ``T_rr = F_n R_w (tau0 + tau1 (1 - X)) sgn(omega)`` (``"contact"`` balance) or
    ``T_rrB = 1.601 F_n R_w (1 - X) sgn(omega)`` (``"traction"`` balance).

    Parameters
    ----------
    omega_mps : array_like
        Wheel circumferential speed ``R_w * omega`` [m/s] (only its sign matters).
    """
    return torque_from_coefficient(omega_mps, torque_coefficient(F_n, X, R_w, p), p)


def torque_coefficient(F_n, X, R_w, p: TerrainParams):
    """The speed-independent factor ``F_n R_w coef(X)`` of the resistance torque."""
    if p.torque_balance == "traction":
        coef = TRACTION_BALANCE_TAU * (1.0 - X)
    else:
        coef = p.tau0 + p.tau1 * (1.0 - X)
    return F_n * R_w * coef


def torque_from_coefficient(omega_mps, coef, p: TerrainParams):
    """The resistance torque from the factor of :func:`torque_coefficient`."""
    return coef * smooth_sign(omega_mps, p.sign_eps_mps)


def free_rolling_coefficient(F_n, X, R_w, p: TerrainParams):
    """The speed-independent factor of :func:`free_rolling_torque`, ``F_n R_w c_free(X)``.

    ``"contact"`` balance: ``c_free = min(b_trF / X^A, tau0 + tau1 (1 - X))``; ``"traction"``: 0.
    """
    if p.torque_balance == "traction":
        return F_n * R_w * (0.0 * X)
    return F_n * R_w * np.minimum(p.b_trF / X**p.A, p.tau0 + p.tau1 * (1.0 - X))


def free_rolling_torque(omega_mps, F_n, X, R_w, p: TerrainParams):
    """Resistance torque of a wheel that rolls free, with no drivetrain behind it [N m] (docs/model.md
    section 2, "Terrain resistance torque").

    The fitted ``T_rr`` of :func:`resistance_torque` holds what the *driven* wheels of Table 2 lost,
    the driveline's losses included.  It splits as ``T_rr = T_free + T_loss``: ``T_free`` is the
    terrain's share, the torque that makes a free wheel resist with exactly Eq. 3, and ``T_loss``
    the driveline losses (derived from the fit, ``>= 0``):

    * ``"contact"`` balance, ``J dw/dt = T_m - R_w (F_t - F_tr) - T``: a free wheel (``T_m = 0``) in
      steady rolling passes ``F_t - F_tr = -T / R_w`` to the chassis, which is ``-F_tr`` (Eq. 3) exactly
      when ``T_free = R_w F_tr = F_n R_w b_trF / X^A sgn(w)`` (its traction is then 0, at zero slip);
    * ``"traction"`` balance, ``J dw/dt = T_m - R_w F_t - T``: the chassis receives ``F_t - F_tr``
      whatever the wheel torque, and a free wheel is at ``F_t = 0`` when ``T_free = 0``.

    ``T_free`` is capped at ``T_rr`` (``T_loss >= 0``): the fit, made on ``X`` in [0.65, 1], falls below
    ``R_w F_tr`` only on snow looser than ``X`` = 0.018 (FrostyBoy), where a free wheel then resists as a
    driven one.  ``sgn`` is smoothed as in :func:`resistance_torque`.

    Parameters
    ----------
    omega_mps : array_like
        Wheel circumferential speed ``R_w * omega`` [m/s] (only its sign matters).
    F_n, X, R_w : array_like
        Normal load [N], terrain coefficient, wheel radius [m].
    """
    return torque_from_coefficient(omega_mps, free_rolling_coefficient(F_n, X, R_w, p), p)


def wheel_reaction_torque(F_t, F_tr, T_rr, R_w, p: TerrainParams):
    """Terrain torque opposing the motor in the wheel torque balance [N m].

    ``J dw/dt = T_m - wheel_reaction_torque``; ``R_w (F_t - F_tr) + T_rr`` for the
    ``"contact"`` convention, ``R_w F_t + T_rrB`` for ``"traction"`` (docs/model.md section 2).
    """
    if p.torque_balance == "traction":
        return R_w * F_t + T_rr
    return R_w * (F_t - F_tr) + T_rr


def normal_load_N(weight_per_wheel_N, sin_theta, cos_theta, transfer):
    """Normal load per wheel on the front and rear axle of a segment on a grade (docs/model.md section 7).

    ``F_n = W (cos(theta) -+ t sin(theta))``, front ``-``, rear ``+``, with ``W = m g / n_wheels`` the
    level-ground load per wheel and ``t = 2 h / b`` the static pitch load transfer of a centre of
    mass at height ``h`` over a wheelbase ``b`` (0: none).  Every terrain law that uses the normal
    load (Eqs. 2 and 3, the resistance torque) takes this one.  At ``theta = 0`` it is ``W``.

    Parameters
    ----------
    weight_per_wheel_N : array_like, shape (..., N)
        ``m g / n_wheels`` of each segment [N].
    sin_theta, cos_theta : array_like, shape (..., N)
        Sine and cosine of the grade under each segment (positive uphill).
    transfer : array_like, shape (..., N)
        ``2 h / b`` of each segment.

    Returns
    -------
    ndarray, shape (..., N, 2)
        Normal load per wheel, front and rear axle [N].
    """
    shift = transfer * sin_theta
    return np.stack([weight_per_wheel_N * (cos_theta - shift), weight_per_wheel_N * (cos_theta + shift)], axis=-1)


def gravity_force_N(mass_kg, gravity_mps2, sin_theta):
    """Gravity along the track on a segment, ``-m g sin(theta)`` [N] (forward positive; docs/model.md section 7)."""
    return -mass_kg * gravity_mps2 * sin_theta


def sled_force_N(weight_N, friction, sin_theta, cos_theta, direction):
    """Backward pull of a towed sled on the rear segment [N] (docs/model.md section 4, "Towed load").

    ``F = m_s g (sin(theta) + mu cos(theta) d)``: gravity along the grade and Coulomb friction on the
    snow, which opposes the sled's motion: ``d`` is the direction of motion, the smooth sign
    ``tanh(v / v_s)`` of the rear segment's speed in the kernel (at rest only gravity), 1 for steady
    forward motion.

    Parameters
    ----------
    weight_N : array_like
        The sled's weight ``m_s g`` [N].
    friction : array_like
        Sliding friction coefficient ``mu`` of the sled on the snow.
    sin_theta, cos_theta : array_like
        Grade at the rear segment (positive uphill).
    direction : array_like
        Direction of the sled's motion, in [-1, 1].
    """
    return weight_N * (sin_theta + friction * cos_theta * direction)


@dataclass(frozen=True)
class TerrainProfile:
    """Terrain coefficient X_t as a function of position along the track [paper section 3].

    Either a constant (``positions_m`` empty) or a piecewise-linear table of
    ``(position_m, xt)`` pairs, held constant beyond its ends.  Evaluated per axle, so a segment
    can straddle two kinds of snow.

    Parameters
    ----------
    positions_m : tuple of float
        Strictly increasing positions [m]; empty for a constant profile.
    values : tuple of float
        X_t at each position (or one value for a constant profile); every value > 0.
    """

    positions_m: tuple
    values: tuple

    @classmethod
    def constant(cls, xt: float) -> TerrainProfile:
        return cls((), (float(xt),))

    @property
    def is_constant(self) -> bool:
        return len(self.positions_m) == 0

    def __call__(self, x_m):
        """X_t at the positions ``x_m`` (any shape)."""
        if self.is_constant:
            return np.full(np.shape(x_m), self.values[0])
        return np.interp(x_m, self.positions_m, self.values)

    def minimum(self) -> float:
        return float(min(self.values))


# ------------------------------------------------------------------ terrain along the route
# Builders that compile route descriptions (patches, seeded random profiles) into the single
# piecewise-linear :class:`TerrainProfile` table, so the chain model keeps ONE evaluation path.

#: Width [m] of the linear transition used for a patch edge given without a ramp (``ramp_m = 0``):
#: a true step would make the right-hand side discontinuous inside a solver step.
STEP_WIDTH_M = 1e-3


def patch_profile(base_xt: float, patches) -> TerrainProfile:
    """X_t along the route: a base value with patches of other snow [paper section 3, "location dependent"].

    Parameters
    ----------
    base_xt : float
        X_t outside every patch (> 0).
    patches : sequence of (start_m, end_m, xt, ramp_m)
        Sorted, non-overlapping patches.  X_t equals ``xt`` on ``[start_m, end_m]`` and changes
        linearly back to ``base_xt`` over ``ramp_m`` metres outside each edge (over
        :data:`STEP_WIDTH_M` when ``ramp_m`` is 0).  Validation (order, overlap, signs) is done by
        ``scenario.TerrainConfig``; this function assumes valid input.

    Returns
    -------
    TerrainProfile
        Constant when there are no patches, otherwise a table.
    """
    if not patches:
        return TerrainProfile.constant(base_xt)
    pos, val = [], []
    for start, end, xt, ramp in patches:
        r = max(float(ramp), STEP_WIDTH_M)
        pos += [start - r, start, end, end + r]
        val += [base_xt, xt, xt, base_xt]
    # adjacent patches whose ramps touch share a breakpoint: drop exact duplicates
    P, V = [pos[0]], [val[0]]
    for p, v in zip(pos[1:], val[1:]):
        if p > P[-1]:
            P.append(p)
            V.append(v)
        else:
            V[-1] = v
    return TerrainProfile(tuple(float(p) for p in P), tuple(float(v) for v in V))


def random_profile(
    mean: float,
    std: float,
    correlation_length_m: float,
    seed: int,
    length_m: float,
    min_xt: float,
    start_m: float = 0.0,
) -> TerrainProfile:
    """A seeded random X_t profile: Gaussian-filtered white noise (a stationary Gaussian process).

    White noise on a grid of spacing ``correlation_length_m / 8`` is convolved with a Gaussian
    kernel of standard deviation ``correlation_length_m / 2``, which gives the squared-exponential
    correlation ``rho(r) = exp(-r^2 / correlation_length_m^2)`` (``rho = 1/e`` at one correlation
    length); it is scaled to standard deviation ``std``, shifted to ``mean`` and clipped to
    ``[min_xt, 1]`` so X_t stays in its domain (0, 1].  The same arguments always give the same profile
    (``numpy.random.default_rng(seed)``); beyond ``[start_m, start_m + length_m]`` X_t is held at
    the end values.

    Parameters
    ----------
    mean, std : float
        Mean and standard deviation of X_t before clipping.
    correlation_length_m : float
        Correlation length [m] (> 0).
    seed : int
        Seed of the random generator.
    length_m : float
        Length of the generated stretch [m].
    min_xt : float
        Lower clip of X_t (> 0).
    start_m : float
        Position of the first grid point [m].
    """
    pos, field_ = gaussian_field(correlation_length_m, seed, length_m, start_m)
    xt = np.clip(mean + std * field_, min_xt, 1.0)
    return TerrainProfile(tuple(pos.tolist()), tuple(xt.tolist()))


def gaussian_field(correlation_length_m: float, seed: int, length_m: float, start_m: float = 0.0):
    """The generator of :func:`random_profile`: a stationary Gaussian field of zero mean and unit variance.

    White noise on a grid of spacing ``correlation_length_m / 8`` convolved with a Gaussian kernel of
    standard deviation ``correlation_length_m / 2`` (correlation ``exp(-r^2 / correlation_length_m^2)``),
    seeded by ``numpy.random.default_rng(seed)``.  ``snoworm odds`` adds it, scaled, to a route's X_t
    (docs/odds.md).

    Returns
    -------
    pos, values : ndarray
        Grid positions from ``start_m`` [m] and the field's values there.
    """
    dx = correlation_length_m / 8.0
    n = int(np.ceil(length_m / dx)) + 1
    sigma_k = correlation_length_m / 2.0
    half = int(np.ceil(4.0 * sigma_k / dx))
    rng = np.random.default_rng(int(seed))
    noise = rng.standard_normal(n + 2 * half)
    r = np.arange(-half, half + 1) * dx
    kern = np.exp(-0.5 * (r / sigma_k) ** 2)
    kern /= np.sqrt(np.sum(kern**2))  # unit variance of the filtered noise
    return start_m + dx * np.arange(n), np.convolve(noise, kern, mode="valid")[:n]
