"""Held-out review 129 (the model layer against Pinocchio): what it found, pinned as
behaviour."""

from __future__ import annotations

import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import swarm_ik
from swarm_ik.kernels import lie


def _series(t: float, first: int) -> float:
    """``Σ_k (−1)^k t^{2k} / (2k + first)!`` in exact rational arithmetic (40 terms: beyond
    round-off for |t| ≤ 3), rounded once."""
    x = Fraction(t) ** 2
    return float(sum((-1) ** k * x**k / math.factorial(2 * k + first) for k in range(40)))


@pytest.mark.parametrize("t", [1e-9, 3e-5, 1e-4, 1.124e-4, 1e-3, 0.05, 0.31, 0.32, 1.0, 3.0])
def test_the_coefficients_of_exp_and_its_jacobian_are_accurate_to_round_off(t: float) -> None:
    """``(1 − cos θ)/θ²`` and ``(θ − sin θ)/θ³`` as quotients lost up to 6ε/θ² of their
    value just above the Taylor switch (θ = 1e-4): 2.4e-12 m/rad of a 5.6 m floating-base
    Jacobian against Pinocchio's, where 1e-12 is promised."""
    a, b, c = lie.exp3_coeffs(t, 0.0, 0.0)
    assert a == pytest.approx(_series(t, 1), rel=0, abs=4e-16)
    assert b == pytest.approx(_series(t, 2), rel=0, abs=4e-16)
    assert c == pytest.approx(_series(t, 3), rel=0, abs=4e-16)


MIMIC_OFF_PATH = """<?xml version="1.0"?>
<robot name="offpath">
  <link name="base"/>
  <link name="l1"><inertial><mass value="1"/><origin xyz="0.2 0 0"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip"/>
  <link name="wheel"><inertial><mass value="1"/><origin xyz="0 0.1 0"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="flap"><inertial><mass value="2"/><origin xyz="0.3 0 0"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="jt" type="fixed"><parent link="l1"/><child link="tip"/>
    <origin xyz="0.4 0 0"/></joint>
  <joint name="wheelj" type="continuous"><parent link="base"/><child link="wheel"/>
    <origin xyz="0 0.3 0"/><axis xyz="0 0 1"/></joint>
  <joint name="flapj" type="continuous"><parent link="wheel"/><child link="flap"/>
    <origin xyz="0 0.2 0"/><axis xyz="0 0 1"/><mimic joint="wheelj" offset="1.2"/></joint>
</robot>
"""


def test_an_off_path_mimic_follower_of_a_continuous_joint_follows_its_rule(
    tmp_path: Path,
) -> None:
    """Off-path followers were held at their rule's value only between one-number joints: a
    continuous follower of a continuous driver stayed at 0 where its rule (offset 1.2) said
    1.2, and the centre of mass, which counts every link, was 0.19 m off Pinocchio's."""
    from swarm_ik.goals import CenterOfMass

    path = tmp_path / "offpath.urdf"
    path.write_text(MIMIC_OFF_PATH)
    robot = swarm_ik.load_robot(path, ["tip"])
    assert robot.joint_names == ("j1",)
    full = pin.buildModelFromUrdf(str(path))
    data = full.createData()
    q = pin.neutral(full)
    q[full.joints[full.getJointId("j1")].idx_q] = 0.7
    i = full.joints[full.getJointId("flapj")].idx_q
    q[i : i + 2] = (math.cos(1.2), math.sin(1.2))  # (the rule: wheelj at 0, plus 1.2)
    expected = pin.centerOfMass(full, data, q)
    got = CenterOfMass(point=[0.0, 0.0, 0.0]).center(robot, np.array([0.7]))
    np.testing.assert_allclose(got, expected, atol=1e-12)


def test_elbow_mirrors_of_several_threads_are_each_their_own() -> None:
    """``solve_many``'s elbow mirrors of a robot came from one Pinocchio ``Data`` shared by
    every thread: one thread read the frames another had just computed, and a threaded call
    differed from the same call made alone (review 132).  Threads switching as often as
    possible, each mirror is the serial one."""
    import sys
    import threading

    from swarm_ik import many

    robot = swarm_ik.load_robot("ur5")
    hops = many._hops_for(robot)
    assert hops is not None
    qs = robot.random_q(np.random.default_rng(0), 64)
    serial = [[m.copy() for m in hops.elbow(q)] for q in qs]
    assert any(serial)
    wrong: list[int] = []

    def work(offset: int) -> None:
        for k in range(400):
            i = (k + offset) % len(qs)
            got = hops.elbow(qs[i])
            if len(got) != len(serial[i]) or any(
                not np.array_equal(a, b) for a, b in zip(got, serial[i], strict=True)
            ):
                wrong.append(i)

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        threads = [threading.Thread(target=work, args=(7 * t,)) for t in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(timeout=120)
    finally:
        sys.setswitchinterval(interval)
    assert not wrong, f"{len(wrong)} mirrors read another thread's frames"


def test_a_robot_that_is_a_floating_base_alone_gets_its_paths_and_solutions() -> None:
    """``solve_path`` and ``solve_many`` of a drone (a free flyer, no joint) crashed with a
    bare IndexError in the elbow mirrors, which read past its one joint's frames; the command
    line said "internal error" (review 131)."""
    robot = swarm_ik.load_robot("quadrotor_base", floating_base=True)
    start = robot.fk(robot.mid_q())
    poses = np.repeat(start[None], 2, axis=0)
    poses[1, :3, 3] += [0.05, 0.0, 0.0]
    res = swarm_ik.solve_path(robot, poses)
    assert res.success and res.status == "converged"
    for q, pose in zip(res.q, poses, strict=True):
        np.testing.assert_allclose(robot.fk_pinocchio(q), pose, atol=1e-5)
    many = swarm_ik.solve_many(swarm_ik.IKProblem(robot, poses[1]), n=2)
    assert len(many) >= 1 and all(r.success for r in many)
