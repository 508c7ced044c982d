"""ODEPACK's VODE stepped one step at a time, with dense output and state events.

``simulation.method: VODE`` (the inching scenarios) integrates through :class:`VodeStepper`
instead of :func:`scipy.integrate.solve_ivp`.  VODE is a variable-coefficient BDF code with a
banded Jacobian; unlike LSODA it never switches to the non-stiff Adams methods.  After every
restart at a gait phase change LSODA starts non-stiff, switches to BDF in the stiff transient
(locked wheels, joint force loops) and re-evaluates its Jacobian far more often (inchworm6:
docs/performance.md).

The stepper is driven by time, not by a ``t_span``: :meth:`VodeStepper.advance` integrates
from wherever the stepper is to a time ``t1`` that it never steps past (VODE's critical time,
``itask = 5``), samples an output grid from VODE's Nordsieck history and stops at the first
terminal event, located by Brent's method on the same interpolant (as ``solve_ivp`` does).

Controls may change between two calls of :meth:`advance` **without a restart**: set
:attr:`VodeStepper.ctl` and call :meth:`advance` again.  The multistep history then carries on
across the switch; the error test sees the jump in the right-hand side and shortens the step
as it needs, and if VODE gives up on it (repeated error-test failures at a large jump), the
stepper restarts at the switch by itself (:attr:`VodeStepper.recoveries`).  :meth:`restart` discards the history (order 1, a new initial step), which is
what the interval driver does at every interval start, and what must happen after an event
(the stepper has then already stepped beyond the event time).

Numbers from a run with this stepper differ from a ``solve_ivp`` run within the tolerances,
not bitwise.  Its error test is VODE's weighted RMS norm, so the driver keeps LSODA (weighted
max norm) for stacked batches, where each member must be held to its own tolerance.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import ode
from scipy.optimize import brentq

__all__ = ["VodeStepper", "VodeError"]

#: Positions in VODE's work arrays (DVODE's optional outputs, 0-based).
_RW_TCRIT, _RW_H0, _RW_HU, _RW_YH = 0, 4, 10, 20
_IW_NST, _IW_NFE, _IW_NJE, _IW_NQU, _IW_NLU = 10, 11, 12, 13, 18
_ITASK_ONE_STEP_TCRIT = 5
#: Events are located to this absolute time [s] (``solve_ivp`` locates to 4 machine epsilons).
EVENT_XTOL_S = 4 * np.finfo(float).eps


class VodeError(ArithmeticError):
    """VODE failed (its ``istate`` and time are in the message)."""


class VodeStepper:
    """VODE (BDF, banded Jacobian) under the caller's control, one step at a time.

    Parameters
    ----------
    fun : callable
        ``fun(t, y, ctl) -> dy/dt``.
    jac : callable
        ``jac(t, y, ctl)``: the Jacobian in LAPACK packed band format, shape
        ``(lband + uband + 1, n)`` (as for ``solve_ivp(method="LSODA")``).
    n : int
        Number of states.
    rtol : float
        Relative tolerance.
    atol : array_like
        Absolute tolerance (scalar or per state).
    lband, uband : int
        Lower and upper bandwidth of the Jacobian.
    max_step : float, optional
        Largest step [s] (None: unlimited).
    ctl : object, optional
        Controls handed to ``fun`` and ``jac`` (see :attr:`ctl`).
    max_order : int
        Highest BDF order (1 to 5).
    first_step : float, optional
        Step size tried first after a restart [s] (None: VODE's own estimate).

    Attributes
    ----------
    ctl : object
        The controls the right-hand side sees from now on; may be changed between calls of
        :meth:`advance` (with or without :meth:`restart`).
    t, y : float, ndarray
        Where the integration stands (after the last step).
    t_old : float or None
        Start of the last step (None right after a restart).
    nfev, njev, nlu, nsteps : int
        Cumulative right-hand-side calls, Jacobians, LU decompositions and steps since construction.
    recoveries : int
        Restarts made by :meth:`step` after a failure of a continued history.
    """

    def __init__(self, fun, jac, n, *, rtol, atol, lband, uband, max_step=None, ctl=None, max_order=5, first_step=None):
        self.ctl = ctl
        self.first_step = first_step
        self.n = int(n)
        self._fun, self._jac = fun, jac
        self._ode = ode(fun, jac)  # sets VODE up; steps call its runner with (ctl,) as the extra arguments
        self._ode.set_integrator(
            "vode",
            method="bdf",
            rtol=rtol,
            atol=atol,
            lband=lband,
            uband=uband,
            nsteps=10**9,
            order=max_order,
            max_step=0.0 if max_step is None else max_step,
        )
        self._it = self._ode._integrator
        self._done = {"nfev": 0, "njev": 0, "nlu": 0, "nsteps": 0}
        self.t = self.t_old = None
        self.y = None
        self._fresh = True
        #: restarts after a failure with history from before a change of controls (see :meth:`step`)
        self.recoveries = 0

    # ------------------------------------------------------------------ counters
    def _counts(self):
        iw = self._it.iwork
        return {"nfev": int(iw[_IW_NFE]), "njev": int(iw[_IW_NJE]), "nlu": int(iw[_IW_NLU]), "nsteps": int(iw[_IW_NST])}

    def _cum(self, key):
        return self._done[key] + (self._counts()[key] if self.t is not None else 0)

    nfev = property(lambda self: self._cum("nfev"))
    njev = property(lambda self: self._cum("njev"))
    nlu = property(lambda self: self._cum("nlu"))
    nsteps = property(lambda self: self._cum("nsteps"))

    # ------------------------------------------------------------------ stepping
    def restart(self, t, y):
        """Start again at ``(t, y)``: history discarded, order 1 (VODE chooses the first step)."""
        if self.t is not None:
            for k, v in self._counts().items():
                self._done[k] += v
        self._ode.set_initial_value(np.array(y, float), float(t))
        if self.first_step:
            self._it.rwork[_RW_H0] = self.first_step
        self.t, self.t_old, self.y = float(t), None, np.array(y, float)
        self._fresh = True

    def step(self, t_bound):
        """Take one step that does not pass ``t_bound``; returns the new time.

        If VODE fails while its history reaches back before the last restart's point (after
        :attr:`ctl` changed without a restart, say), it is restarted at the last accepted state
        and the step is tried once more (counted in :attr:`recoveries`).

        Raises
        ------
        VodeError
            If VODE fails from a fresh restart (error test or corrector failures, too small a
            step), returns a non-finite state, or makes no progress.
        """
        try:
            return self._step(t_bound)
        except VodeError:
            if self._fresh:
                raise
        self.recoveries += 1
        self.restart(self.t, self.y)
        return self._step(t_bound)

    def _step(self, t_bound):
        it = self._it
        rtol, atol, _, istate, rwork, iwork, mf = it.call_args
        rwork[_RW_TCRIT] = t_bound
        args = (self.ctl,)
        # the runner of scipy's vode wrapper (what its run() calls), without the wrapper's warning
        y, t, istate = it.runner(
            self._fun,
            self._jac,
            self.y,
            self.t,
            t_bound,
            rtol,
            atol,
            _ITASK_ONE_STEP_TCRIT,
            istate,
            rwork,
            iwork,
            mf,
            args,
            args,
            it.state_doubles,
            it.state_ints,
        )
        if istate < 0:
            raise VodeError(f"VODE failed near t = {self.t:.6g} s (istate {istate})")
        it.call_args[3] = 2  # continue (what run() does after a success)
        if not (t > self.t and np.isfinite(y.sum())):  # one reduction: NaN or inf anywhere
            raise VodeError(f"VODE made no finite progress at t = {self.t:.6g} s")
        self.t_old, self.t, self.y = self.t, float(t), y
        self._fresh = False
        return self.t

    def dense(self, ts):
        """States at times ``ts`` within the last step, shape ``(len(ts), n)``.

        Evaluates VODE's Nordsieck history ``z_j = h^j y^(j) / j!`` (``rwork[20:]``, column-major
        ``(n, q + 1)``) at ``s = (t - t_n) / h``: ``y(t) = sum_j z_j s^j`` (DVODE's interpolation
        routine DVINDY).  On return from a step the history is still scaled by the step just
        taken (``h = rwork[10]``) at the order just used (``q = iwork[13]``); the rescaling for
        the next step happens when it starts (checked in tests/test_simulation_vode.py).
        """
        it = self._it
        q = int(it.iwork[_IW_NQU])
        yh = it.rwork[_RW_YH : _RW_YH + (q + 1) * self.n].reshape((self.n, q + 1), order="F")
        s = (np.atleast_1d(np.asarray(ts, float)) - self.t) / it.rwork[_RW_HU]
        return (s[:, None] ** np.arange(q + 1)) @ yh.T

    # ------------------------------------------------------------------ intervals
    def nfev_now(self) -> int:
        """Right-hand-side calls since construction, read from VODE's own counter (cheap: for work limits)."""
        return self._done["nfev"] + (int(self._it.iwork[_IW_NFE]) if self.t is not None else 0)

    def advance(self, t1, events=(), t_eval=None, on_step=None):
        """Integrate from :attr:`t` to ``t1`` or to the first terminal event, whichever comes first.

        Parameters
        ----------
        t1 : float
            End time; never stepped past.
        events : sequence of callable
            Terminal events ``ev(t, y) -> float`` with an optional ``direction`` attribute
            (as in ``solve_ivp``: > 0 only rising, < 0 only falling, 0 either).
        t_eval : sequence of float, optional
            Increasing output times within ``[t, t1]``; those at or before the stepper's
            current time are taken from its current state.
        on_step : callable, optional
            ``on_step(t, nfev)`` after every step, with :meth:`nfev_now` (work limits; it may raise).

        Returns
        -------
        ts : ndarray
            The ``t_eval`` times reached before the end, then the end time itself (an event
            time, or ``t1`` if it is not already the last ``t_eval`` time).
        ys : ndarray, shape ``(len(ts), n)``
        t_end : float
        y_end : ndarray
        which : int or None
            Index of the event that ended the integration, or None if ``t1`` was reached.
            After an event the stepper stands beyond ``t_end``: call :meth:`restart` before
            integrating on.
        """
        # the output grid as a Python list walked by index: no NumPy call per step
        grid = [] if t_eval is None else (t_eval if isinstance(t_eval, list) else np.asarray(t_eval, float).tolist())
        ng, gi, t_now = len(grid), 0, self.t
        out_t, out_y = [], []
        while gi < ng and grid[gi] <= t_now:
            gi += 1
        if gi:
            out_t.extend(grid[:gi])
            out_y.extend([self.y.copy()] * gi)
        dirs = [getattr(ev, "direction", 0) for ev in events]
        g = [ev(self.t, self.y) for ev in events]
        while True:
            self.step(t1)
            if on_step is not None:
                on_step(self.t, self.nfev_now())
            hit = None
            if events:
                hit, g = self._locate(events, dirs, g)
            gj = gi
            if hit:
                while gj < ng and grid[gj] < hit[0]:
                    gj += 1
            else:
                while gj < ng and grid[gj] <= self.t:
                    gj += 1
            if gj > gi:
                out_t.extend(grid[gi:gj])
                out_y.extend(self.dense(grid[gi:gj]))
                gi = gj
            if hit:
                t_end, which = hit
                y_end = self.dense(t_end)[0]
                break
            if self.t >= t1:
                t_end, which, y_end = t1, None, self.y.copy()
                break
        if not out_t or out_t[-1] != t_end:
            out_t.append(t_end)
            out_y.append(y_end)
        else:
            out_y[-1] = y_end
        return np.asarray(out_t, float), np.asarray(out_y, float), float(t_end), y_end, which

    def _locate(self, events, dirs, g_old):
        """The earliest event whose sign change over the last step matches its direction."""
        if not events:
            return None, g_old
        g_new = [ev(self.t, self.y) for ev in events]
        hits = []
        for j, ev in enumerate(events):
            up = g_old[j] <= 0 <= g_new[j]
            down = g_old[j] >= 0 >= g_new[j]
            if (up and dirs[j] >= 0 or down and dirs[j] <= 0) and (g_old[j] != 0 or g_new[j] != 0):
                if g_new[j] == 0:
                    t_root = self.t
                elif g_old[j] == 0:
                    t_root = self.t_old
                else:
                    t_root = brentq(
                        lambda tt, e=ev: e(tt, self.dense(tt)[0]),
                        self.t_old,
                        self.t,
                        xtol=EVENT_XTOL_S,
                        rtol=EVENT_XTOL_S,
                    )
                hits.append((t_root, j))
        return (min(hits) if hits else None), g_new
