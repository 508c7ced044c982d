"""Shared test helpers."""
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"


@pytest.fixture
def scenario_path():
    """Path of a shipped scenario by name."""
    return lambda name: SCENARIOS / f"{name}.yaml"
