"""One stepper for one chain or many: held-command periods of B chains, solved as stacks.

:class:`ChainStepper` advances ``B`` chains (``B = 1``: one chain) over a period in which each
member holds its controls, with no events: a control period of a
:class:`~snoworm.simulation.stepwise.Simulator`, of the single Gymnasium environment or of the
vector environment (``B`` copies of one chain), or an interval of the batched sweeps'
:func:`~snoworm.simulation.driver.simulate_batch` (``B`` member chains of one structure,
:meth:`ChainStepper.of_members`).  The members are integrated as stacks
(:meth:`ChainModel.stack <snoworm.model.chain.ChainModel.stack>`: the kernel with one more
leading axis), each by its own :class:`~snoworm.simulation.interval.IntervalSolver`.  How they
are stacked and what a failed stack does is the stepper's :class:`StackPolicy`:

* :data:`PERIODS` (the Simulator's and the environments'): stacks of at most :func:`stack_size`
  members on VODE with its tolerances divided by sqrt(stack size) (``vode_stack``: VODE's error
  test is a weighted RMS norm over the whole stack, and with those tolerances a stack that passes
  it has every member within the RMS norm it has alone).  A stack whose solve fails, or whose
  states leave the physics (non-finite, or a speed beyond
  :data:`~snoworm.simulation.guard.SPEED_SANITY_FACTOR` times the member's fastest no-load wheel
  speed), is solved again member by member from the same start, so one bad member never stops the
  others: each member gets its own status (``failed``) and message.
* :data:`WHOLE_RUNS` (the batched sweeps'): one stack of every member as given, on the scenario's
  method (a stack skips VODE for LSODA, whose weighted max-norm error test holds every member to
  the tolerance it has alone).  A failed stack raises :class:`~snoworm.simulation.guard.SolverError`:
  its caller runs each member alone from the start of its run (a whole run has a mode's state
  that a period cannot restore), and checks the run's states when it ends
  (:func:`~snoworm.simulation.guard.check_sane`, as for a single run).

Why stacks of at most :data:`STACK_MAX_MEMBERS` members and :data:`STACK_MAX_STATES` states on the
periods of :data:`PERIODS`: a stack steps at the pace of its most demanding member, so its
evaluations per period grow with its size (tow6, random actions: 193 for 1 member, 317 for 64, 481
for 256, 662 for 1 000) while the kernel's cost per member falls until ~64 members; and VODE's
level-1 BLAS calls on the whole state start OpenBLAS threads past 10 000 elements, which cost
3-10x a period on a loaded machine.  The batched sweeps keep their group as one stack on LSODA
(groups of 100-500 cases measured as the sweet spot, docs/performance.md).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..model.chain import ChainModel
from .guard import SPEED_SANITY_FACTOR, SolverError
from .interval import IntervalSolver

__all__ = [
    "ChainStepper",
    "StackPolicy",
    "PERIODS",
    "WHOLE_RUNS",
    "STACK_MAX_MEMBERS",
    "STACK_MAX_STATES",
    "stack_size",
]

#: Most members of one stacked solve under :data:`PERIODS` (see the module docstring).
STACK_MAX_MEMBERS = 64
#: Most states of one stacked solve under :data:`PERIODS` (see the module docstring).
STACK_MAX_STATES = 8192


@dataclass(frozen=True)
class StackPolicy:
    """How a :class:`ChainStepper` stacks its members and what a failed stack does.

    Attributes
    ----------
    bounded : bool
        Stacks of at most :func:`stack_size` members (of sizes that differ by at most one); False:
        one stack of every member as given.
    vode_stack : bool
        A stack may run on VODE with its tolerances divided by sqrt(stack size)
        (:class:`~snoworm.simulation.interval.IntervalSolver`); False: a stack skips VODE for LSODA.
    members_alone : bool
        A stack whose solve fails or whose states leave the physics is solved again member by
        member for the period, each member with its own status; False: the stack's
        :class:`~snoworm.simulation.guard.SolverError` goes to the caller.
    """

    bounded: bool
    vode_stack: bool
    members_alone: bool


#: The Simulator's and the environments' policy: bounded stacks on VODE, failed members alone per period.
PERIODS = StackPolicy(bounded=True, vode_stack=True, members_alone=True)
#: The batched sweeps' policy (:func:`~snoworm.simulation.driver.simulate_batch`): one stack of the
#: group, the scenario's method (LSODA's max norm for a stack), a failure to the caller.
WHOLE_RUNS = StackPolicy(bounded=False, vode_stack=False, members_alone=False)


def stack_size(model) -> int:
    """Most members of ``model`` in one stacked solve under :data:`PERIODS`: :data:`STACK_MAX_MEMBERS`,
    fewer if their states would pass :data:`STACK_MAX_STATES`, at least 1."""
    return max(1, min(STACK_MAX_MEMBERS, STACK_MAX_STATES // model.n_states))


def _stacks(models, most):
    """``[(members, stacked model)]``: the member ``models`` in the fewest stacks of at most ``most``
    members, of sizes that differ by at most one (one stacked model per run of the same members:
    copies of one model share it)."""
    count = -(-len(models) // most)
    q, r = divmod(len(models), count)
    sizes = [q + 1] * r + [q] * (count - r)
    made, out, start = {}, [], 0
    for k in sizes:
        part = models[start : start + k]
        key = tuple(map(id, part))
        if key not in made:
            made[key] = ChainModel.stack(part) if k > 1 else part[0]
        out.append((slice(start, start + k), made[key]))
        start += k
    return out


def _members(ctl, members):
    """The controls of ``members`` (a slice or an index) out of stacked controls (the arrays with a
    member axis have two dimensions)."""
    return replace(
        ctl, **{k: getattr(ctl, k)[members] for k in ctl.__dataclass_fields__ if np.ndim(getattr(ctl, k)) == 2}
    )


def _speed_limit(model) -> float:
    """The sanity limit on a member's speeds [m/s]: :data:`SPEED_SANITY_FACTOR` times its fastest
    no-load wheel speed."""
    return SPEED_SANITY_FACTOR * float(np.max(model.seg.no_load_speed_radps * model.seg.wheel_radius_m))


class ChainStepper:
    """``num_members`` copies of ``model`` (or the members of :meth:`of_members`) advanced over
    held-command periods (see the module docstring).

    Parameters
    ----------
    model : ChainModel
        One chain (not stacked).
    sim : SimulationConfig
        The scenario's solver settings (method, tolerances, work and wall-clock limits).
    num_members : int
        B, the copies stepped together (1: one chain).
    name : str
        The run's name in solver messages.
    policy : StackPolicy
        How the members are stacked and what a failed stack does (:data:`PERIODS` or :data:`WHOLE_RUNS`).
    carry_history : bool
        See :attr:`carry_history`.
    asked_steps : bool
        Each period is a step asked (``IntervalSolver(asked_steps=True)``: the work limit allows it
        :data:`~snoworm.simulation.guard.WORK_NFEV_PER_INTERVAL` more); False for a mode's intervals.
    progress : callable, optional
        ``progress(t_s, duration_s)`` within long periods, handed to each stack's interval solve.
    members : list of ChainModel, optional
        The member chains (one structure, their own parameters) instead of ``num_members`` copies
        of ``model`` (:meth:`of_members`).

    Attributes
    ----------
    stats : dict
        Solver counters over every stack (``nfev``, ``njev``, ``nlu``, ``intervals``, and ``retries``
        once a period needed another method); under a policy that solves members alone, also
        ``member_solves`` (members solved alone after their stack failed) and ``solver_failures``.
    """

    def __init__(
        self,
        model,
        sim,
        num_members=1,
        name="step",
        *,
        policy=PERIODS,
        carry_history=False,
        asked_steps=True,
        progress=None,
        members=None,
    ):
        models = [model] * int(num_members) if members is None else list(members)
        self.models, self.model, self.sim, self.name = models, models[0], sim, name
        self.num_members, self.policy = len(models), policy
        self.stats = {"nfev": 0, "njev": 0, "nlu": 0, "intervals": 0}
        if policy.members_alone:
            self.stats.update(member_solves=0, solver_failures=0)
        same = all(m is model for m in models)
        self._vmax = np.array([_speed_limit(model)] * len(models) if same else [_speed_limit(m) for m in models])
        most = stack_size(model) if policy.bounded else len(models)
        self._stacks = [
            (
                part,
                IntervalSolver(
                    m,
                    sim,
                    name,
                    progress=progress,
                    vode_stack=policy.vode_stack,
                    stats=self.stats,
                    asked_steps=asked_steps,
                ),
            )
            for part, m in _stacks(models, most)
        ]
        self.carry_history = carry_history

    @classmethod
    def of_members(cls, models, sim, name="step", **options) -> ChainStepper:
        """A stepper of the member chains ``models`` (same structure, their own parameters: a
        batched sweep's cases), stacked with :meth:`ChainModel.stack <snoworm.model.chain.ChainModel.stack>`;
        ``options`` as for :class:`ChainStepper` (``policy``, ``carry_history``, ``asked_steps``,
        ``progress``).

        Raises ValueError (from :meth:`~snoworm.model.chain.ChainModel.stack`) if the models cannot be stacked."""
        models = list(models)
        if not models:
            raise ValueError("ChainStepper.of_members needs at least one member model")
        return cls(models[0], sim, len(models), name, members=models, **options)

    @property
    def stacks(self) -> list:
        """``[(members, model)]``: the members (a slice) of each stack and its (stacked) model."""
        return [(members, solver.model) for members, solver in self._stacks]

    @property
    def carry_history(self) -> bool:
        """Whether VODE carries its history into the next period (while every member holds its
        command; a state that changed between periods restarts it by itself)."""
        return self._carry

    @carry_history.setter
    def carry_history(self, value) -> None:
        self._carry = bool(value)
        for _, solver in self._stacks:
            solver.carry_history = self._carry

    def solve(self, ctl, t0, t1, y, t_eval, label="step"):
        """One period ``[t0, t1]`` of every member from the states ``y`` (B, n_states) under ``ctl``
        (controls of one chain, or stacked with a member axis of length B); ``label`` names the
        period in solver messages.

        Returns
        -------
        ys : ndarray, shape (len(t_eval), B, n_states)
            The states at ``t_eval``; a failed member's rows hold its start state.
        y_end : ndarray, shape (B, n_states)
            The integrator's states at ``t1`` (a failed member's: its start state).
        failed : ndarray of bool, shape (B,)
            The members whose period failed alone too (solver failure or a state out of the physics).
        errors : dict
            ``{member: message}`` of the failed members.

        Raises
        ------
        SolverError
            Under a policy that does not solve members alone (:data:`WHOLE_RUNS`), if a stack fails.
        """
        B, n_s = self.num_members, self.model.n_states
        y = np.asarray(y, float).reshape(B, n_s)
        if not self.policy.members_alone:
            return self._solve_stacks(ctl, t0, t1, y, t_eval, label)
        ys, y_end = np.empty((len(t_eval), B, n_s)), y.copy()
        failed, errors = np.zeros(B, bool), {}
        for members, solver in self._stacks:
            part = ctl if len(self._stacks) == 1 else _members(ctl, members)
            try:
                ts, yk, _, yk_end, _ = solver.solve(part, t0, t1, y[members].reshape(-1), (), t_eval, label)
                if ts.size == len(t_eval):
                    yk = yk.reshape(ts.size, -1, n_s)
                    ys[:, members] = yk
                    if not self._insane(yk, members).any():
                        y_end[members] = np.reshape(yk_end, (-1, n_s))
                        continue
            except SolverError as exc:
                if members.stop - members.start == 1:  # one chain: solving it alone again is the same solve
                    ys[:, members], failed[members], errors[members.start] = y[members], True, str(exc)
                    self.stats["solver_failures"] += 1
                    continue
            self._solve_members(ctl, t0, t1, t_eval, y, members, (ys, y_end), failed, errors, label)
        return ys, y_end, failed, errors

    def _solve_stacks(self, ctl, t0, t1, y, t_eval, label):
        """:meth:`solve` of a policy that leaves a failed stack to its caller: every stack's period,
        the first failure raised.  One stack's states are the solver's own array, not copied (a
        batched sweep's group of hundreds of members; and the same memory layout as the solver's,
        so what is summed from them is summed in the same order)."""
        n_t, n_s = len(t_eval), self.model.n_states
        ys, ends = [], []
        for members, solver in self._stacks:
            part = ctl if len(self._stacks) == 1 else _members(ctl, members)
            ts, yk, _, yk_end, _ = solver.solve(part, t0, t1, y[members].reshape(-1), (), t_eval, label)
            if ts.size != n_t:
                raise SolverError(
                    f"{self.name!r}: the stacked solve ended at {ts.size} of {n_t} output times ({label})"
                )
            ys.append(yk.reshape(n_t, -1, n_s))
            ends.append(np.reshape(yk_end, (-1, n_s)))
        if len(ys) > 1:
            ys, ends = [np.concatenate(ys, axis=1)], [np.concatenate(ends)]
        return ys[0], ends[0], np.zeros(self.num_members, bool), {}

    def _solve_members(self, ctl, t0, t1, t_eval, y, members, out, failed, errors, label):
        """Each member of the stack ``members`` (a slice) alone into ``out`` (``ys``, ``y_end``),
        ``failed`` and ``errors``."""
        ys, y_end = out
        stacked = self.num_members > 1
        for b in range(members.start, members.stop):
            self.stats["member_solves"] += 1
            ys[:, b] = y[b]
            try:
                alone = IntervalSolver(self.models[b], self.sim, self.name, stats=self.stats)
                part = _members(ctl, b) if stacked else ctl
                tb, yb, _, yb_end, _ = alone.solve(part, t0, t1, y[b], (), t_eval, label)
            except SolverError as exc:
                failed[b], errors[b] = True, str(exc)
                self.stats["solver_failures"] += 1
                continue
            if tb.size != len(t_eval) or self._insane(yb[:, None, :], slice(b, b + 1))[0]:
                failed[b], errors[b] = True, "the member's state left the physics (non-finite or runaway speed)"
                self.stats["solver_failures"] += 1
                continue
            ys[:, b, :], y_end[b] = yb, yb_end

    def _insane(self, ys, members):
        """Per member of ``members`` (a slice): a non-finite state or a speed beyond its sanity limit
        in ``ys`` (n_t, members, n_states)."""
        lay = self.model.layout
        Y = ys.reshape(ys.shape[:2] + (lay.n, lay.n_s))
        # two reductions per period (this runs after every step of the Simulator and the environments):
        # a NaN or an infinity anywhere makes a member's sum non-finite, and a NaN speed fails ``<=``
        v = np.abs(Y[..., lay.v]).max(axis=(0, 2))
        return ~np.isfinite(Y.sum(axis=(0, 2, 3))) | ~(v <= self._vmax[members])
