"""The sections of a scenario: vehicle, terrain, tow and numerics, as validated frozen configs.

Each class is a :class:`~snoworm.config.schema.Config`: validated when constructed (from YAML by
:func:`~snoworm.config.schema.build`, from Python directly, or by :func:`dataclasses.replace`).
Physical values come from the named parameter set (:mod:`snoworm.config.params`); no field here has a
physical default.  The mode section is a :class:`~snoworm.config.mode_registry.ModeConfig`,
declared by each mode (:mod:`snoworm.modes`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from pathlib import Path

from ..model.arrays import STATE_FIELDS
from ..slope import ElevationProfile, grade_patch_profile
from ..terrain import (
    SINKAGE_LAWS,
    STANDSTILL_LAWS,
    STEP_WIDTH_M,
    TerrainParams,
    TerrainProfile,
    patch_profile,
    random_profile,
)
from .routes import GRADE_DOMAIN, GradePatchConfig, check_grade_inputs, read_route
from .schema import Config, ScenarioError, build, check_field, dump, field, quote, short_key, suggest

__all__ = [
    "XT_DOMAIN",
    "FINITE_WHY",
    "BIG_FORCE_N",
    "BIG_SPEED_MPS",
    "DRIVETRAINS",
    "MAX_SEGMENTS",
    "MAX_OUTPUT_SAMPLES",
    "SegmentConfig",
    "LinkConfig",
    "TerrainModelConfig",
    "PatchConfig",
    "RandomTerrainConfig",
    "TerrainConfig",
    "TowConfig",
    "VehicleConfig",
    "ImmobilisedConfig",
    "SimulationConfig",
]


#: Domain of the terrain coefficient X_t wherever it appears (constant, profiles, patches, random
#: profiles, sweeps, mobility-map grids, calibration): paper section 3 defines X_t on (0, 1].
XT_DOMAIN = dict(
    gt=0,
    le=1,
    why="X_t is defined on (0, 1] (paper section 3: 1 is firm neve, lower is "
    "looser snow); above about 1.1 the traction law of Eq. 2 reverses.",
)
#: Generous but finite bounds: far beyond any rover, small enough that a run stays finite.
BIG_FORCE_N = 1e6
BIG_SPEED_MPS = 100.0
BIG_TIME_S = 1e5
MAX_SEGMENTS = 200
#: most output samples of a run (time steps x segments), which bounds the memory of the results and
#: the CSVs (~900 bytes a sample at the peak: 150 000 keep a run under ~200 MB; shipped runs have at most 12 000)
MAX_OUTPUT_SAMPLES = 150_000
_REG_WHY = "A regularisation speed, small against the driving speeds."
FINITE_WHY = "A larger value would only make the run stiff or meaningless (it must stay finite)."
#: States of a segment's drivetrain (``vehicle.segment_overrides.K.drivetrain``): a failed one gives no
#: torque and its wheels roll free, without the driveline's losses (docs/model.md section 4).
DRIVETRAINS = ("working", "failed")


@dataclass(frozen=True)
class SegmentConfig(Config):
    """Physical parameters of one segment (docs/model.md section 1)."""

    _section = "vehicle.segment"
    mass_kg: float = field(gt=0, le=1e5, why=FINITE_WHY, unit="kg", doc="segment mass including wheels")
    wheel_radius_m: float = field(gt=0, le=10, why=FINITE_WHY, unit="m", doc="wheel radius R_w")
    wheel_inertia_kgm2: float = field(gt=0, le=1e4, why=FINITE_WHY, unit="kg m^2", doc="inertia of one wheel J")
    wheelbase_m: float = field(ge=0, le=100, why=FINITE_WHY, unit="m", doc="distance between the two axles")
    wheels_per_axle: int = field(ge=1, le=100, why=FINITE_WHY, doc="wheels on each of the two axles")
    gravity_mps2: float = field(gt=0, le=100, why=FINITE_WHY, unit="m/s^2", doc="gravitational acceleration")
    motor_slope_Nms_per_rad: float = field(
        gt=0, le=1e5, why=FINITE_WHY, unit="N m s/rad", doc="motor torque-speed slope at the wheel"
    )
    no_load_speed_radps: float = field(gt=0, le=1e4, why=FINITE_WHY, unit="rad/s", doc="no-load wheel speed")
    torque_limit_Nm: float = field(
        gt=0, le=1e6, why=FINITE_WHY, unit="N m", doc="motor torque limit at the wheel, per wheel"
    )
    drivetrain_efficiency: float = field(gt=0, le=1, doc="drivetrain efficiency, for electrical energy")
    speed_kp_Nms_per_rad: float = field(
        gt=0, le=1e5, why=FINITE_WHY, unit="N m s/rad", doc="wheel-speed PI proportional gain"
    )
    speed_ki_Nm_per_rad: float = field(ge=0, le=1e6, why=FINITE_WHY, unit="N m/rad", doc="wheel-speed PI integral gain")
    com_height_m: float = field(
        ge=0,
        le=100,
        why=FINITE_WHY,
        unit="m",
        doc="height of the centre of mass above the ground (pitch load transfer on a grade)",
    )
    drivetrain: str = field(
        "working",
        choices=DRIVETRAINS,
        doc="'working', or 'failed': the motors give no torque and the wheels roll free "
        "(docs/model.md section 4); a condition of the segment, not a value of the parameter set",
    )

    @property
    def driven(self) -> float:
        """1.0 when the segment's drivetrain works, 0.0 when it has failed (:class:`SegmentArrays`)."""
        return 1.0 if self.drivetrain == "working" else 0.0


