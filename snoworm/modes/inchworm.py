r"""Inchworm mobility mode: push-pull gaits through active prismatic joints (paper section 5.1).

Where rolling immobilises the vehicle, segments push and pull one another through the
prismatic joints in their links; the held segments' locked wheels (speed control to zero,
"closed loop speed control to maintain zero speed") act as anchors through their terrain
resistance.

The gait (which segments move in each phase, and so the role of each joint) is planned by
:func:`gait_plan` (section "Gaits").

Gaits
-----
A gait is a cyclic list of phases; each phase names the segments that move.  From it follow,
for every phase, the role of each joint:

* a joint between a moving segment and a held one *contracts* if the held segment is ahead
  (it pulls the mover forward) and *extends* if the held segment is behind (it pushes);
* every other joint holds its length (held segments joined by holding joints form one anchor
  *cluster*).

A phase ends on events, not timers: a moving group is done when one of its joints reaches its
stroke limit (it then holds, and the group's wheels lock); the next phase starts when every
group is done.  Shipped gaits: ``two_segment`` = ``[[1], [0]]`` (section 5.1's sequence: from
extended, hold the front and pull the rear forward, then hold the rear and push the front) and
``six_segment`` = ``[[0, 3], [1, 4], [2, 5]]`` (Fig 5: two held for each moving one).

:func:`gait_plan` derives every phase's joint roles and checks the gait can run (when the scenario
is validated); :func:`progress_conditions` states the paper's Eqs. 4-6 for a two-segment push.

Joint force control (Eqs. 4-5)
------------------------------
Each active joint regulates its moving group's speed to ``target_speed_mps`` with a
proportional force loop that backs off while its anchor slides backward (the paper's "simple
force controller ... to limit backwards sliding"),
``|F| = clip(F_ff + K_v (v_target - v) - K_a max(0, -v_anchor), 0, F_lim)``, where the
feed-forward ``F_ff`` is the group's terrain resistance shared over its joints, and the limit
keeps the load on every anchor cluster below ``hold_margin`` times what its locked wheels can
hold (Eq. 5: ``F_tr,rear - F_c >= 0``) and no higher than the mover needs:

    F_lim,j = min(F_max, F_ff,j (1 + headroom), F_ff,j * hold_margin * C_cluster / sum(F_ff on the cluster))

and the groups moving in one phase get the same headroom, so identical segments move alike.
with ``C_cluster`` the cluster's full terrain resistance plus its locked-wheel traction.  The
force is high while the mover breaks loose and falls to ``F_ff`` once it moves, so the anchors'
backward sliding peaks shortly after motion starts and then drops off, as in Fig 5.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .. import terrain
from ..config.mode_registry import ModeConfig
from ..config.schema import ScenarioError, field, suggest
from ..config.sections import FINITE_WHY
from ..model.inputs import Controls
from .base import Interval, Mode, refuse_failed_drivetrains, register_mode

if TYPE_CHECKING:
    from numpy.typing import NDArray

    from ..config.scenario import Scenario
    from ..config.sections import VehicleConfig
    from ..model.chain import ChainModel

__all__ = ["InchwormConfig", "InchwormMode", "GAITS", "PhasePlan", "gait_plan", "progress_conditions"]

# ---------------------------------------------------------------------------------------- gaits
#: Named gaits: lists of phases, each the list of moving segments.
GAITS = {
    "two_segment": ((1,), (0,)),
    "six_segment": ((0, 3), (1, 4), (2, 5)),
}


@dataclass(frozen=True)
class PhasePlan:
    """Joint roles of one gait phase."""

    moving: tuple  # moving segment indices
    groups: tuple  # tuples of consecutive moving segments
    role: np.ndarray  # per link: +1 extend, -1 contract, 0 hold
    group_of_joint: np.ndarray  # per link: index into groups, -1 if holding
    mover_of_joint: np.ndarray  # per link: the adjacent moving segment (or the link index)
    cluster_of_joint: np.ndarray  # per link: index into clusters of its anchor, -1 if holding
    clusters: tuple  # tuples of consecutive held segments


def _runs(indices):
    runs, cur = [], []
    for k in indices:
        if cur and k != cur[-1] + 1:
            runs.append(tuple(cur))
            cur = []
        cur.append(k)
    if cur:
        runs.append(tuple(cur))
    return tuple(runs)


def gait_plan(
    phases: Sequence[Sequence[int]], n: int, link_types: Sequence[str], path: str = "mode.gait"
) -> list[PhasePlan]:
    """Derive the joint roles of every phase and check the gait can run.

    Raises
    ------
    ScenarioError
        A segment index out of range, a phase moving nothing or everything, a moving group with
        no joint, a joint that is not prismatic, or a joint that would extend (or contract) twice
        in a row and jam at its stroke limit.
    """
    if n < 2:
        raise ScenarioError(f"{path}: inchworm movement needs at least 2 segments (vehicle.segments = {n}).")
    plans = []
    for p, ph in enumerate(phases):
        moving = tuple(sorted(set(ph)))
        bad = [k for k in moving if not 0 <= k < n]
        if bad:
            raise ScenarioError(f"{path}[{p}]: segment {bad[0]} out of range 0..{n - 1}.")
        if len(moving) == n:
            raise ScenarioError(f"{path}[{p}]: moves every segment; inching needs held segments as anchors.")
        held = tuple(k for k in range(n) if k not in moving)
        groups, clusters = _runs(moving), _runs(held)
        role = np.zeros(n - 1)
        group_of = np.full(n - 1, -1)
        mover_of = np.arange(n - 1)
        cluster_of = np.full(n - 1, -1)
        for g, grp in enumerate(groups):
            joints = []
            if grp[0] > 0:  # held segment ahead: pull (contract)
                j = grp[0] - 1
                role[j], group_of[j], mover_of[j] = -1, g, grp[0]
                joints.append(j)
            if grp[-1] < n - 1:  # held segment behind: push (extend)
                j = grp[-1]
                role[j], group_of[j], mover_of[j] = 1, g, grp[-1]
                joints.append(j)
            for j in joints:
                if link_types[j] != "prismatic":
                    raise ScenarioError(
                        f"vehicle.links.type: link {j} must be 'prismatic' for the gait "
                        f"(phase {p} moves segments {list(grp)} through it); it is 'fixed'."
                    )
                anchor = j if role[j] == -1 else j + 1
                cluster_of[j] = next(c for c, cl in enumerate(clusters) if anchor in cl)
        plans.append(PhasePlan(moving, groups, role, group_of, mover_of, cluster_of, clusters))
    # every joint must alternate extend / contract around the cycle
    for j in range(n - 1):
        seq = [(p, pl.role[j]) for p, pl in enumerate(plans) if pl.role[j] != 0]
        if len(seq) == 1:
            word = "extends" if seq[0][1] > 0 else "contracts"
            raise ScenarioError(
                f"{path}: joint {j} only {word} (phase {seq[0][0]}) and never makes the opposite "
                "stroke; it would jam at its stroke limit after one cycle. Add a phase that "
                "moves the segment on its other side."
            )
        for (p1, r1), (p2, r2) in zip(seq, seq[1:] + seq[:1]):
            if len(seq) > 1 and r1 == r2:
                word = "extends" if r1 > 0 else "contracts"
                raise ScenarioError(
                    f"{path}: joint {j} {word} in phase {p1} and again in phase {p2} without the "
                    "opposite stroke between; it would jam at its stroke limit. Reorder the phases."
                )
    return plans


def progress_conditions(
    F_c: float, Ft_front: float, Ftr_front: float, Ftr_rear: float, G_front: float = 0.0, G_rear: float = 0.0
) -> dict[str, float | bool]:
    """The paper's conditions for inchworm progress of a 2-segment push phase, Eqs. 4-6, with gravity.

    On a grade (docs/model.md section 7) gravity along the track ``G = -m g sin(theta)`` (negative
    uphill) acts on each segment; the paper's level-ground Eqs. 4-6 are the case ``G = 0``.

    Parameters
    ----------
    F_c : float
        Joint force pushing the segments apart [N].
    Ft_front, Ftr_front : float
        Tractive and terrain-resistance force of the moving (front) segment [N].
    Ftr_rear : float
        Terrain resistance the held (rear) segment can provide [N].
    G_front, G_rear : float
        Gravity along the track on the moving and the held segment [N] (0 on level ground).

    Returns
    -------
    dict
        ``eq4_N = F_c + F_t,front - F_tr,front + G_front`` (> 0: the mover advances),
        ``eq5_N = F_tr,rear + G_rear - F_c`` (>= 0: the anchor holds; uphill gravity pulls it back too),
        ``eq6_N = F_t,front + F_tr,rear - F_tr,front + G_front + G_rear`` (> 0: some F_c satisfies both),
        and ``progress`` (Eqs. 4 and 5 both hold).
    """
    eq4 = F_c + Ft_front - Ftr_front + G_front
    eq5 = Ftr_rear + G_rear - F_c
    eq6 = Ft_front + Ftr_rear - Ftr_front + G_front + G_rear
    return {"eq4_N": float(eq4), "eq5_N": float(eq5), "eq6_N": float(eq6), "progress": bool(eq4 > 0 and eq5 >= 0)}


#: A joint is at its stroke limit this close to it [m] (the soft end stop approaches it smoothly).
STROKE_TOL_M = 1e-3

#: A joint within this distance of its event level (``STROKE_TOL_M`` short of its limit) when an
#: interval starts counts as having reached it [m].  Identical groups (a long chain's gait moves
#: several alike) reach their limits within ~1e-13 s of each other; the solver stops at the first
#: crossing, and whether the others are then a rounding error short of their level or past it
#: must not decide whether their group is done: past it, their rising-crossing event would never
#: fire and the phase would never end (docs/model.md section 5.1, "Phase changes").  1e-9 m is
#: 1e4 times that rounding and 1e-6 of ``STROKE_TOL_M``.
EVENT_TOL_M = 1e-9


@dataclass(frozen=True)
class InchwormConfig(ModeConfig):
    """``mode: {type: inchworm, gait: six_segment, ...}`` (paper section 5.1)."""

    type: str = field(choices=("inchworm",), doc="mode name")
    gait: object = field(
        doc="a named gait (two_segment, six_segment) or a list of phases, each a list of moving segments"
    )
    target_speed_mps: float = field(
        gt=0, le=100, why=FINITE_WHY, unit="m/s", doc="speed of a moving segment that the joint force loop aims at"
    )
    mover_wheel_speed_mps: float = field(
        ge=0, le=100, why=FINITE_WHY, unit="m/s", doc="wheel-speed set-point R_w*omega of moving segments (held: 0)"
    )
    hold_margin: float | None = field(
        gt=0,
        le=100,
        doc="fraction of an anchor cluster's resistance the joints may load it with "
        "(Eq. 5); null: no limit but the joint force limit",
    )
    joint_control: str = field(
        "speed",
        choices=("speed", "length", "force"),
        doc="speed: force loop on the mover's speed; length: stroke at target_speed_mps; force: constant joint_force_N",
    )
    speed_gain_Ns_per_m: float = field(
        2000.0, ge=0, le=1e6, why=FINITE_WHY, unit="N s/m", doc="joint force loop gain K_v on the mover's speed error"
    )
    joint_force_N: float | None = field(
        None, gt=0, le=1e6, why=FINITE_WHY, unit="N", doc="joint force of joint_control: force"
    )
    anchor_gain_Ns_per_m: float = field(
        0.0,
        ge=0,
        le=1e6,
        why=FINITE_WHY,
        unit="N s/m",
        doc="joint force reduction per m/s of backward sliding of its anchor",
    )
    force_headroom: float = field(
        0.2,
        ge=0,
        le=100,
        doc="joint force allowed above the feed-forward, as a fraction of it, "
        "to accelerate the mover (speed and length control)",
    )
    start_time_s: float = field(0.0, ge=0, le=1e5, unit="s", doc="time the gait starts (motors off before)")
    feedforward: str = field(
        "resistance",
        choices=("resistance", "none"),
        doc="speed control's force feed-forward: the mover's terrain resistance, or none",
    )

    def inching_settings(self) -> dict[str, Any]:
        """This mode's own settings (without ``type`` and ``start_time_s``)."""
        return {
            f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name not in ("type", "start_time_s")
        }

    def phases(self) -> tuple[tuple[int, ...], ...]:
        """The gait as a tuple of phases (tuples of moving segment indices)."""
        if isinstance(self.gait, str):
            return GAITS[self.gait]
        gait = cast(Sequence[Sequence[int]], self.gait)  # a list of phases (checked by _check)
        return tuple(tuple(int(k) for k in ph) for ph in gait)

    def _check(self, path):
        g = self.gait
        if isinstance(g, str):
            if g not in GAITS:
                raise ScenarioError(
                    f"{path}.gait: unknown gait {g!r}.{suggest(g, GAITS)} Known gaits: "
                    f"{', '.join(GAITS)}; or give a list of phases such as [[1], [0]]."
                )
            return
        ok = (
            isinstance(g, (list, tuple))
            and len(g) > 0
            and all(
                isinstance(ph, (list, tuple))
                and len(ph) > 0
                and all(isinstance(k, int) and not isinstance(k, bool) for k in ph)
                for ph in g
            )
        )
        if not ok:
            raise ScenarioError(
                f"{path}.gait: expected a gait name ({', '.join(GAITS)}) or a non-empty list of phases, "
                f"each a non-empty list of segment indices, e.g. [[0], [1], [2], [3]]; got {g!r}."
            )

    def check_vehicle(self, vehicle: VehicleConfig, path: str) -> None:
        if (self.joint_control == "force") != (self.joint_force_N is not None):
            raise ScenarioError(
                f"{path}.joint_force_N: give it exactly when joint_control is 'force' "
                f"(joint_control = {self.joint_control!r}, joint_force_N = {self.joint_force_N!r})."
            )
        gait_plan(self.phases(), vehicle.segments, vehicle.link_types(), f"{path}.gait")
        refuse_failed_drivetrains(vehicle, "inchworm", "holds segments on their locked wheels and drives the others")


