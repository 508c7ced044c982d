"""The force diagram of a force-control run (snoworm.plotting.diagram)."""

import dataclasses

import numpy as np
import pytest

from snoworm import load_scenario, simulate
from snoworm.plotting import diagram
from tests.conftest import SCENARIOS


@pytest.fixture(scope="module")
def uniform():
    return simulate(load_scenario(SCENARIOS / "tow6_uniform.yaml", ["simulation.duration_s=2"]))


def test_one_box_per_segment_with_its_wheel_force(uniform):
    fig = diagram.plot_force_diagram(uniform)
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert sum(t.startswith(("leader 0", "follower")) for t in texts) == uniform.n_segments
    assert sum("wheels" in t for t in texts) == uniform.n_segments


def test_force_diagram_never_prints_minus_zero(uniform):
    links = dict(uniform.links, force_N=np.full_like(uniform.links["force_N"], -1e-3))
    segments = dict(uniform.segments, net_force_N=np.full_like(uniform.segments["net_force_N"], -0.02))
    res = dataclasses.replace(uniform, links=links, segments=segments)
    fig = diagram.plot_force_diagram(res)
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert any("0.0 N" in t for t in texts)
    assert not [t for t in texts if "-0.0" in t or "\u22120.0" in t]