@dataclass(frozen=True)
class LinkConfig(Config):
    """Inter-segment links: fixed spring-dampers or active prismatic joints (docs/model.md section 4)."""

    _section = "vehicle.links"
    type: tuple[str, ...] = field(doc="'fixed' or 'prismatic', one for all links or a list with one per link")
    stiffness_N_per_m: float = field(gt=0, le=1e9, why=FINITE_WHY, unit="N/m", doc="link stiffness k_c")
    damping_Ns_per_m: float = field(ge=0, le=1e8, why=FINITE_WHY, unit="N s/m", doc="link damping c_c")
    rest_spacing_m: float = field(
        gt=0, le=100, why=FINITE_WHY, unit="m", doc="centre-to-centre spacing of unloaded segments"
    )
    stroke_min_m: float = field(
        ge=-100, le=100, why=FINITE_WHY, unit="m", doc="prismatic joint fully contracted extension"
    )
    stroke_max_m: float = field(
        ge=-100, le=100, why=FINITE_WHY, unit="m", doc="prismatic joint fully extended extension"
    )
    force_max_N: float = field(gt=0, le=BIG_FORCE_N, why=FINITE_WHY, unit="N", doc="prismatic joint force limit")
    rate_max_mps: float = field(gt=0, le=BIG_SPEED_MPS, why=FINITE_WHY, unit="m/s", doc="prismatic joint rate limit")
    force_gain_per_s: float = field(gt=0, le=1e5, why=FINITE_WHY, unit="1/s", doc="bandwidth of the joint's force loop")
    joint_efficiency: float = field(
        gt=0, le=1, doc="prismatic actuator efficiency, mechanical work / electrical energy"
    )

    def _check(self, path):
        for j, t in enumerate(self.type):
            if t not in ("fixed", "prismatic"):
                raise ScenarioError(
                    f"{path}.type[{j}]: must be 'fixed' or 'prismatic', got {quote(t)}.{suggest(t, ('fixed', 'prismatic'))}"
                )
        if not self.stroke_max_m > self.stroke_min_m:
            raise ScenarioError(
                f"{path}.stroke_max_m: must be greater than stroke_min_m ({self.stroke_min_m} m), "
                f"got {self.stroke_max_m} m. Give the joint a positive stroke."
            )


