"""A wall-clock bound on a user's code: a controller looping forever cannot hang a run.

``simulation.max_wall_s`` is checked by the driver between right-hand-side evaluations, which a
loop inside a controller's ``__call__`` or ``__init__`` (or its module's import) never reaches.
:func:`wall_limit` therefore arms a POSIX interval timer (``signal.setitimer(ITIMER_REAL)``)
for the time left before the run's deadline; its ``SIGALRM`` handler raises :class:`WallLimit`
inside the user's code, wherever it loops, and again every :data:`REPEAT_S` seconds should the
code swallow it.  :class:`WallLimit` derives from ``BaseException`` so an ``except Exception``
in the user's code does not catch it.

Limits (documented in docs/controllers.md): the timer works in the main thread of a process on
POSIX systems only -- ``snoworm run``, ``sweep`` in one process or with ``-j`` (each worker
process runs its cases in its main thread); on a Dask worker (threads), in a thread of your
own, or on Windows the block runs unbounded.  A C extension that does not return to the
interpreter (a blocking system call that retries on EINTR, a long NumPy operation) is
interrupted only when it returns.  The user's own ``SIGALRM`` timer, if any, is suspended
during the call and restored after.
"""

from __future__ import annotations

import signal
import threading
import time
from contextlib import contextmanager

__all__ = ["WallLimit", "wall_limit", "REPEAT_S", "bounded"]

#: Seconds between repeated alarms once the deadline has passed (user code that swallowed one).
REPEAT_S = 0.25


class WallLimit(BaseException):
    """The run's wall-clock deadline passed inside the user's code."""


def bounded() -> bool:
    """Whether :func:`wall_limit` can bound code here (POSIX, main thread)."""
    return hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()


def _alarm(signum, frame):
    raise WallLimit()


@contextmanager
def wall_limit(deadline):
    """Run the block with a deadline (a :func:`time.perf_counter` value; None: no bound).

    Raises
    ------
    WallLimit
        The deadline passed before or during the block (only where :func:`bounded`).
    """
    if deadline is None or not bounded():
        yield
        return
    left = deadline - time.perf_counter()
    if left <= 0:
        raise WallLimit()
    old_handler = signal.signal(signal.SIGALRM, _alarm)
    old_timer = signal.setitimer(signal.ITIMER_REAL, left, REPEAT_S)
    try:
        yield
    finally:
        _disarm(old_handler if old_handler is not None else signal.SIG_DFL, old_timer)


def _disarm(old_handler, old_timer):
    """Stop the timer and restore the earlier handler and timer; an alarm arriving meanwhile
    (its WallLimit raised here, not in the user's code) is absorbed and the step retried."""
    while True:
        try:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, old_handler)
            break
        except WallLimit:
            continue
    if old_timer[0] > 0:
        signal.setitimer(signal.ITIMER_REAL, *old_timer)
