"""Wilson intervals, percentiles and Sobol indices of the odds study (snoworm/studies/odds/stats.py)."""

import math

import numpy as np
import pytest
from scipy import stats as sps

from snoworm.studies.odds.inputs import Distribution, ScalarInput, Uncertainty
from snoworm.studies.odds.sampling import design
from snoworm.studies.odds.stats import draws_for_half_width, percentiles, sobol, wilson

Z95 = 1.959963984540054


@pytest.mark.parametrize("k,n", [(0, 10), (3, 10), (41, 100), (97, 100), (100, 100), (410, 1000)])
def test_wilson_inverts_the_score_test(k, n):
    """Each end p0 of Wilson's interval solves |k/n - p0| = z sqrt(p0 (1 - p0) / n) (the score test's
    boundary, an independent definition of the interval), and the interval holds k/n."""
    lo, hi = wilson(k, n)
    p = k / n
    for p0 in (lo, hi):
        if p0 in (0.0, 1.0) and p in (0.0, 1.0):
            continue  # the end at the boundary the estimate sits on
        assert abs(abs(p - p0) - Z95 * math.sqrt(p0 * (1 - p0) / n)) < 1e-9
    assert lo <= p <= hi
    assert 0.0 <= lo and hi <= 1.0


def test_wilson_of_no_draws_says_nothing_is_known():
    assert wilson(0, 0) == (0.0, 1.0)


def _exact_coverage(n, p):
    k = np.arange(n + 1)
    pmf = sps.binom.pmf(k, n, p)
    cover = np.array([wilson(int(j), n)[0] <= p <= wilson(int(j), n)[1] for j in k])
    return float(np.sum(pmf[cover]))


def test_wilson_covers_at_the_nominal_rate_in_simulation():
    """Seeded binomial draws: the fraction of intervals holding the true p agrees with the exact
    coverage (a sum over the binomial pmf) within 4 Monte Carlo standard errors, and the exact coverage
    averaged over p is the nominal 95 % within 1.5 points (Brown, Cai & DasGupta 2001, Fig. 5: Wilson's
    coverage oscillates about the nominal level)."""
    rng = np.random.default_rng(20261128)
    M = 4000
    exact_all = []
    for n in (20, 100, 400):
        for p in (0.05, 0.2, 0.5, 0.8):
            k = rng.binomial(n, p, size=M)
            ci = np.array([wilson(int(j), n) for j in k])
            sim = float(np.mean((ci[:, 0] <= p) & (p <= ci[:, 1])))
            exact = _exact_coverage(n, p)
            exact_all.append(exact)
            se = math.sqrt(exact * (1 - exact) / M)
            assert abs(sim - exact) < 4 * se, (n, p, sim, exact)
    assert abs(np.mean(exact_all) - 0.95) < 0.015


def test_draws_for_half_width_gives_the_promised_interval():
    """n = z^2 p (1 - p) / h^2 draws give a Wilson interval of half width about h at p."""
    for p, h in ((0.5, 0.03), (0.9, 0.02), (0.41, 0.05)):
        n = draws_for_half_width(p, h)
        lo, hi = wilson(round(p * n), n)
        assert abs((hi - lo) / 2 - h) < 0.1 * h


def test_percentiles_skip_missing_values():
    v = [None, 1.0, 2.0, 3.0, float("nan"), 4.0, 5.0]
    assert percentiles(v) == {
        "p5": np.percentile([1, 2, 3, 4, 5], 5),
        "p50": 3.0,
        "p95": np.percentile([1, 2, 3, 4, 5], 95),
    }
    assert percentiles([None]) is None


def _ishigami_indices(a=7.0, b=0.1):
    """Known Sobol indices of Ishigami's function (Ishigami & Homma 1990; Sobol' & Levitan 1999)."""
    pi4, pi8 = math.pi**4, math.pi**8
    V1 = 0.5 * (1 + b * pi4 / 5) ** 2
    V2 = a * a / 8
    V13 = b * b * pi8 * (1 / 18 - 1 / 50)
    V = V1 + V2 + V13
    return {"x1": (V1 / V, (V1 + V13) / V), "x2": (V2 / V, V2 / V), "x3": (0.0, V13 / V)}