@dataclass(frozen=True)
class TerrainModelConfig(Config):
    """Terrain-model coefficients (paper Table 3, docs/model.md section 2)."""

    _section = "terrain.model"
    b_tF: float = field(
        gt=0,
        le=100,
        search=(1e-3, 5.0),
        doc="Eq. 2 slip-to-tractive-force coefficient",
        why="Eq. 2: b_tF scales the peak traction F_n X^d b_tF.",
    )
    b_trF: float = field(
        ge=0,
        le=100,
        search=(0.0, 2.0),
        doc="Eq. 3 terrain resistance coefficient",
        why="Eq. 3: b_trF scales the resistance b_trF F_n / X^A, which opposes motion.",
    )
    A: float = field(
        gt=0,
        le=10,
        search=(1e-3, 5.0),
        doc="Eq. 3 terrain coefficient exponent",
        why="Eq. 3: the resistance grows as X_t falls (looser snow), so A > 0.",
    )
    peak_exponent_d: float = field(
        gt=0,
        le=10,
        search=(1e-3, 6.0),
        doc="exponent of X_t in Eq. 2's peak factor (2 default, 1 literal)",
        why="Eq. 2: the peak traction F_n X^d b_tF falls with X_t, so d > 0.",
    )
    tau0: float = field(
        ge=0,
        le=100,
        search=(0.0, 100.0),
        doc="resistance torque law constant",
        why="The resistance torque opposes the wheel's rotation, so tau0 >= 0.",
    )
    tau1: float = field(
        ge=0,
        le=100,
        search=(0.0, 100.0),
        doc="resistance torque law slope in (1 - X_t)",
        why="The resistance torque grows in looser snow (1 - X_t), so tau1 >= 0.",
    )
    slip_eps_mps: float = field(gt=0, le=1, unit="m/s", doc="slip regularisation speed", why=_REG_WHY)
    sign_eps_mps: float = field(gt=0, le=1, unit="m/s", doc="smooth-sign speed scale", why=_REG_WHY)
    torque_balance: str = field(choices=("contact", "traction"), doc="wheel torque-balance convention")
    standstill: str = field(
        choices=STANDSTILL_LAWS,
        doc="law of the slip near rest: 'regularised' (Eq. 1, viscous at rest) or 'shear' (Janosi shear "
        "displacement per axle: a stopped wheel holds)",
    )
    shear_modulus_K_m: float = field(
        gt=0,
        le=1,
        unit="m",
        doc="shear deformation modulus K of the 'shear' standstill law",
        why="K is the shear displacement that builds most of the traction: millimetres to centimetres in snow.",
    )

    sinkage: str = field(
        choices=SINKAGE_LAWS,
        doc="slip-sinkage: 'off', or 'slip' (a sinkage state per axle that grows with slip beyond "
        "sinkage_onset_slip and raises the Eq. 3 resistance by 1 + z / sinkage_ref_m)",
    )
    sinkage_rate: float = field(
        ge=0, le=100, doc="c_z: metres of sinkage per metre of slip displacement beyond the onset", why=FINITE_WHY
    )
    sinkage_onset_slip: float = field(
        ge=0, lt=1, doc="i_0: the slip beyond which a wheel digs in", why="A slip lies in [0, 1)."
    )
    sinkage_relax_length_m: float = field(
        gt=0, le=1e3, unit="m", doc="L_relax: ground distance over which a rolling wheel leaves its rut", why=FINITE_WHY
    )
    sinkage_max_m: float = field(gt=0, le=10, unit="m", doc="z_max: depth at which digging saturates", why=FINITE_WHY)
    sinkage_ref_m: float = field(
        gt=0, le=10, unit="m", doc="z_ref: sinkage that doubles the Eq. 3 resistance", why=FINITE_WHY
    )

    def params(self) -> TerrainParams:
        """The coefficients as the laws' :class:`~snoworm.terrain.TerrainParams` (same field names)."""
        return TerrainParams(**{k: getattr(self, k) for k in TerrainParams.__dataclass_fields__})


