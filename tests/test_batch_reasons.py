"""solve_batch's reasons speak solve's words: a target proven out of reach is "unreachable"
in both (it was "local_minima" in the batch)."""

from __future__ import annotations

import numpy as np

import swarm_ik
from swarm_ik.goals import AvoidCollisions, JointValue, Pose
from swarm_ik.scene import Box, Scene


def _targets(robot: swarm_ik.RobotModel, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.stack([robot.fk(q) for q in robot.random_q(rng, n)])


def test_a_target_beyond_reach_is_unreachable_as_in_solve() -> None:
    robot = swarm_ik.load_robot("panda")
    t = _targets(robot, 4, 3)
    far = t[1].copy()
    far[:3, 3] *= 3.0 * robot.reach_radius() / np.linalg.norm(far[:3, 3])
    res = swarm_ik.solve_batch(robot, np.stack([t[0], far, t[2]]), max_starts=4)
    assert res.reason.tolist() == ["converged", "unreachable", "converged"]
    assert res.unreachable is not None and res.unreachable.tolist() == [False, True, False]
    single = swarm_ik.solve(swarm_ik.IKProblem(robot, far), max_evals=200)
    assert single.reason == "unreachable"


def test_a_missed_reachable_target_is_not_called_unreachable() -> None:
    """A target within reach that one start of two evaluations (the least a start takes)
    does not meet is missed, never called "unreachable"."""
    robot = swarm_ik.load_robot("panda")
    t = _targets(robot, 3, 4)
    res = swarm_ik.solve_batch(robot, t, max_starts=1, max_iters=2)
    assert not res.success.any()
    assert not res.unreachable.any()
    assert "unreachable" not in res.reason.tolist()


def test_position_only_points_beyond_reach() -> None:
    robot = swarm_ik.load_robot("ur5")
    r = robot.reach_radius()
    points = np.array([[0.3, 0.2, 0.4], [r * 1.01, 0.0, 0.0], [1e300, 1e300, 0.0]])
    res = swarm_ik.solve_batch(robot, points, position_only=True, max_starts=4)
    assert res.reason.tolist() == ["converged", "unreachable", "unreachable"]


def test_a_goal_no_joint_vector_meets_makes_every_target_unreachable() -> None:
    robot = swarm_ik.load_robot("panda")
    t = _targets(robot, 3, 5)
    beyond = JointValue(robot.joint_names[0], float(robot.upper[0]) + 1.0)
    res = swarm_ik.solve_batch(robot, t, goals=[beyond], max_starts=2)
    assert res.reason.tolist() == ["unreachable"] * 3
    ee = robot.ee_frame
    alone = swarm_ik.solve(swarm_ik.IKProblem(robot, goals=[Pose(ee, t[0]), beyond]))
    assert alone.reason == "unreachable"


def test_a_target_point_inside_an_obstacle_is_unreachable_as_in_solve() -> None:
    robot = swarm_ik.load_robot("panda")
    t = _targets(robot, 6, 6)
    # a box around one target's point, far from the others and from the base
    inside = next(x for x in t if np.linalg.norm(x[:3, 3]) > 0.45)
    others = [x for x in t if np.linalg.norm(x[:3, 3] - inside[:3, 3]) > 0.5][:2]
    scene = Scene([Box((0.12, 0.12, 0.12), tuple(inside[:3, 3]))])
    avoid = AvoidCollisions(scene)
    res = swarm_ik.solve_batch(robot, np.stack([*others, inside]), goals=[avoid], max_starts=8)
    assert res.reason[-1] == "unreachable"
    assert res.unreachable.tolist()[-1]
    assert "unreachable" not in res.reason[:-1].tolist()
    single = swarm_ik.solve(
        swarm_ik.IKProblem(robot, goals=[Pose(robot.ee_frame, inside), avoid]), max_evals=300
    )
    assert single.reason == "unreachable"


def test_coal_probes_stop_at_the_deadline_and_the_reach_test_does_not() -> None:
    """Under a batch's time limit the obstacle probes (13 µs each) end at the limit: a point
    not probed by then is not called unreachable; points beyond reach are judged at once."""
    from swarm_ik.api import unreachable_targets

    robot = swarm_ik.load_robot("panda")
    t = _targets(robot, 6, 6)
    inside = next(x for x in t if np.linalg.norm(x[:3, 3]) > 0.45)
    scene = Scene([Box((0.12, 0.12, 0.12), tuple(inside[:3, 3]))])
    problem = swarm_ik.IKProblem(
        robot, goals=[Pose(robot.ee_frame, inside), AvoidCollisions(scene)]
    )
    points = np.stack([inside[:3, 3], [5.0, 0.0, 0.0]])
    assert unreachable_targets(problem, points).tolist() == [True, True]
    assert unreachable_targets(problem, points, deadline=0.0).tolist() == [False, True]
