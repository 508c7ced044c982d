"""Piecewise-constant inputs of the chain during one integration interval.

Modes (:mod:`snoworm.modes`) produce :class:`Controls`; the model (:mod:`snoworm.dynamics`)
reads them.  They carry the *settings* of the control laws of :mod:`snoworm.feedback` (set-points,
references, gains, limits), never states.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

__all__ = ["Controls", "as_float", "control_arrays", "control_flags"]


@dataclass(frozen=True)
class Controls:
    """Piecewise-constant inputs of the chain during one integration interval.

    Modes (``snoworm.modes``) produce these; the physics stays the same for every mode.
    Arrays have length N (segments) or N-1 (links).

    Attributes
    ----------
    motor_on : (N,) 1 where the segment's motors run (after its start time), else 0.
    speed_sp_mps : (N,) wheel-speed set-point ``R_w w_ref`` [m/s]; 0 locks the wheels.
    fc_active : (N,) 1 where an outer force loop sets the wheel-speed set-point.
    fc_link : (N,) int, index of the controlled force: link ``j`` (0..N-2) or ``N-1`` = the tow.
    fc_sigma : (N,) +1 if the controlled link is behind the segment, -1 if ahead.
    fc_ref_N, fc_nominal_mps, fc_kp, fc_ki, fc_vmax_mps : (N,) outer PI loop settings:
        ``v_sp = clip(v_nom + kp e + q, 0, v_max)``, ``e = sigma (F_ref - F)``.
    joint_active : (N-1,) 1 where a prismatic joint is driven, 0 where it is locked at its length.
    joint_length_mode : (N-1,) 1: commanded in length (to ``joint_sref_m`` at rate
        ``joint_vtarget_mps``, force limited to ``joint_limit_N``); 0: commanded in force.
    joint_sref_m : (N-1,) length command (extension) of length-commanded joints [m].
    joint_dir : (N-1,) +1 to push (extend, compression), -1 to pull (contract, tension).
    joint_ff_N, joint_kv, joint_vtarget_mps, joint_limit_N : (N-1,) force command
        ``|F| = clip(ff + kv (v_target - v_mover), 0, limit)``.
    joint_mover : (N-1,) int, index of the segment whose speed the joint regulates.
    joint_anchor, joint_ka : (N-1,) int and [N s/m]: the held segment the joint bears on, and the
        gain by which the force command drops while that anchor slides backward,
        ``|F| -= ka max(0, -v_anchor)`` (limits backward sliding, paper section 5.1).
    torque_active : (N,) 1 where the motors apply ``torque_cmd_Nm`` directly instead of the
        wheel-speed PI (a controller's ``wheel_torque_Nm`` command); default 0 everywhere.
    torque_cmd_Nm : (N,) direct motor torque per wheel at the wheel [N m], clipped to the motor
        envelope (:func:`snoworm.feedback.direct_torque`).
    """

    motor_on: np.ndarray
    speed_sp_mps: np.ndarray
    fc_active: np.ndarray
    fc_link: np.ndarray
    fc_sigma: np.ndarray
    fc_ref_N: np.ndarray
    fc_nominal_mps: np.ndarray
    fc_kp: np.ndarray
    fc_ki: np.ndarray
    fc_vmax_mps: np.ndarray
    joint_active: np.ndarray
    joint_length_mode: np.ndarray
    joint_sref_m: np.ndarray
    joint_dir: np.ndarray
    joint_ff_N: np.ndarray
    joint_kv: np.ndarray
    joint_vtarget_mps: np.ndarray
    joint_limit_N: np.ndarray
    joint_mover: np.ndarray
    joint_anchor: np.ndarray
    joint_ka: np.ndarray
    torque_active: np.ndarray = None
    torque_cmd_Nm: np.ndarray = None

    def __post_init__(self):
        n = np.shape(self.motor_on)[-1]
        for name in ("torque_active", "torque_cmd_Nm"):  # no direct torque unless given
            if getattr(self, name) is None:
                object.__setattr__(self, name, np.zeros(n))

    @classmethod
    def rolling(cls, n: int, motor_on, speed_sp_mps) -> Controls:
        """Plain wheel-speed control: no force loop, every joint holding its length."""
        z = np.zeros(n)
        zl = np.zeros(max(n - 1, 0))
        return cls(
            motor_on=np.asarray(motor_on, float) * np.ones(n),
            speed_sp_mps=np.asarray(speed_sp_mps, float) * np.ones(n),
            fc_active=z.copy(),
            fc_link=np.full(n, n - 1, dtype=int),
            fc_sigma=np.ones(n),
            fc_ref_N=z.copy(),
            fc_nominal_mps=z.copy(),
            fc_kp=np.ones(n),
            fc_ki=z.copy(),
            fc_vmax_mps=z.copy(),
            joint_active=zl.copy(),
            joint_length_mode=zl.copy(),
            joint_sref_m=zl.copy(),
            joint_dir=np.ones_like(zl),
            joint_ff_N=zl.copy(),
            joint_kv=zl.copy(),
            joint_vtarget_mps=zl.copy(),
            joint_limit_N=zl.copy(),
            joint_mover=np.arange(max(n - 1, 0), dtype=int),
            joint_anchor=np.arange(1, max(n, 1), dtype=int),
            joint_ka=zl.copy(),
        )

    @classmethod
    def stack(cls, controls) -> Controls:
        """The controls of B stacked chains (:meth:`ChainModel.stack`): arrays equal in every member
        stay as they are, the others get a leading batch axis; index arrays must be equal."""
        kw = {}
        for name in cls.__dataclass_fields__:
            arrs = [np.asarray(getattr(c, name)) for c in controls]
            if all(np.array_equal(a, arrs[0]) for a in arrs[1:]):
                kw[name] = arrs[0]
            elif arrs[0].dtype.kind in "iu":
                raise ValueError(f"stacked controls need the same {name}")
            else:
                kw[name] = np.stack(arrs)
        return cls(**kw)

    def with_(self, **kw) -> Controls:
        """A copy with some arrays replaced (converted to float arrays)."""
        return replace(self, **{k: np.asarray(v) for k, v in kw.items()})


def as_float(a):
    """A control array as floats; symbolic arrays of the float kernel's trace as they are."""
    return a if isinstance(a, np.ndarray) and a.dtype.kind == "O" else np.asarray(a, float)


def control_flags(model, ctl: Controls) -> dict:
    """Which parts of the laws act in an interval of ``model`` (a :class:`~snoworm.dynamics.ChainModel`)
    under ``ctl``: the kernel's branches on the controls (constant within an interval, so skipping
    the other parts changes no result), from the controls' values."""
    f = {
        "all_on": bool(np.all(np.asarray(ctl.motor_on, float) == 1.0)),
        "torque": (np.asarray(ctl.torque_active) > 0)[..., None] if np.any(ctl.torque_active) else None,
    }
    if model.has_joints and model.n > 1:
        f["length_mode"] = np.asarray(ctl.joint_length_mode) > 0
        moving = np.asarray(ctl.joint_active, float) * model.links.prismatic != 0
        f["moving"] = moving
        f["any_active"] = bool(np.any(moving))
        f["any_length"] = bool(np.any(f["length_mode"] & moving))
        f["any_force"] = bool(np.any(~f["length_mode"] & moving))
        f["any_kv"] = bool(np.any(np.asarray(ctl.joint_kv) != 0))
        f["any_ka"] = bool(np.any(np.asarray(ctl.joint_ka) != 0))
    return f


def control_arrays(model, ctl: Controls, flags: dict) -> dict:
    """The arrays ``model``'s kernel takes from ``ctl``, with the ``flags`` of :func:`control_flags`
    (arithmetic only: the float kernel, :mod:`snoworm.model.floatkernel`, traces it on symbols)."""
    on = as_float(ctl.motor_on)[..., None]  # on_mask None: all on, no masking (same result)
    d = dict(
        flags,
        on=on,
        w_ref=(as_float(ctl.speed_sp_mps) / model.seg.wheel_radius_m)[..., None],
        on_mask=None if flags["all_on"] else on,
        torque_cmd=as_float(ctl.torque_cmd_Nm)[..., None],
    )
    if model.has_joints and model.n > 1:
        d["neg_dir"] = -as_float(ctl.joint_dir)
        d["neg_vt"] = -as_float(ctl.joint_vtarget_mps)
        d["active"] = as_float(ctl.joint_active) * model.links.prismatic
    return d
