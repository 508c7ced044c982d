r"""Gaits of the inchworm mode: which segments move in each phase, what each joint does (paper section 5.1).

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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..config.schema import ScenarioError

__all__ = ["GAITS", "PhasePlan", "gait_plan", "progress_conditions"]

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


def gait_plan(phases, n, link_types, path="mode.gait"):
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


def progress_conditions(F_c, Ft_front, Ftr_front, Ftr_rear, G_front=0.0, G_rear=0.0):
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