@register_mode
class InchwormMode(Mode):
    """Run a push-pull gait on a chain with prismatic joints; phases change on stroke-limit events."""

    name = "inchworm"
    config_class = InchwormConfig
    cfg: InchwormConfig

    def __init__(self, cfg: InchwormConfig, scenario: Scenario, model: ChainModel) -> None:
        super().__init__(cfg, scenario, model)
        n = model.n
        self.plans = gait_plan(cfg.phases(), n, scenario.vehicle.link_types())
        self.phase = 0
        self.cycles_done = 0
        self.group_done: NDArray[np.bool_] | None = None
        self.phase_log: list[dict[str, Any]] = []
        L = model.links
        # initial extension: the opposite end of each joint's first stroke
        s0 = np.full(n - 1, 0.5) * (L.stroke_min_m + L.stroke_max_m)
        for j in range(n - 1):
            first = next((pl.role[j] for pl in self.plans if pl.role[j] != 0), 0)
            if first > 0:
                s0[j] = L.stroke_min_m[j]
            elif first < 0:
                s0[j] = L.stroke_max_m[j]
        self.s0 = s0

    def initial_state(self) -> NDArray[np.float64]:
        return self.model.initial_state(joint_extension_m=self.s0)

    # ------------------------------------------------------------ terrain forces for the plan
    def _segment_forces(self, y):
        """Per segment: full forward terrain resistance, locked-wheel traction (i = 1) and gravity along
        the track [N], at the normal loads on the grade (docs/model.md section 7)."""
        m = self.model
        x = m.field(m.unpack(y), "x_m")
        X = m.xt_at_axles(x)
        _, _, Fn, G = m.grade_terms(x)
        nw = m.wheels_per_axle[:, None]
        Ftr = (nw * terrain.resistance_force(np.inf, Fn, X, m.tp)).sum(-1)
        Ft1 = (nw * terrain.traction_force(1.0, Fn, X, m.tp)).sum(-1)
        return Ftr, Ft1, G

    def _joint_commands(self, plan, y):
        cfg, m = self.cfg, self.model
        n = m.n
        Ftr, Ft1, G = self._segment_forces(y)
        # gravity (negative uphill) adds to what a mover must overcome and takes from what an anchor
        # holds (every planned joint force on an anchor pushes or pulls it backward): Eqs. 4-5 with gravity
        need = Ftr - G
        active = (plan.role != 0) & (plan.group_of_joint >= 0)
        active &= ~self.group_done[np.maximum(plan.group_of_joint, 0)]
        ff = np.zeros(n - 1)
        for g, grp in enumerate(plan.groups):
            js = np.nonzero(active & (plan.group_of_joint == g))[0]
            if cfg.joint_control == "force":
                ff[js] = cfg.joint_force_N
            elif js.size and cfg.feedforward == "resistance":
                ff[js] = need[list(grp)].sum() / js.size
        Fmax = m.links.force_max_N
        limit = Fmax.copy()
        capacity = np.array([(Ftr[list(cl)] + Ft1[list(cl)] + G[list(cl)]).sum() for cl in plan.clusters])
        if cfg.hold_margin is not None:
            for c in range(len(plan.clusters)):
                js = np.nonzero(active & (plan.cluster_of_joint == c))[0]
                if js.size == 0:
                    continue
                demand = np.maximum(ff[js], 1e-9)
                share = cfg.hold_margin * capacity[c] * demand / demand.sum()
                limit[js] = np.minimum(Fmax[js], share)
        if cfg.joint_control != "force":
            # load the anchors no more than the movers need: feed-forward plus a headroom to accelerate
            if cfg.feedforward == "resistance":
                limit = np.where(active, np.minimum(limit, ff * (1.0 + cfg.force_headroom)), limit)
            # synchronise the groups of a phase: every group gets the same force headroom above
            # its feed-forward (the smallest any group has), so identical segments accelerate
            # alike and the groups' speed traces overlap (Fig 5)
            heads = [limit[js].sum() - ff[js].sum() for js in self._group_joints(plan, active)]
            common = max(min(heads), 0.0) if heads else 0.0
            for js in self._group_joints(plan, active):
                if js.size:
                    w = ff[js] / ff[js].sum() if ff[js].sum() > 0 else np.full(js.size, 1.0 / js.size)
                    limit[js] = np.minimum(limit[js], ff[js] + common * w)
        ff = np.minimum(ff, limit)
        return active, ff, limit, capacity, Ftr, Ft1, G

    @staticmethod
    def _group_joints(plan, active):
        """Indices of the active joints of each moving group of a phase."""
        return [np.nonzero(active & (plan.group_of_joint == g))[0] for g in range(len(plan.groups))]

    def interval(self, t: float, y: NDArray[np.float64]) -> Interval:
        cfg, m = self.cfg, self.model
        n = m.n
        if t < cfg.start_time_s - 1e-12:
            ctl = Controls.rolling(n, np.zeros(n), np.zeros(n))
            return Interval(cfg.start_time_s, ctl, [], "before start")
        if self.group_done is None:
            self.group_done = np.zeros(len(self.plans[self.phase].groups), bool)
            self._begin_phase(t, y)
        for _ in range(sum(len(p.groups) for p in self.plans)):  # groups already at their limit are done
            j = self._joint_at_limit(y)
            if j is None:
                break
            self._group_done(t, y, j)
        plan = self.plans[self.phase]
        active, ff, limit, capacity, _, _, _ = self._joint_commands(plan, y)
        moving = np.zeros(n, bool)
        for g, grp in enumerate(plan.groups):
            if not self.group_done[g]:
                moving[list(grp)] = True
        L = m.links
        # the speed gain is per group: shared by the group's joints
        kv = np.zeros(n - 1)
        if cfg.joint_control == "speed":
            for js in self._group_joints(plan, active):
                kv[js] = cfg.speed_gain_Ns_per_m / max(js.size, 1)
        ctl = Controls.rolling(n, np.ones(n), np.where(moving, cfg.mover_wheel_speed_mps, 0.0)).with_(
            joint_active=active.astype(float),
            joint_dir=plan.role.astype(float),
            joint_ff_N=ff,
            joint_length_mode=np.full(n - 1, 1.0 if cfg.joint_control == "length" else 0.0),
            joint_sref_m=np.where(plan.role > 0, L.stroke_max_m, L.stroke_min_m),
            joint_kv=kv,
            joint_vtarget_mps=np.full(n - 1, cfg.target_speed_mps),
            joint_limit_N=limit,
            joint_mover=plan.mover_of_joint.astype(int),
            joint_anchor=np.where(plan.role < 0, np.arange(n - 1), np.arange(n - 1) + 1),
            joint_ka=np.full(n - 1, cfg.anchor_gain_Ns_per_m if cfg.joint_control != "force" else 0.0),
        )
        events, self._event_joints = [], []
        for j in np.nonzero(active)[0]:
            k = m.layout.flat_index(int(j), "s_m")  # extension of joint j (the link behind segment j)
            sign, level = self._event_level(plan, j)

            def ev(t_, y_, k=k, sign=sign, level=level):
                return sign * (y_[k] - level)

            ev.direction = 1  # type: ignore[attr-defined]  # scipy's solve_ivp event API (rising crossings only)
            events.append(ev)
            self._event_joints.append(int(j))
        label = f"phase {self.phase} (moving {[k for k in range(n) if moving[k]]})"
        return Interval(np.inf, ctl, events, label)

    def _begin_phase(self, t, y):
        plan = self.plans[self.phase]
        active, ff, limit, capacity, Ftr, Ft1, G = self._joint_commands(plan, y)
        diag = []
        for g, grp in enumerate(plan.groups):
            js = np.nonzero(active & (plan.group_of_joint == g))[0]
            Fc = float(limit[js].sum())
            cl = sorted({int(plan.cluster_of_joint[j]) for j in js})
            # Eq. 5 per anchor cluster: its capacity against every planned joint force on it
            eq5 = min(
                float(capacity[c] - limit[np.nonzero(active & (plan.cluster_of_joint == c))[0]].sum()) for c in cl
            )
            # (the anchors' capacity already includes their gravity)
            pc = progress_conditions(
                Fc,
                float(Ft1[list(grp)].sum()),
                float(Ftr[list(grp)].sum()),
                float(min(capacity[c] for c in cl)),
                G_front=float(G[list(grp)].sum()),
            )
            pc["eq5_N"] = eq5
            pc["progress"] = bool(pc["eq4_N"] > 0 and eq5 >= 0)
            diag.append({"segments": list(grp), "joints": [int(j) for j in js], "joint_force_limit_N": Fc, **pc})
        x = self.model.field(self.model.unpack(y), "x_m")
        self.phase_log.append(
            {
                "phase": self.phase,
                "t_start_s": float(t),
                "t_end_s": None,
                "moving": list(plan.moving),
                "x_start_m": x.tolist(),
                "predicted": diag,
            }
        )

    def _event_level(self, plan, j):
        """``(sign, level)``: joint ``j`` has reached its stroke limit when ``sign (s_j - level) >= 0``."""
        L = self.model.links
        if plan.role[j] > 0:
            return 1.0, float(L.stroke_max_m[j] - STROKE_TOL_M)
        return -1.0, float(L.stroke_min_m[j] + STROKE_TOL_M)

    def _joint_at_limit(self, y):
        """A joint of a group of the current phase not yet done that is within :data:`EVENT_TOL_M`
        of its event level (or past it), or None."""
        plan = self.plans[self.phase]
        s = self.model.field(self.model.unpack(y), "s_m")
        for j in np.nonzero(plan.role != 0)[0]:
            if self.group_done[int(plan.group_of_joint[j])]:
                continue
            sign, level = self._event_level(plan, j)
            if sign * (s[j] - level) >= -EVENT_TOL_M:
                return int(j)
        return None

    def on_event(self, t: float, y: NDArray[np.float64], index: int) -> None:
        self._group_done(t, y, self._event_joints[index])

    def _group_done(self, t, y, j):
        """Joint ``j`` reached its stroke limit: its group is done; the next phase starts when all are."""
        plan = self.plans[self.phase]
        g = int(plan.group_of_joint[j])
        self.group_done[g] = True
        word = "extended" if plan.role[j] > 0 else "contracted"
        x0 = float(self.model.field(self.model.unpack(y), "x_m")[0])
        self.log.append(
            {
                "t_s": float(t),
                "kind": "joint_limit",
                "x_m": x0,
                "detail": f"joint {j} fully {word}: segments {list(plan.groups[g])} done",
            }
        )
        if self.group_done.all():
            self.phase_log[-1]["t_end_s"] = float(t)
            self.phase = (self.phase + 1) % len(self.plans)
            if self.phase == 0:
                self.cycles_done += 1
            self.group_done = np.zeros(len(self.plans[self.phase].groups), bool)
            self.log.append(
                {
                    "t_s": float(t),
                    "kind": "phase_change",
                    "x_m": x0,
                    "detail": f"phase {self.phase} starts (moving {list(self.plans[self.phase].moving)}) "
                    f"after joint {j} reached its stroke limit",
                }
            )
            self._begin_phase(t, y)

    def summary(self, result: Any) -> dict:
        t = result.t
        v = result.segments["v_mps"]
        held = (result.segments["speed_setpoint_mps"] == 0.0) & (t[:, None] >= self.cfg.start_time_s)
        back = np.where(held, np.minimum(v, 0.0), 0.0)
        F = result.links["force_N"]
        prism = self.model.links.prismatic > 0
        phases = []
        for ph in self.phase_log:
            t0, t1 = ph["t_start_s"], ph["t_end_s"] if ph["t_end_s"] is not None else float(t[-1])
            sel = (t >= t0) & (t <= t1)
            obs = {}
            if sel.any():
                i0, i1 = np.nonzero(sel)[0][[0, -1]]
                adv = result.segments["x_m"][i1] - result.segments["x_m"][i0]
                obs = {
                    "advance_m": adv.tolist(),
                    "peak_backward_speed_mps": float(-back[sel].min()),
                    "mean_abs_joint_force_N": np.abs(F[sel][:, prism]).mean(0).tolist() if prism.any() else [],
                }
            phases.append({**ph, "t_end_s": t1, "observed": obs})
        return {
            "gait_cycles": self.cycles_done,
            "gait_phases_completed": sum(1 for p in self.phase_log if p["t_end_s"] is not None),
            "peak_backward_speed_held_mps": float(-back.min()),
            "peak_joint_force_N": float(np.abs(F[:, prism]).max()) if prism.any() else 0.0,
            "phases": phases,
        }
