"""The draws of an odds study (snoworm/studies/odds/sampling.py): reproducible, stratified, Saltelli's blocks."""

import numpy as np
import pytest

from snoworm.config.schema import ScenarioError
from snoworm.studies.odds.inputs import Distribution, ScalarInput, Uncertainty, XtField
from snoworm.studies.odds.sampling import design, field_seed, uniforms

U01 = Distribution("uniform", (0.0, 1.0))


def _unc(k=2, field=False):
    return Uncertainty(tuple(ScalarInput(f"p{j}", U01) for j in range(k)), XtField(0.05, 5.0) if field else None)


@pytest.mark.parametrize("method", ["random", "sobol", "lhs"])
def test_same_seed_same_draws_other_seed_other_draws(method):
    a, b, c = uniforms(method, 64, 3, 5), uniforms(method, 64, 3, 5), uniforms(method, 64, 3, 6)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    assert a.shape == (64, 3) and a.min() >= 0 and a.max() < 1


def test_latin_hypercube_has_one_point_per_stratum():
    n = 50
    u = uniforms("lhs", n, 4, 0)
    for j in range(4):
        assert sorted(np.floor(u[:, j] * n).astype(int)) == list(range(n))


def test_sobol_points_fill_the_square_better_than_random():
    """The star discrepancy of 256 scrambled Sobol' points is below that of 256 random points."""
    from scipy.stats import qmc

    assert qmc.discrepancy(uniforms("sobol", 256, 2, 0)) < qmc.discrepancy(uniforms("random", 256, 2, 0))


def test_field_seeds_depend_on_the_seed_and_draw_only():
    assert field_seed(3, 7) == field_seed(3, 7)
    assert len({field_seed(3, k) for k in range(100)}) == 100
    d1, d2 = design(_unc(1, True), 10, "random", 3), design(_unc(1, True), 20, "random", 3)
    assert np.array_equal(d1.field_seeds, d2.field_seeds[:10])  # more draws keep the first ones' fields


def test_saltelli_blocks():
    """AB_i is A with group i's coordinates (and the field seed, for the field) taken from B."""
    unc = _unc(2, True)
    d = design(unc, 16, "sobol", 1, sensitivity=True)
    assert d.n_draws == 16 * (3 + 2) and d.groups == ("p0", "p1", "xt_field")
    A, B = d.U[d.block("A")], d.U[d.block("B")]
    for j, g in enumerate(("p0", "p1")):
        M = d.U[d.block(f"AB:{g}")]
        assert np.array_equal(M[:, j], B[:, j])
        assert np.array_equal(np.delete(M, j, axis=1), np.delete(A, j, axis=1))
        assert np.array_equal(d.field_seeds[d.block(f"AB:{g}")], d.field_seeds[d.block("A")])
    assert np.array_equal(d.U[d.block("AB:xt_field")], A)
    assert np.array_equal(d.field_seeds[d.block("AB:xt_field")], d.field_seeds[d.block("B")])
    assert d.independent.sum() == 32


def test_sensitivity_needs_two_inputs():
    with pytest.raises(ScenarioError, match="at least two uncertain inputs"):
        design(_unc(1), 16, "random", 0, sensitivity=True)
    with pytest.raises(ScenarioError, match="--method"):
        uniforms("halton", 4, 1, 0)


def test_sobol_points_come_in_powers_of_two():
    """scipy only warns that n Sobol' points lose their balance unless n is a power of 2; odds refuses,
    naming the two nearest counts."""
    with pytest.raises(ScenarioError, match="--samples 100 with --method sobol.*--samples 64 or 128"):
        uniforms("sobol", 100, 2, 0)
    assert uniforms("sobol", 128, 2, 0).shape == (128, 2)
