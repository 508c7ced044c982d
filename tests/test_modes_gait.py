"""Gaits of the inchworm mode (snoworm.modes.gait, paper section 5.1): joint roles and gait checks."""

import numpy as np
import pytest

from snoworm.config.schema import ScenarioError
from snoworm.modes.gait import GAITS, gait_plan


def test_gait_validation():
    with pytest.raises(ScenarioError, match="jam"):
        gait_plan([[0], [0]], 2, ["prismatic"])
    with pytest.raises(ScenarioError, match="only extends"):
        gait_plan([[0]], 2, ["prismatic"])
    with pytest.raises(ScenarioError, match="every segment"):
        gait_plan([[0, 1]], 2, ["prismatic"])
    with pytest.raises(ScenarioError, match="must be 'prismatic'"):
        gait_plan([[1], [0]], 2, ["fixed"])
    with pytest.raises(ScenarioError, match="out of range"):
        gait_plan([[2], [0]], 2, ["prismatic"])
    # a 4-segment gait moving one segment at a time, rear to front, is valid
    plans = gait_plan([[3], [2], [1], [0]], 4, ["prismatic"] * 3)
    assert [list(p.role) for p in plans] == [[0, 0, -1], [0, -1, 1], [-1, 1, 0], [1, 0, 0]]


def test_shipped_gaits_alternate_every_joint_and_keep_anchors():
    """Fig 5's six-segment gait: each joint extends and contracts once per cycle, and each phase
    holds two segments for each moving one (the held clusters are the anchors)."""
    plans = gait_plan(GAITS["six_segment"], 6, ["prismatic"] * 5)
    roles = np.array([p.role for p in plans])  # (phase, joint)
    assert np.all((roles == 1).sum(0) == 1) and np.all((roles == -1).sum(0) == 1)
    assert [len(p.moving) for p in plans] == [2, 2, 2]
    assert all(sum(len(c) for c in p.clusters) == 4 for p in plans)
    two = gait_plan(GAITS["two_segment"], 2, ["prismatic"])
    assert [list(p.role) for p in two] == [[-1], [1]]  # pull the rear forward, then push the front
