"""The controller contract: what a controller observes and what it may command.

Shared by the ``controller`` mode (:mod:`snoworm.modes.controller`) and the step-by-step
:class:`snoworm.simulation.stepwise.Simulator`, so a controller sees the same :class:`Observation` and its
commands become the same :class:`~snoworm.model.inputs.Controls` either way (docs/controllers.md).

* :func:`observe` -- the :class:`Observation` of a state, from the same function the results use
  (:func:`snoworm.model.quantities.output_series`), under the controls held while it was reached.
* :class:`CommandState` -- the held command: :meth:`CommandState.apply` merges a command mapping
  (keys of :data:`COMMAND_KEYS`; keys left out keep their value) and returns the controls.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ..model.inputs import Controls
from ..model.quantities import output_series

if TYPE_CHECKING:
    from numpy.typing import ArrayLike, NDArray

    from ..model.chain import ChainModel

__all__ = ["Observation", "observe", "CommandState", "COMMAND_KEYS", "observed_fields"]

#: Keys a command may hold, with their length ("N": one per segment, "N-1": one per link).
COMMAND_KEYS = {
    "wheel_speed_mps": "N",  # set-points R_w*omega_ref of the wheel-speed PI [m/s]
    "wheel_torque_Nm": "N",  # motor torque per wheel at the wheel, clipped to the motor envelope [N m]
    "wheel_lock": "N",  # booleans: hold the wheels at zero speed (overrides the two above)
    "joint_force_N": "N-1",  # link force reference of the prismatic joints, tension positive [N]
    "joint_length_m": "N-1",  # extension reference of the prismatic joints [m]
}


#: Observation arrays: name -> (table of :func:`output_series`, its column).
_SOURCES = {
    "x_m": (0, "x_m"),
    "v_mps": (0, "v_mps"),
    "wheel_speed_mps": (0, "wheel_speed_mps"),
    "slip": (0, "slip"),
    "motor_torque_Nm": (0, "motor_torque_Nm"),
    "xt": (0, "xt"),
    "grade_deg": (0, "grade_deg"),
    "link_force_N": (1, "force_N"),
    "link_length_m": (1, "length_m"),
    "joint_extension_m": (1, "extension_m"),
}


def observed_fields(seg: Mapping[str, Any], lk: Mapping[str, Any], row: int = -1) -> dict[str, Any]:
    """The observation's arrays (every field but ``t_s``, in :attr:`Observation.FIELDS` order) at
    sample ``row`` of :func:`~snoworm.model.quantities.output_series`' tables ``seg, lk``."""
    tables = (seg, lk)
    return {k: tables[i][c][row] for k, (i, c) in _SOURCES.items()}


class Observation:
    """What a controller measures at time ``t_s`` (read-only; arrays cannot be written).

    Build one from values (``Observation(t_s=0.0, x_m=..., ...)``, e.g. to unit-test a
    controller) or from a state with :func:`observe`; then the arrays are computed by
    :func:`snoworm.model.quantities.output_series` when first read (a controller reading only ``t_s``
    costs no evaluation of the chain).

    Attributes
    ----------
    t_s : float
        Time [s].
    x_m, v_mps, wheel_speed_mps, slip, motor_torque_Nm, xt, grade_deg : ndarray (N,)
        Per segment, as in the results' ``segments`` (:data:`snoworm.results.result.SEGMENT_COLUMNS`):
        position [m], ground speed [m/s], wheel speed R_w*omega [m/s] and slip (means of the
        axles), motor torque per wheel [N m], the terrain coefficient X_t and the grade under the
        segment [deg, positive uphill] (docs/model.md section 7; built from values without
        ``grade_deg``, an observation is on level ground: zeros).
    link_force_N, link_length_m, joint_extension_m : ndarray (N-1,)
        Per link, as in the results' ``links``: force (tension positive) [N], centre-to-centre
        distance [m] and prismatic joint extension (0 for a fixed link) [m].
    """

    __slots__ = ("_t", "_vals", "_src")
    _t: float
    _vals: dict[str, NDArray[np.float64]] | None
    _src: tuple[ChainModel, NDArray[np.float64], Controls] | None
    # the arrays (properties made from _SOURCES below), declared for type checkers
    x_m: NDArray[np.float64]
    v_mps: NDArray[np.float64]
    wheel_speed_mps: NDArray[np.float64]
    slip: NDArray[np.float64]
    motor_torque_Nm: NDArray[np.float64]
    xt: NDArray[np.float64]
    grade_deg: NDArray[np.float64]
    link_force_N: NDArray[np.float64]
    link_length_m: NDArray[np.float64]
    joint_extension_m: NDArray[np.float64]
    FIELDS = ("t_s",) + tuple(_SOURCES)

    def __init__(self, t_s: float, **arrays: ArrayLike) -> None:
        if "grade_deg" not in arrays and "x_m" in arrays:  # level ground unless given
            arrays["grade_deg"] = np.zeros(np.shape(arrays["x_m"]))
        if set(arrays) != set(_SOURCES):
            raise TypeError(
                f"Observation needs t_s and exactly {', '.join(_SOURCES)}; "
                f"missing {sorted(set(_SOURCES) - set(arrays))}, unknown {sorted(set(arrays) - set(_SOURCES))}"
            )
        object.__setattr__(self, "_t", float(t_s))
        object.__setattr__(self, "_vals", {k: _frozen(v) for k, v in arrays.items()})
        object.__setattr__(self, "_src", None)

    @classmethod
    def _of_state(cls, model: ChainModel, y: ArrayLike, ctl: Controls, t: float) -> Observation:
        obs = cls.__new__(cls)
        object.__setattr__(obs, "_t", float(t))
        object.__setattr__(obs, "_vals", None)
        object.__setattr__(obs, "_src", (model, np.array(y, float), ctl))
        return obs

    def _values(self) -> dict[str, NDArray[np.float64]]:
        if self._vals is None:
            model, y, ctl = self._src  # type: ignore[misc]  # _src is set whenever _vals is None
            seg, lk = output_series(model, y[None, :], ctl)
            vals = {k: _frozen(v) for k, v in observed_fields(seg, lk, row=0).items()}
            object.__setattr__(self, "_vals", vals)
            object.__setattr__(self, "_src", None)
            return vals
        return self._vals

    @property
    def t_s(self) -> float:
        return self._t

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"Observation is read-only (cannot set {name!r})")

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        """Pickle and copy (an environment holding an Observation is then picklable and deep-copyable)."""
        return (_rebuilt_observation, (self._t, self._vals, self._src))

    def __repr__(self) -> str:
        return "Observation(" + ", ".join(f"{k}={getattr(self, k)!r}" for k in self.FIELDS) + ")"

    def as_dict(self) -> dict:
        """Name -> value (arrays copied, writable)."""
        return {"t_s": self._t} | {k: np.array(v) for k, v in self._values().items()}