@dataclass(frozen=True)
class PatchConfig(Config):
    """A patch of other snow on the route (``terrain.patches``), X_t = ``xt`` on ``[start_m, end_m]``."""

    _section = "terrain.patches[]"
    start_m: float = field(ge=-1e7, le=1e7, why=FINITE_WHY, unit="m", doc="position where the patch's X_t is reached")
    end_m: float = field(ge=-1e7, le=1e7, why=FINITE_WHY, unit="m", doc="position where the patch's X_t ends")
    xt: float = field(**XT_DOMAIN, doc="terrain coefficient X_t inside the patch")
    ramp_m: float = field(
        0.0,
        ge=0,
        le=1e7,
        why=FINITE_WHY,
        unit="m",
        doc="length of the linear transition to the base X_t outside each edge (0: a step)",
    )

    def _check(self, path):
        if not self.end_m > self.start_m:
            raise ScenarioError(
                f"{path}.end_m: must be greater than start_m ({self.start_m} m), got {self.end_m} m. "
                "A patch covers [start_m, end_m]."
            )


@dataclass(frozen=True)
class RandomTerrainConfig(Config):
    """A seeded random X_t profile (``terrain.random``): Gaussian-filtered white noise, clipped."""

    _section = "terrain.random"
    mean: float = field(**XT_DOMAIN, doc="mean X_t")
    std: float = field(ge=0, le=1, why="X_t lies in (0, 1].", doc="standard deviation of X_t before clipping")
    correlation_length_m: float = field(
        gt=0, le=1e7, why=FINITE_WHY, unit="m", doc="distance at which the correlation falls to 1/e"
    )
    seed: int = field(
        ge=0, le=2**63 - 1, why="A 64-bit seed.", doc="seed of the random generator (same seed, same profile)"
    )
    length_m: float = field(
        gt=0, le=1e7, why=FINITE_WHY, unit="m", doc="length of the generated stretch (X_t held beyond it)"
    )
    start_m: float = field(
        0.0, ge=-1e7, le=1e7, why=FINITE_WHY, unit="m", doc="position where the generated stretch starts"
    )
    min_xt: float = field(0.05, **XT_DOMAIN, doc="lower clip of X_t, keeps X_t > 0")

    def _check(self, path):
        if self.length_m / (self.correlation_length_m / 8.0) > 200000:
            raise ScenarioError(
                f"{path}: length_m / correlation_length_m = "
                f"{self.length_m / self.correlation_length_m:.0f} needs more than 200000 grid points; "
                "shorten length_m or lengthen correlation_length_m."
            )


