"""The chain as arrays: parameters per segment and per link, and the named state vector.

:class:`SegmentArrays` and :class:`LinkArrays` are what a run's assembly
(:func:`snoworm.simulation.driver.chain_model`) hands the kernel (:class:`snoworm.dynamics.ChainModel`),
one value per segment or link in SI units; :class:`StateLayout` names the fields of the state (docs/model.md section 4): one block of
``n_s`` fields per segment, interleaved so the Jacobian is banded.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LinkArrays", "SegmentArrays", "SHEAR_FIELDS", "SINKAGE_FIELDS", "STATE_FIELDS", "StateLayout"]

#: Every field a segment's state block may hold, in block order (``q_mps`` with a force loop,
#: ``s_m`` with prismatic joints, ``j_front_m``/``j_rear_m`` with the shear-displacement law of
#: the slip near rest, ``terrain.model.standstill: shear``, ``z_front_m``/``z_rear_m`` with
#: slip-sinkage, ``terrain.model.sinkage: slip``).
STATE_FIELDS = (
    "x_m",
    "v_mps",
    "omega_front",
    "omega_rear",
    "integral_front_Nm",
    "integral_rear_Nm",
    "q_mps",
    "s_m",
    "j_front_m",
    "j_rear_m",
    "z_front_m",
    "z_rear_m",
)

#: The fields of the shear displacement per axle (front, rear).
SHEAR_FIELDS = ("j_front_m", "j_rear_m")

#: The fields of the slip-sinkage per axle (front, rear; ``terrain.model.sinkage: slip``).
SINKAGE_FIELDS = ("z_front_m", "z_rear_m")


@dataclass(frozen=True)
class SegmentArrays:
    """Per-segment physical parameters as arrays of length N (SI units)."""

    mass_kg: np.ndarray
    wheel_radius_m: np.ndarray
    wheel_inertia_kgm2: np.ndarray
    wheelbase_m: np.ndarray
    wheels_per_axle: np.ndarray
    gravity_mps2: np.ndarray
    motor_slope_Nms_per_rad: np.ndarray
    no_load_speed_radps: np.ndarray
    torque_limit_Nm: np.ndarray
    drivetrain_efficiency: np.ndarray
    speed_kp_Nms_per_rad: np.ndarray
    speed_ki_Nm_per_rad: np.ndarray
    com_height_m: np.ndarray
    #: 1.0 where the segment's drivetrain works, 0.0 where it has failed (no motor torque, wheels free)
    driven: np.ndarray

    @classmethod
    def from_list(cls, segments) -> SegmentArrays:
        """Stack a list of per-segment parameter objects (with the same attribute names)."""
        names = cls.__dataclass_fields__
        return cls(**{n: np.array([float(getattr(s, n)) for s in segments]) for n in names})

    @property
    def normal_force_N(self) -> np.ndarray:
        """Static normal load per wheel, ``m g / (2 n_w)`` (no load transfer)."""
        return self.mass_kg * self.gravity_mps2 / (2.0 * self.wheels_per_axle)


@dataclass(frozen=True)
class LinkArrays:
    """Per-link parameters as arrays of length N-1."""

    stiffness_N_per_m: np.ndarray
    damping_Ns_per_m: np.ndarray
    rest_spacing_m: np.ndarray
    prismatic: np.ndarray  # 1.0 for an active prismatic joint, 0.0 for a fixed link
    stroke_min_m: np.ndarray
    stroke_max_m: np.ndarray
    force_max_N: np.ndarray
    rate_max_mps: np.ndarray
    force_gain_per_s: np.ndarray


class StateLayout:
    """Names of the chain state: which field of which segment sits where.

    Parameters
    ----------
    n : int
        Number of segments.
    force_loop : bool
        Whether each segment carries the outer force-loop integral ``q_mps``.
    joints : bool
        Whether each segment carries the extension ``s_m`` of the joint behind it.
    shear : bool
        Whether each segment carries the shear displacement of each axle, ``j_front_m`` and
        ``j_rear_m`` (``terrain.model.standstill: shear``, docs/model.md section 2).
    sinkage : bool
        Whether each segment carries the slip-sinkage of each axle, ``z_front_m`` and
        ``z_rear_m`` (``terrain.model.sinkage: slip``, docs/model.md section 2).
    batch_shape : tuple of int
        Leading shape of stacked chains (``()`` for one chain).

    Attributes
    ----------
    fields : tuple of str
        Field names of one segment's block, in order.
    index : dict of str -> int
        Position of each field within a block.
    x, v : int
        Positions of ``x_m`` and ``v_mps``.
    omega, integral : slice
        The wheel speeds (front, rear axle) and the wheel-speed PI integrals.
    q, s : int or None
        Positions of ``q_mps`` and ``s_m`` when present.
    j, z : slice or None
        The shear displacements and the sinkages (front, rear axle) when present.
    """

    def __init__(
        self, n: int, force_loop: bool, joints: bool, batch_shape=(), shear: bool = False, sinkage: bool = False
    ):
        fields = [
            f
            for f in STATE_FIELDS
            if (f != "q_mps" or force_loop)
            and (f != "s_m" or joints)
            and (f not in SHEAR_FIELDS or shear)
            and (f not in SINKAGE_FIELDS or sinkage)
        ]
        self.fields = tuple(fields)
        self.index = {f: j for j, f in enumerate(fields)}
        self.n = int(n)
        self.n_s = len(fields)
        self.batch_shape = tuple(batch_shape)
        self.n_batch = int(np.prod(self.batch_shape, dtype=int))
        self.size = self.n_batch * self.n * self.n_s
        self.shape = self.batch_shape + (self.n, self.n_s)
        self.x, self.v = 0, 1
        self.omega, self.integral = slice(2, 4), slice(4, 6)
        self.q = self.index.get("q_mps")
        self.s = self.index.get("s_m")
        self.j = slice(self.index["j_front_m"], self.index["j_front_m"] + 2) if shear else None
        self.z = slice(self.index["z_front_m"], self.index["z_front_m"] + 2) if sinkage else None

    def __kernel_key__(self):
        """What the layout is made of (it keys generated code, :mod:`snoworm.model.floatkernel`)."""
        return (self.n, self.fields, self.batch_shape)

    def unpack(self, y):
        """View a flat state (or a stack of states, leading dims) as ``(..., N, n_s)``."""
        y = np.asarray(y)
        return y.reshape(y.shape[:-1] + self.shape)

    def get(self, Y, name):
        """One named field of an unpacked state, shape ``(..., N)``."""
        return Y[..., self.index[name]]

    def flat_index(self, segment: int, name: str) -> int:
        """Index of field ``name`` of ``segment`` in the flat state of one chain."""
        return int(segment) * self.n_s + self.index[name]

    def per_state(self, per_field: dict) -> np.ndarray:
        """A flat array over the whole state from one value per field name (e.g. tolerances)."""
        return np.tile([per_field[f] for f in self.fields], self.n_batch * self.n)
