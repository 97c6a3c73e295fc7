"""Shared fixtures: robots are loaded once per session (loading parses URDFs)."""

from __future__ import annotations

import os

import numpy as np
import pytest

os.environ.setdefault("SWARM_IK_QUICK", "1")  # examples and benchmarks run short in tests
os.environ.setdefault("MPLBACKEND", "Agg")

try:  # keep property-based tests bounded on CI's 2 cores
    from hypothesis import settings

    settings.register_profile("ci", max_examples=15, deadline=None)
    settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))
except ImportError:  # pragma: no cover
    pass

import swarm_ik

_CACHE: dict[str, swarm_ik.RobotModel] = {}


def robot(name: str) -> swarm_ik.RobotModel:
    """A robot loaded once per test session."""
    if name not in _CACHE:
        _CACHE[name] = swarm_ik.load_robot(name)
    return _CACHE[name]


@pytest.fixture(scope="session")
def get_robot():
    """Fixture giving the cached loader ``get_robot(name)``."""
    return robot


@pytest.fixture(scope="session")
def planar2_urdf(tmp_path_factory) -> str:
    """A 2-link planar arm (links 1 m and 0.8 m, joints about z) as a URDF file."""
    text = """<?xml version="1.0"?>
<robot name="planar2">
  <link name="base"/>
  <link name="l1"/>
  <link name="l2"/>
  <link name="tip"/>
  <joint name="j1" type="revolute">
    <parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.1" upper="3.1" effort="1" velocity="1"/>
  </joint>
  <joint name="j2" type="revolute">
    <parent link="l1"/><child link="l2"/>
    <origin xyz="1 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3.1" upper="3.1" effort="1" velocity="1"/>
  </joint>
  <joint name="tool" type="fixed">
    <parent link="l2"/><child link="tip"/><origin xyz="0.8 0 0" rpy="0 0 0"/>
  </joint>
</robot>
"""
    path = tmp_path_factory.mktemp("planar") / "planar2.urdf"
    path.write_text(text)
    return str(path)


@pytest.fixture()
def rng() -> np.random.Generator:
    """A fresh seeded generator."""
    return np.random.default_rng(12345)