@dataclass(frozen=True)
class TerrainConfig(Config):
    """Terrain coefficient and elevation along the track.

    Exactly one of: a constant ``xt`` (optionally with ``patches`` of other snow on it), a
    ``profile`` table of ``[position_m, xt]`` pairs, a seeded ``random`` profile, or a ``route``
    file (which gives the elevation too).  All of them compile to one
    :class:`~snoworm.terrain.TerrainProfile` (:meth:`compile`).  The elevation (docs/model.md
    section 7): level unless ``grade_deg`` (optionally with ``grade_patches``), an ``elevation``
    table or a ``route`` is given; it compiles to one :class:`~snoworm.slope.ElevationProfile`
    (:meth:`elevation_profile`).
    """

    _section = "terrain"
    model: TerrainModelConfig = field(doc="terrain-model coefficients")
    xt: float | None = field(
        None, **XT_DOMAIN, search=(0.05, 1.0), doc="constant terrain coefficient X_t (the base X_t with patches)"
    )
    profile: tuple[tuple[float, ...], ...] | None = field(None, doc="list of [position_m, xt] pairs")
    patches: tuple[PatchConfig, ...] | None = field(None, doc="patches of other snow on the base xt")
    random: RandomTerrainConfig | None = field(None, doc="seeded random X_t profile")
    grade_deg: float | None = field(
        None, **GRADE_DOMAIN, unit="deg", doc="constant grade, positive uphill (the base grade with grade_patches)"
    )
    grade_patches: tuple[GradePatchConfig, ...] | None = field(None, doc="stretches of other grade on grade_deg")
    elevation: tuple[tuple[float, ...], ...] | None = field(None, doc="list of [distance_m, elevation_m] pairs")
    route: str | None = field(
        None, doc="CSV route file (distance_m, elevation_m, xt columns), relative to the scenario's folder"
    )

    def _check(self, path):
        given = [k for k in ("xt", "profile", "random", "route") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ScenarioError(
                f"{path}: give exactly one of 'xt' (a constant X_t, optionally with 'patches'), "
                f"'profile' (a list of [position_m, xt] pairs), 'random' (a seeded random profile) or "
                f"'route' (a route file); "
                f"got {' and '.join(repr(g) for g in given) if given else 'none of them'}."
            )
        check_grade_inputs(self, path)
        if self.patches is not None:
            if self.xt is None:
                raise ScenarioError(
                    f"{path}.patches: patches lie on a base X_t; give 'xt' (the X_t outside the "
                    f"patches) instead of '{given[0]}'."
                )
            prev_end, prev_j = -math.inf, None
            for j, pt in enumerate(self.patches):
                lo = pt.start_m - max(pt.ramp_m, STEP_WIDTH_M)
                if lo < prev_end:
                    raise ScenarioError(
                        f"{path}.patches[{j}]: overlaps patches[{prev_j}] (with its ramps): it starts "
                        f"at {lo:g} m (start_m - ramp_m) before the previous one ends at {prev_end:g} m "
                        "(end_m + ramp_m). List patches in order along the route, without overlap."
                    )
                prev_end, prev_j = pt.end_m + max(pt.ramp_m, STEP_WIDTH_M), j
        if self.profile is not None:
            if len(self.profile) < 1:
                raise ScenarioError(f"{path}.profile: needs at least one [position_m, xt] pair.")
            prev = -math.inf
            for j, pair in enumerate(self.profile):
                if len(pair) != 2:
                    raise ScenarioError(
                        f"{path}.profile[{j}]: expected a pair [position_m, xt], got {quote(list(pair))}."
                    )
                if not pair[0] > prev:
                    raise ScenarioError(
                        f"{path}.profile[{j}]: positions must increase strictly; {pair[0]} m follows {prev} m."
                    )
                check_field(PatchConfig, "start_m", pair[0], f"{path}.profile[{j}][0]")
                check_field(PatchConfig, "xt", pair[1], f"{path}.profile[{j}][1]")
                prev = pair[0]

    def files(self) -> list:
        """The files this section refers to (the route file), as absolute paths."""
        return [str(Path(self.route).resolve())] if self.route is not None else []

    def route_data(self):
        """The :class:`~snoworm.config.routes.Route` read from ``route`` (None without one)."""
        return None if self.route is None else self._route_table

    @functools.cached_property
    def _route_table(self):
        """The route file read once (a cache of a value derived from the config, not a setting)."""
        return read_route(self.route)

    def elevation_profile(self) -> ElevationProfile | None:
        """The elevation along the track (docs/model.md section 7), or None on level ground."""
        if self.route is not None:
            return self.route_data().elevation_profile()
        if self.elevation is not None:
            return ElevationProfile(tuple(p[0] for p in self.elevation), tuple(p[1] for p in self.elevation))
        if self.grade_deg is not None:
            return grade_patch_profile(
                self.grade_deg, [(p.start_m, p.end_m, p.grade_deg, p.ramp_m) for p in self.grade_patches or ()]
            )
        return None

    def compile(self) -> TerrainProfile:
        """Compile ``xt``, ``xt`` + ``patches``, ``profile`` or ``random`` to one X_t table.

        Every form becomes a :class:`~snoworm.terrain.TerrainProfile`, the single evaluation path
        of X_t along the track (paper section 3: X_t is "location dependent").
        """
        if self.profile is not None:
            return TerrainProfile(tuple(p[0] for p in self.profile), tuple(p[1] for p in self.profile))
        if self.route is not None:
            r = self.route_data()
            return TerrainProfile(r.distance_m, r.xt)
        if self.random is not None:
            r = self.random
            return random_profile(r.mean, r.std, r.correlation_length_m, r.seed, r.length_m, r.min_xt, r.start_m)
        if self.patches:
            return patch_profile(self.xt, [(p.start_m, p.end_m, p.xt, p.ramp_m) for p in self.patches])
        return TerrainProfile.constant(self.xt)


@dataclass(frozen=True)
class TowConfig(Config):
    """Towed load on the rear segment: a constant force and a sled (docs/model.md section 4, "Towed load")."""

    _section = "tow"
    force_N: float = field(
        ge=-BIG_FORCE_N,
        le=BIG_FORCE_N,
        why=FINITE_WHY,
        unit="N",
        doc="constant force pulling the rear segment backward",
    )
    mass_kg: float = field(
        0.0,
        ge=0,
        le=1e5,
        why=FINITE_WHY,
        unit="kg",
        doc="mass of a sled towed behind the rear segment (0: none); it adds m g (sin(theta) + "
        "friction cos(theta)) at the rear segment's grade, docs/model.md section 4",
    )
    friction: float | None = field(
        None,
        ge=0,
        le=5,
        doc="the sled's sliding friction coefficient on the snow (needed with mass_kg > 0)",
        why="A friction coefficient is >= 0; a sled on snow slides at 0.02-0.5 (beyond a few it would not slide).",
    )

    def _check(self, path):
        if self.mass_kg > 0 and self.friction is None:
            raise ScenarioError(
                f"{path}.friction: a sled (tow.mass_kg = {self.mass_kg:g} kg) needs its sliding friction "
                "coefficient on the snow; there is no default. Give tow.friction, e.g. 0.1 for a plastic sled "
                'on packed snow (docs/model.md section 4, "Towed load").'
            )

    @property
    def sled_friction(self) -> float:
        """The sled's friction coefficient, 0 without a sled (no value given)."""
        return 0.0 if self.friction is None else float(self.friction)


@dataclass(frozen=True)
class VehicleConfig(Config):
    """The chain of segments."""

    _section = "vehicle"
    parameter_set: str = field(
        doc="named set of physical values (one of PARAMETER_SETS), or the path of a YAML "
        "parameter-set file of the user's own vehicle"
    )
    segments: int = field(
        ge=1,
        le=MAX_SEGMENTS,
        doc="number of segments N (segment 0 leads)",
        why="The paper's vehicles have 2 to 6; more only costs memory and time.",
    )
    segment: SegmentConfig = field(doc="parameters shared by every segment")
    links: LinkConfig = field(doc="inter-segment links")
    segment_overrides: dict[int, dict] = field(default_factory=dict, doc="per-segment parameter changes, by index")

    def _check(self, path):
        for k, ov in self.segment_overrides.items():
            if not isinstance(ov, dict) and ov is not None:
                raise ScenarioError(
                    f"{path}.segment_overrides.{short_key(k)}: expected a mapping of segment keys (e.g. "
                    f"{{mass_kg: 120}}), got {type(ov).__name__} {quote(ov)}."
                )
            if not 0 <= k < self.segments:
                raise ScenarioError(
                    f"{path}.segment_overrides.{short_key(k)}: segment index out of range 0..{self.segments - 1}."
                )
            merged = {**dump(self.segment), **(ov or {})}
            build(SegmentConfig, merged, f"{path}.segment_overrides.{short_key(k)}")
        n_links = max(self.segments - 1, 0)
        if len(self.links.type) not in (1, n_links) and n_links > 0:
            raise ScenarioError(
                f"{path}.links.type: give one type for all links or {n_links} (one per link); "
                f"got {len(self.links.type)}."
            )

    def segment_params(self):
        """Per-segment :class:`SegmentConfig` list with overrides applied."""
        if not self.segment_overrides:
            return [self.segment] * self.segments  # frozen: safe to share
        base = dump(self.segment)
        return [build(SegmentConfig, {**base, **(self.segment_overrides.get(k) or {})}) for k in range(self.segments)]

    def link_types(self):
        """``'fixed'`` or ``'prismatic'`` for each of the N-1 links."""
        n_links = max(self.segments - 1, 0)
        t = self.links.type
        return list(t) * n_links if len(t) == 1 else list(t)


@dataclass(frozen=True)
class ImmobilisedConfig(Config):
    """When a run counts as immobilised (``simulation.immobilised``; docs/model.md section
    "Immobilisation verdict", :func:`snoworm.results.verdict.verdict`).

    The chain is immobilised from the first output time ``t`` after which, over ``window_s``, its
    wheels are driven (commanded or turning) for at least ``speed_mps`` of travel per second, yet
    its centre advances less than ``speed_mps`` per second and less than ``1 - slip`` of the
    wheels' travel; or when its mean sinkage reaches ``sinkage_m`` (a run with a sinkage series).
    A judgement of the results: it changes nothing of the run.
    """

    _section = "simulation.immobilised"
    speed_mps: float | None = field(
        None,
        gt=0,
        le=10,
        unit="m/s",
        doc="progress per second below which the chain is stalled (none: max(0.05 m/s, 5 terrain.model.sign_eps_mps), "
        "above the smooth sign's creep)",
        why="A stall is slower than walking pace.",
    )
    window_s: float = field(
        5.0,
        gt=0,
        le=BIG_TIME_S,
        unit="s",
        doc="time over which the chain must stay stalled (longer than a gait phase and the start-up)",
        why=FINITE_WHY,
    )
    slip: float = field(
        0.9,
        gt=0,
        le=1,
        doc="the chain covers less than (1 - slip) of its wheels' travel over the window",
        why="A slip ratio lies in (0, 1].",
    )
    sinkage_m: float | None = field(
        None,
        gt=0,
        le=10,
        unit="m",
        doc="mean sinkage of the chain's wheels at which it is dug in (none: 0.9 x the terrain model's "
        "sinkage_max_m when its sinkage law is on, else not judged)",
        why="A wheel sinks by centimetres to decimetres.",
    )


@dataclass(frozen=True)
class SimulationConfig(Config):
    """Numerical settings, and how a run is judged (``goal_m``, ``immobilised``): no physics here."""

    _section = "simulation"
    duration_s: float = field(
        ge=1e-3,
        le=BIG_TIME_S,
        unit="s",
        doc="simulated time",
        why="From a millisecond to about 28 hours of simulated time.",
    )
    output_dt_s: float = field(0.05, gt=0, le=BIG_TIME_S, why=FINITE_WHY, unit="s", doc="output sampling interval")
    method: str = field(
        "LSODA",
        choices=("LSODA", "VODE", "BDF", "Radau", "RK45", "DOP853"),
        doc="solve_ivp method; VODE: ODEPACK VODE (BDF) stepped by snoworm.simulation.vode (inching gaits)",
    )
    rtol: float = field(1e-5, gt=0, lt=1, doc="relative tolerance")
    atol_scale: float = field(
        1.0,
        gt=0,
        le=1e3,
        why="At 1e3 the position tolerance is already 1 mm.",
        doc="multiplies the per-component absolute tolerances",
    )
    atol_scale_fields: dict[str, float] = field(
        default_factory=dict,
        gt=0,
        le=1e3,
        why="At 1e3 a wheel speed's tolerance is already 1e-2 rad/s.",
        doc="per state field (x_m, v_mps, omega_front, omega_rear, integral_front_Nm, integral_rear_Nm, q_mps, "
        "s_m, j_front_m, j_rear_m, z_front_m, z_rear_m): a further factor on that field's absolute tolerance (e.g. {omega_front: 10, omega_rear: 10})",
    )
    max_step_s: float | None = field(
        None, gt=0, le=BIG_TIME_S, why=FINITE_WHY, unit="s", doc="largest solver step (none: unlimited)"
    )
    max_wall_s: float | None = field(
        None,
        gt=0,
        le=1e7,
        why=FINITE_WHY,
        unit="s",
        doc="wall-clock time after which the run stops with a solver failure (none: no limit)",
    )
    goal_m: float | None = field(
        None,
        ge=-1e7,
        le=1e7,
        why=FINITE_WHY,
        unit="m",
        doc="position of the leader at which the run has reached the end of its route (none: the last point of "
        "terrain.route or terrain.elevation, if given; else no end)",
    )
    immobilised: ImmobilisedConfig = field(
        default_factory=ImmobilisedConfig, doc="when the run counts as immobilised (the verdict)"
    )

    def _check(self, path):
        for k in self.atol_scale_fields:
            if k not in STATE_FIELDS:
                raise ScenarioError(
                    f"{path}.atol_scale_fields.{short_key(k)}: not a state field; use one of "
                    f"{', '.join(STATE_FIELDS)}.{suggest(k, STATE_FIELDS)}"
                )