def test_sobol_reproduces_ishigami_within_the_bootstrap_intervals():
    """Saltelli's design of the odds study (three uniform inputs on [-pi, pi], scrambled Sobol' points) and
    scipy's estimators: every known first-order and total index lies in its bootstrap interval."""
    u = Distribution("uniform", (-math.pi, math.pi))
    unc = Uncertainty(tuple(ScalarInput(n, u) for n in ("x1", "x2", "x3")))
    dsg = design(unc, 1024, "sobol", 7, sensitivity=True)
    v = unc.values(dsg.U)
    x1, x2, x3 = v["x1"], v["x2"], v["x3"]
    f = np.sin(x1) + 7 * np.sin(x2) ** 2 + 0.1 * x3**4 * np.sin(x1)
    res = sobol(f, dsg, seed=3)
    for name, (first, total) in _ishigami_indices().items():
        r = res[name]
        assert r["first_ci"][0] <= first <= r["first_ci"][1], (name, r, first)
        assert r["total_ci"][0] <= total <= r["total_ci"][1], (name, r, total)
        assert r["first_ci"][1] - r["first_ci"][0] < 0.2  # informative, not a [-inf, inf] interval


def test_sobol_of_a_constant_output_is_zero():
    u = Distribution("uniform", (0, 1))
    unc = Uncertainty((ScalarInput("a", u), ScalarInput("b", u)))
    dsg = design(unc, 32, "random", 0, sensitivity=True)
    res = sobol(np.ones(dsg.n_draws), dsg)
    assert all(r["first"] == 0 and r["total"] == 0 for r in res.values())


def test_sobol_intervals_are_the_same_for_the_same_study():
    """The bootstrap is seeded: the same outputs give the same intervals, whatever the global random state
    (scipy's own SobolResult.bootstrap draws from fresh entropy every time)."""
    u = Distribution("uniform", (0.0, 1.0))
    unc = Uncertainty((ScalarInput("a", u), ScalarInput("b", u)))
    dsg = design(unc, 64, "random", 0, sensitivity=True)
    v = unc.values(dsg.U)
    f = (v["a"] + 0.5 * v["b"] > 0.8).astype(float)
    first = sobol(f, dsg)
    np.random.seed(5)
    assert sobol(f, dsg) == first


def test_the_bootstrap_statistic_is_scipys_estimator():
    """_indices on the whole design gives scipy.stats.sobol_indices's point estimates (so the intervals are
    those of the same estimators)."""
    from scipy.stats import sobol_indices

    from snoworm.studies.odds.stats import _indices

    u = Distribution("uniform", (-math.pi, math.pi))
    unc = Uncertainty(tuple(ScalarInput(n, u) for n in ("x1", "x2", "x3")))
    dsg = design(unc, 256, "random", 2, sensitivity=True)
    v = unc.values(dsg.U)
    f = np.sin(v["x1"]) + 7 * np.sin(v["x2"]) ** 2 + 0.1 * v["x3"] ** 4 * np.sin(v["x1"])
    fA, fB = f[dsg.block("A")], f[dsg.block("B")]
    fAB = np.stack([f[dsg.block(f"AB:{g}")] for g in dsg.groups])
    ref = sobol_indices(func={"f_A": fA[None], "f_B": fB[None], "f_AB": fAB[:, None]}, n=256)
    first, total = _indices(fA, fB, fAB)
    assert np.allclose(first, ref.first_order, rtol=1e-12, atol=1e-14)
    assert np.allclose(total, ref.total_order, rtol=1e-12, atol=1e-14)


def test_wilson_ends_are_exact_at_zero_and_all():
    """With every draw a success (or none) the interval ends exactly at 1 (or 0): the summary printed
    "99-100.0 %" when rounding left 1 - 1e-16."""
    for n in (7, 60, 1024):
        assert wilson(n, n)[1] == 1.0 and wilson(0, n)[0] == 0.0
