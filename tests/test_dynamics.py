"""The kernel's public face (snoworm.dynamics) and the kernel's one interface (issue 31, seam 1)."""

import ast
from pathlib import Path

import numpy as np
import pytest

import snoworm
from snoworm import dynamics
from snoworm.model import chain, floatkernel, inputs
from tests.conftest import SCENARIOS, model_for, random_state

PKG = Path(snoworm.__file__).parent


def test_the_public_face_names_the_kernel():
    assert dynamics.ChainModel is chain.ChainModel
    assert dynamics.Controls is inputs.Controls
    assert "m_k dv_k/dt" in dynamics.__doc__  # the equations are stated where users look


def test_kernel_inputs_are_every_attribute_but_the_caches():
    m = model_for(SCENARIOS / "tow6_uniform.yaml")
    ins = m.kernel_inputs()
    assert set(ins) == set(vars(m)) - chain.CACHES
    assert list(ins) == sorted(ins)
    assert "float_kernel" not in ins and "tow_force_N" in ins


def test_with_inputs_replaces_inputs_and_refuses_anything_else():
    m = model_for(SCENARIOS / "tow6_uniform.yaml")
    m2 = m.with_inputs({"tow_force_N": 500.0})
    assert m2.tow_force_N == 500.0 and m.tow_force_N != 500.0
    y, ctl = random_state(m, np.random.default_rng(1)), dynamics.Controls.rolling(m.n, np.ones(m.n), np.ones(m.n))
    assert not np.allclose(m2.evaluate(m2.unpack(y), ctl)[0], m.evaluate(m.unpack(y), ctl)[0])
    for bad in ({"no_such_attribute": 1.0}, {"float_kernel": None}):
        with pytest.raises(ValueError, match="not kernel inputs"):
            m.with_inputs(bad)


def test_no_module_reads_a_chain_models_private_attributes():
    """Outside snoworm/model/chain.py, no code reads ``<model>._name`` of a ChainModel (the float
    kernel walks ``kernel_inputs()`` instead): checked on the syntax trees of the package, for the
    attribute names a ChainModel sets."""
    m = model_for(SCENARIOS / "tow6_uniform.yaml")
    private = {k for k in vars(m) if k.startswith("_")}
    offenders = []
    for p in PKG.rglob("*.py"):
        if p == PKG / "model" / "chain.py":
            continue
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.Attribute) and node.attr in private:
                base = node.value
                if not (isinstance(base, ast.Name) and base.id in ("self", "cls")):
                    offenders.append(f"{p.relative_to(PKG)}:{node.lineno} .{node.attr}")
    assert not offenders, offenders
    assert floatkernel.model_parameters(m)  # the walk works through the interface