def _field_property(name: str) -> property:
    return property(lambda self: self._values()[name])


for _name in _SOURCES:
    setattr(Observation, _name, _field_property(_name))


def observe(model: ChainModel, y: ArrayLike, ctl: Controls, t: float) -> Observation:
    """The :class:`Observation` of flat state ``y`` at time ``t`` reached under controls ``ctl``
    (computed from a copy of ``y`` when first read)."""
    return Observation._of_state(model, y, ctl, t)


def _rebuilt_observation(t: float, vals: Mapping[str, ArrayLike] | None, src: tuple | None) -> Observation:
    """An :class:`Observation` from its pickled parts (:meth:`Observation.__reduce__`)."""
    obs = Observation.__new__(Observation)
    object.__setattr__(obs, "_t", float(t))
    object.__setattr__(obs, "_vals", None if vals is None else {k: _frozen(v) for k, v in vals.items()})
    object.__setattr__(obs, "_src", src)
    return obs


def _frozen(a: ArrayLike) -> NDArray[np.float64]:
    """A read-only float copy of ``a``."""
    a = np.array(a, float)
    a.flags.writeable = False
    return a


class CommandState:
    """The command held on a chain (zero-order hold) and the :class:`Controls` it amounts to.

    Before any wheel command the motors are off (torque 0, as before a built-in mode's start
    time); before any joint command the prismatic joints hold their length.  A wheel command
    switches the motors on; per segment the latest of ``wheel_speed_mps`` and ``wheel_torque_Nm``
    acts, and ``wheel_lock`` (wheel-speed PI at zero speed, as the inchworm gait's anchors)
    overrides both while it is true.  Per joint the latest of ``joint_force_N`` and
    ``joint_length_m`` acts, through the actuator with its stroke, force and rate limits.

    Parameters
    ----------
    model : ChainModel
        The chain the commands drive.
    batch : int, optional
        Hold the commands of ``batch`` copies of the chain at once (the vector environment,
        :mod:`snoworm.env.vector`): every command array then has shape ``(batch, length)`` and the
        controls a leading batch axis, as :meth:`Controls.stack` gives for the members of
        :meth:`ChainModel.stack`.
    """

    def __init__(self, model: ChainModel, batch: int | None = None) -> None:
        self.model = model
        n = model.n
        self._lead = () if batch is None else (int(batch),)
        self.source = np.zeros(n, int)  # 0 motors off, 1 speed, 2 torque
        self.speed = np.zeros(n)
        self.torque = np.zeros(n)
        self.lock = np.zeros(n, bool)
        self.joint_mode: str | None = None  # None: joints hold; "force" or "length"
        self.joint_value = np.zeros(max(n - 1, 0))
        self.controls = self._build()

    def _sizes(self) -> dict[str, int]:
        return {"N": self.model.n, "N-1": max(self.model.n - 1, 0)}

    def _check(self, command: object) -> dict[str, NDArray[Any]]:
        """Validated arrays of ``command`` (ValueError naming the key)."""
        if command is None:
            return {}
        if not isinstance(command, Mapping):
            raise ValueError(
                f"a command must be a mapping with keys among {', '.join(COMMAND_KEYS)}; "
                f"got {type(command).__name__} {command!r}"
            )
        sizes, out = self._sizes(), {}
        for key, value in command.items():
            if key not in COMMAND_KEYS:
                raise ValueError(f"command key {key!r}: unknown; known keys: {', '.join(COMMAND_KEYS)}")
            size = sizes[COMMAND_KEYS[key]]
            try:
                arr = np.asarray(value)
                real = arr.dtype.kind != "c"
                arr = arr.astype(bool if key == "wheel_lock" else float) if real else arr
            except (TypeError, ValueError):
                raise ValueError(f"command key {key!r}: expected {size} numbers, got {value!r}") from None
            if not real:
                raise ValueError(
                    f"command key {key!r}: expected {size} real numbers, got complex values {value!r}; "
                    "pass the real part (np.real) if that is what you mean"
                )
            if arr.shape != self._lead + (size,):
                raise ValueError(
                    f"command key {key!r}: expected {size} values ({COMMAND_KEYS[key]}), "
                    f"got shape {arr.shape}" + (f" (batch {self._lead[0]})" if self._lead else "")
                )
            if key == "wheel_lock" and not all(
                isinstance(v, (bool, np.bool_)) or v in (0, 1) for v in np.asarray(value, object).reshape(-1)
            ):
                raise ValueError(f"command key {key!r}: expected true/false values, got {value!r}")
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"command key {key!r}: every value must be finite, got {value!r}")
            if key.startswith("joint_") and not self.model.has_joints:
                raise ValueError(
                    f"command key {key!r}: the vehicle has no prismatic joints (vehicle.links.type is fixed)"
                )
            out[key] = arr
        for a, b in (("wheel_speed_mps", "wheel_torque_Nm"), ("joint_force_N", "joint_length_m")):
            if a in out and b in out:
                raise ValueError(f"command keys {a!r} and {b!r}: give one of them in a command, not both")
        return out

    def apply(self, command: Mapping[str, ArrayLike] | None) -> Controls:
        """Merge ``command`` into the held command and return the controls (the same object if
        nothing changed).  Raises ValueError naming the key (nothing is changed then)."""
        new = self._check(command)
        if not new:
            return self.controls
        if "wheel_speed_mps" in new:
            self.source = np.full(self.model.n, 1)
            self.speed = new["wheel_speed_mps"]
        if "wheel_torque_Nm" in new:
            self.source = np.full(self.model.n, 2)
            self.torque = new["wheel_torque_Nm"]
        if "wheel_lock" in new:
            self.lock = new["wheel_lock"]
        if "joint_force_N" in new or "joint_length_m" in new:
            self.joint_mode = "force" if "joint_force_N" in new else "length"
            self.joint_value = cast("NDArray[np.float64]", new.get("joint_force_N", new.get("joint_length_m")))
        self.controls = self._build()
        return self.controls

    def snapshot(self) -> dict:
        """The held command, for :meth:`restore` (:meth:`apply` never changes arrays in place)."""
        return dict(vars(self))

    def restore(self, snap: dict) -> None:
        """Back to a :meth:`snapshot`."""
        vars(self).update(snap)

    def _build(self) -> Controls:
        n, links = self.model.n, self.model.links
        lock = self.lock
        on = (self.source > 0) | lock
        torque = (self.source == 2) & ~lock
        sp = np.where(lock | (self.source != 1), 0.0, self.speed)
        ctl = Controls.rolling(n, on.astype(float), sp)
        if torque.any():
            ctl = ctl.with_(torque_active=torque.astype(float), torque_cmd_Nm=np.where(torque, self.torque, 0.0))
        if self.joint_mode is None or n < 2:
            return ctl
        ones = np.ones(n - 1)
        limit = np.asarray(links.force_max_N, float)
        if self.joint_mode == "force":
            F = self.joint_value  # T_ref = -dir |F|: dir +1 pushes (compression), -1 pulls (tension)
            return ctl.with_(
                joint_active=ones,
                joint_length_mode=0 * ones,
                joint_dir=np.where(F > 0, -1.0, 1.0),
                joint_ff_N=np.abs(F),
                joint_limit_N=limit,
            )
        return ctl.with_(
            joint_active=ones,
            joint_length_mode=ones,
            joint_sref_m=self.joint_value,
            joint_vtarget_mps=np.asarray(links.rate_max_mps, float),
            joint_limit_N=limit,
        )
