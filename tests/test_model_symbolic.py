"""Symbolic floats and arrays (snoworm.model.symbolic): what the float kernel's trace records."""

import numpy as np
import pytest

from snoworm.model import symbolic
from snoworm.model.symbolic import SymArray, interp, symbols, tracing


def test_interp_is_numpys_interp():
    xp, fp = (0.0, 1.0, 2.5, 4.0), (0.9, 0.3, 0.3, 0.7)
    sl = tuple((fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j]) for j in range(3))
    for x in np.r_[np.linspace(-1, 5, 61), xp]:
        assert interp(float(x), xp, fp, sl) == pytest.approx(np.interp(x, xp, fp), rel=1e-15, abs=1e-15)


def test_operations_on_symbols_are_recorded_and_on_floats_computed():
    with tracing() as tr:
        y = symbols("y", (2,))
        out = np.maximum(y * np.array([2.0, 3.0]) + np.array([1.0, 1.0]) * 4.0, 0.5)
        t = np.tanh(y / 2.0)[0]
    src = [line for _, line, _ in tr.lines]
    assert isinstance(out, SymArray) and out.shape == (2,)
    assert "y0 * 2.0" in src[0] and "y1 * 3.0" in src[1]
    assert any(" + 4.0" in line for line in src)  # 1.0 * 4.0 folded to 4.0
    assert any(">= 0.5 else 0.5" in line for line in src)  # maximum: a conditional expression
    assert src[-1].startswith("_tanh(") and symbolic.source(t) == t.name
    assert symbolic._TRACE is None  # recording ends with the block


def test_a_branch_on_a_symbol_cannot_be_traced():
    with tracing():
        y = symbols("y", (3,))
        with pytest.raises(TypeError):
            if np.any(y > 0):
                pass
        with pytest.raises(TypeError):
            float(y[0] + 1.0)
