"""VodeStepper: steps, dense output, events, continuation across a change of controls, failures."""

import numpy as np
import pytest
from scipy.linalg import expm

from snoworm.simulation.vode import VodeError, VodeStepper

# a banded linear test system dy/dt = A y (tridiagonal, damped, with a fast and slow part)
N = 6
A = (np.diag(np.full(N, -2.0)) + np.diag(np.full(N - 1, 1.0), 1) + np.diag(np.full(N - 1, 0.5), -1)) * np.linspace(
    1, 50, N
)[:, None]
Y0 = np.linspace(1.0, 2.0, N)


def _lin_rhs(t, y, ctl):
    return A @ y + (0.0 if ctl is None else ctl)


def _lin_jac(t, y, ctl):
    """LAPACK packed band (lband = uband = 1): row uband + i - j holds A[i, j]."""
    ab = np.zeros((3, N))
    for j in range(N):
        for i in range(max(0, j - 1), min(N, j + 2)):
            ab[1 + i - j, j] = A[i, j]
    return ab


def _stepper(rtol=1e-9, atol=1e-12, **kw):
    return VodeStepper(_lin_rhs, _lin_jac, N, rtol=rtol, atol=atol, lband=1, uband=1, **kw)


def test_advance_reaches_t1_exactly_and_matches_the_exact_solution():
    st = _stepper()
    st.restart(0.0, Y0)
    grid = np.linspace(0.0, 0.3, 31)
    ts, ys, t_end, y_end, which = st.advance(0.3, t_eval=grid)
    assert which is None and t_end == 0.3 and st.t == 0.3  # never steps past t1
    np.testing.assert_array_equal(ts, grid)
    exact = np.array([expm(A * t) @ Y0 for t in grid])
    np.testing.assert_allclose(ys, exact, rtol=1e-6, atol=1e-8)  # dense output between steps
    np.testing.assert_array_equal(y_end, ys[-1])
    assert st.nsteps > 5 and st.nfev >= st.nsteps and st.njev >= 1


def test_dense_output_reproduces_the_step_ends():
    """The Nordsieck history is scaled by the step just taken: dense(t_old) is the previous state."""
    st = _stepper(rtol=1e-6, atol=1e-9)
    st.restart(0.0, Y0)
    worst = 0.0
    for _ in range(40):
        y_old = st.y.copy()
        st.step(1.0)
        np.testing.assert_allclose(st.dense(st.t)[0], st.y, rtol=0, atol=1e-14)
        worst = max(worst, float(np.max(np.abs(st.dense(st.t_old)[0] - y_old))))
    assert worst < 1e-9


def test_event_is_located_on_the_dense_output():
    # y0 decays as sum of exponentials; locate where the first state falls to 0.5 (falling only)
    def half(t, y):
        return y[0] - 0.5

    half.direction = -1
    st = _stepper()
    st.restart(0.0, Y0)
    ts, ys, t_end, y_end, which = st.advance(5.0, [half], t_eval=np.arange(0.0, 5.0, 0.01))
    assert which == 0 and t_end < 5.0
    assert abs(y_end[0] - 0.5) < 1e-9
    exact = expm(A * t_end) @ Y0
    assert abs(exact[0] - 0.5) < 1e-7
    assert ts[-1] == t_end and np.all(ts[:-1] < t_end) and np.all(np.diff(ts) > 0)
    assert st.t >= t_end  # the stepper stands at or beyond the event


def test_event_direction_filters_crossings():
    def rising(t, y):
        return 0.5 - y[0]  # rises through 0 as y[0] falls through 0.5

    rising.direction = -1  # ... so a falling-only event never fires
    st = _stepper()
    st.restart(0.0, Y0)
    *_, t_end, _, which = st.advance(0.5, [rising])
    assert which is None and t_end == 0.5


def test_controls_change_without_restart_continues_the_history():
    """dy/dt = A y + u: switch u at t = 0.2 with and without a restart; both exact, history kept."""
    u1, u2 = np.full(N, 3.0), np.full(N, -1.0)
    exact_02 = expm(A * 0.2) @ Y0 + np.linalg.solve(A, (expm(A * 0.2) - np.eye(N)) @ u1)
    exact_04 = expm(A * 0.2) @ exact_02 + np.linalg.solve(A, (expm(A * 0.2) - np.eye(N)) @ u2)
    ends = {}
    for restart in (False, True):
        st = _stepper(ctl=u1)
        st.restart(0.0, Y0)
        st.advance(0.2)
        assert st.t == 0.2  # the switch falls on a step boundary (critical time)
        n_before = st.nsteps
        st.ctl = u2
        if restart:
            st.restart(st.t, st.y)
        else:
            assert st.t_old is not None  # the multistep history carries on
        *_, y_end, _ = st.advance(0.4)
        np.testing.assert_allclose(y_end, exact_04, rtol=1e-6, atol=1e-8)
        ends[restart] = (st.nsteps - n_before, st.recoveries)
    assert ends[True][1] == 0 and ends[True][0] > 0


def test_continued_history_survives_a_small_switch_without_recovery():
    """A switch within the tolerance's reach is integrated through with the old history."""
    st = _stepper(rtol=1e-5, atol=1e-6, ctl=np.zeros(N))
    st.restart(0.0, Y0)
    st.advance(0.2)
    st.ctl = np.full(N, 1e-3)
    st.advance(0.4)
    assert st.recoveries == 0


def test_counters_accumulate_over_restarts():
    st = _stepper()
    st.restart(0.0, Y0)
    st.advance(0.1)
    n1 = st.nfev
    st.restart(0.1, st.y)
    st.advance(0.2)
    assert st.nfev > n1 > 0


def test_failure_raises_vode_error():
    """A solution that blows up in finite time (y' = y^2, y(0) = 1, singular at t = 1)."""
    st = VodeStepper(
        lambda t, y, c: y * y, lambda t, y, c: np.array([2 * y]), 1, rtol=1e-6, atol=1e-9, lband=0, uband=0
    )
    st.restart(0.0, [1.0])
    with pytest.raises(VodeError, match="VODE (failed|made no finite progress)"):
        st.advance(2.0)
    assert 0.99 < st.t < 1.0


def test_max_step_is_respected():
    st = _stepper(max_step=0.01)
    st.restart(0.0, Y0)
    prev = st.t
    while st.t < 0.2:
        st.step(0.2)
        assert st.t - prev <= 0.01 + 1e-12
        prev = st.t


def test_max_order_and_first_step():
    st = _stepper(rtol=1e-6, atol=1e-9, max_order=2, first_step=1e-7)
    st.restart(0.0, Y0)
    st.step(1.0)
    assert st.t == pytest.approx(1e-7, rel=1e-9)  # the given first step, accepted
    orders = []
    while st.t < 0.5:
        st.step(0.5)
        orders.append(int(st._it.iwork[13]))
    assert max(orders) == 2


def test_lu_count_is_reported():
    st = _stepper()
    st.restart(0.0, Y0)
    st.advance(0.3)
    assert st.nlu >= st.njev >= 1
