"""One stepper for one chain or many: held-command periods of B copies of a chain, solved as stacks.

:class:`ChainStepper` advances ``B`` copies of one chain (``B = 1``: one chain) over a period in
which each member holds its controls, with no events (a control period of a
:class:`~snoworm.simulation.stepwise.Simulator`, of the single Gymnasium environment or of the
vector environment).  The members are integrated as stacks of at most :func:`stack_size`
members (:meth:`ChainModel.stack <snoworm.model.chain.ChainModel.stack>`: the kernel with one
more leading axis), each by its own :class:`~snoworm.simulation.interval.IntervalSolver` on VODE
with its tolerances divided by sqrt(stack size) (``vode_stack``: VODE's error test is a weighted
RMS norm over the whole stack, and with those tolerances a stack that passes it has every member
within the RMS norm it has alone).  A stack whose solve fails, or whose states leave the physics
(non-finite, or a speed beyond :data:`~snoworm.simulation.guard.SPEED_SANITY_FACTOR` times the
fastest no-load wheel speed), is solved again member by member from the same start, so one bad
member never stops the others: each member gets its own status (``failed``) and message.

Why stacks of at most :data:`STACK_MAX_MEMBERS` members and :data:`STACK_MAX_STATES` states: a
stack steps at the pace of its most demanding member, so its evaluations per period grow with its
size (tow6, random actions: 193 for 1 member, 317 for 64, 481 for 256, 662 for 1 000) while the
kernel's cost per member falls until ~64 members; and VODE's level-1 BLAS calls on the whole state
start OpenBLAS threads past 10 000 elements, which cost 3-10x a period on a loaded machine.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..model.chain import ChainModel
from .guard import SPEED_SANITY_FACTOR, SolverError
from .interval import IntervalSolver

__all__ = ["ChainStepper", "STACK_MAX_MEMBERS", "STACK_MAX_STATES", "stack_size"]

#: Most members of one stacked solve (see the module docstring).
STACK_MAX_MEMBERS = 64
#: Most states of one stacked solve (see the module docstring).
STACK_MAX_STATES = 8192


def stack_size(model) -> int:
    """Most members of ``model`` in one stacked solve: :data:`STACK_MAX_MEMBERS`, fewer if their
    states would pass :data:`STACK_MAX_STATES`, at least 1."""
    return max(1, min(STACK_MAX_MEMBERS, STACK_MAX_STATES // model.n_states))


def _stacks(model, num_members):
    """``[(members, stacked model)]``: ``num_members`` members in the fewest stacks of at most
    :func:`stack_size` members, of sizes that differ by at most one (one stacked model per size)."""
    count = -(-num_members // stack_size(model))
    q, r = divmod(num_members, count)
    sizes = [q + 1] * r + [q] * (count - r)
    models, out, start = {}, [], 0
    for k in sizes:
        if k not in models:
            models[k] = ChainModel.stack([model] * k) if k > 1 else model
        out.append((slice(start, start + k), models[k]))
        start += k
    return out


def _members(ctl, members):
    """The controls of ``members`` (a slice or an index) out of stacked controls (the arrays with a
    member axis have two dimensions)."""
    return replace(
        ctl, **{k: getattr(ctl, k)[members] for k in ctl.__dataclass_fields__ if np.ndim(getattr(ctl, k)) == 2}
    )


class ChainStepper:
    """``num_members`` copies of ``model`` advanced over held-command periods (see the module docstring).

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

    Attributes
    ----------
    stats : dict
        Solver counters over every stack (``nfev``, ``njev``, ``nlu``, ``intervals``), with
        ``member_solves`` (members solved alone after their stack failed) and ``solver_failures``.
    """

    def __init__(self, model, sim, num_members=1, name="step"):
        self.model, self.sim, self.name, self.num_members = model, sim, name, int(num_members)
        self.stats = {"nfev": 0, "njev": 0, "nlu": 0, "intervals": 0, "member_solves": 0, "solver_failures": 0}
        self._vmax = SPEED_SANITY_FACTOR * float(np.max(model.seg.no_load_speed_radps * model.seg.wheel_radius_m))
        self._stacks = [
            (members, IntervalSolver(m, sim, name, vode_stack=True, stats=self.stats, asked_steps=True))
            for members, m in _stacks(model, self.num_members)
        ]
        self.carry_history = False

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

    def solve(self, ctl, t0, t1, y, t_eval):
        """One period ``[t0, t1]`` of every member from the states ``y`` (B, n_states) under ``ctl``
        (controls of one chain, or stacked with a member axis of length B).

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
        """
        B, n_s = self.num_members, self.model.n_states
        y = np.asarray(y, float).reshape(B, n_s)
        ys, y_end = np.empty((len(t_eval), B, n_s)), y.copy()
        failed, errors = np.zeros(B, bool), {}
        for members, solver in self._stacks:
            part = ctl if len(self._stacks) == 1 else _members(ctl, members)
            try:
                ts, yk, _, yk_end, _ = solver.solve(part, t0, t1, y[members].reshape(-1), (), t_eval, "step")
                if ts.size == len(t_eval):
                    yk = yk.reshape(ts.size, -1, n_s)
                    ys[:, members] = yk
                    if not self._insane(yk).any():
                        y_end[members] = np.reshape(yk_end, (-1, n_s))
                        continue
            except SolverError as exc:
                if members.stop - members.start == 1:  # one chain: solving it alone again is the same solve
                    ys[:, members], failed[members], errors[members.start] = y[members], True, str(exc)
                    self.stats["solver_failures"] += 1
                    continue
            self._solve_members(ctl, t0, t1, t_eval, y, members, (ys, y_end), failed, errors)
        return ys, y_end, failed, errors

    def _solve_members(self, ctl, t0, t1, t_eval, y, members, out, failed, errors):
        """Each member of the stack ``members`` (a slice) alone into ``out`` (``ys``, ``y_end``),
        ``failed`` and ``errors``."""
        ys, y_end = out
        stacked = self.num_members > 1
        for b in range(members.start, members.stop):
            self.stats["member_solves"] += 1
            ys[:, b] = y[b]
            try:
                alone = IntervalSolver(self.model, self.sim, self.name, stats=self.stats)
                part = _members(ctl, b) if stacked else ctl
                tb, yb, _, yb_end, _ = alone.solve(part, t0, t1, y[b], (), t_eval, "step")
            except SolverError as exc:
                failed[b], errors[b] = True, str(exc)
                self.stats["solver_failures"] += 1
                continue
            if tb.size != len(t_eval) or self._insane(yb[:, None, :])[0]:
                failed[b], errors[b] = True, "the member's state left the physics (non-finite or runaway speed)"
                self.stats["solver_failures"] += 1
                continue
            ys[:, b, :], y_end[b] = yb, yb_end

    def _insane(self, ys):
        """Per member: a non-finite state or a speed beyond the sanity limit in ``ys`` (n_t, B, n_states)."""
        lay = self.model.layout
        Y = ys.reshape(ys.shape[:2] + (lay.n, lay.n_s))
        finite = np.all(np.isfinite(Y), axis=(0, 2, 3))
        v = np.max(np.abs(np.nan_to_num(Y[..., lay.v], nan=np.inf)), axis=(0, 2))
        return ~finite | (v > self._vmax)
