"""solve_path with a scene: waypoints blocked by obstacles, their reason, and the time limit of
a path whose scene is loaded by the call (swarm_ik.path)."""

from __future__ import annotations

import time

import numpy as np
import pytest
from conftest import robot as get
from conftest import timed

import swarm_ik
from swarm_ik.path import PathResult, solve_path
from swarm_ik.scene import Box, Scene, Sphere


def _ur5_line() -> tuple[np.ndarray, Scene]:
    """A UR5 line of 30 waypoints and a 5 cm ball around waypoint 10's tool point: waypoints
    1–18 have closed-form branches within the limits, every one of them in collision."""
    robot = get("ur5")
    start = robot.fk(np.array([0.3, -1.2, 1.4, -1.8, -1.57, 0.0]))
    poses = np.repeat(start[None], 30, axis=0)
    poses[:, :3, 3] += np.linspace(0, 1, 30)[:, None] * [-0.1, 0.25, 0.05]
    return poses, Scene([Sphere(0.05, tuple(poses[10, :3, 3]), name="ball")])


@pytest.fixture(scope="module")
def blocked() -> tuple[np.ndarray, Scene, PathResult]:
    poses, scene = _ur5_line()
    return poses, scene, solve_path(get("ur5"), poses, max_joint_step=0.2, scene=scene)


def test_stand_ins_hold_still_across_waypoints_blocked_by_an_obstacle(blocked) -> None:
    """The configurations of the waypoint before an unreached one stand in for it whatever
    made that layer (here certified closed-form sets, emptied by the collision check): the
    path holds still across the blocked stretch and jumps once, on leaving it (before: only
    the failed attempts stood in, 17 jumps of 3–9.4 rad between consecutive stand-ins)."""
    _, _, res = blocked
    unreached = np.flatnonzero(~res.reached)
    np.testing.assert_array_equal(unreached, np.arange(1, 19))
    assert len(res.reconfigurations) <= 2, res.reconfigurations
    for i in unreached[1:]:
        np.testing.assert_array_equal(res.q[i], res.q[i - 1])
    np.testing.assert_array_equal(res.q[1], res.q[0])  # (entering it: staying put)


def test_densify_does_not_call_holding_still_a_jump() -> None:
    """With ``densify``, a step that stays put at a waypoint nothing meets is no motion: it is
    not tracked through the (unreachable) interpolated poses, whose failure counted as a jump
    of 12–24 rad for each held step (19 jumps where the path moves once)."""
    robot = get("ur5")
    poses, scene = _ur5_line()
    res = solve_path(robot, poses, max_joint_step=0.2, scene=scene, densify=2)
    assert [i for i, _ in res.reconfigurations] == [19], res.reason
    assert res.q_dense is not None
    held = res.q_dense[0 : 18 * 3 + 1]  # (waypoint 0 to waypoint 18, three rows a step)
    np.testing.assert_array_equal(held, np.broadcast_to(res.q[0], held.shape))


def test_blocked_waypoints_are_called_collision_blocked_with_a_proof(blocked) -> None:
    """The reason names the collisions (not 'none meets it within the joint limits', false:
    waypoint 10 has 6 branches within the limits) and the obstacle holding the target point;
    ``exhaustive`` stays True as the pose's set was certified complete before the collision
    check filtered it, which the reason words as a proof, checked here independently."""
    poses, scene, res = blocked
    robot = get("ur5")
    assert "unreachable: no collision-free IK solution" in res.reason, res.reason
    assert "none meets it within the joint limits" not in res.reason
    assert "each set complete: a proof" in res.reason
    assert "lies inside obstacle 'ball'" in res.reason
    assert res.exhaustive
    branches = swarm_ik.solve_many(swarm_ik.IKProblem(robot, poses[10]), n=16)
    assert len(branches) >= 1
    rc = robot.collision_model()
    for b in branches:
        assert robot.within_limits(b.q) and rc.collides(b.q, scene)


def test_waypoints_beyond_reach_still_hold_still() -> None:
    """Waypoints out of reach (no closed-form branch): held too, no jump, the reason as
    before."""
    robot = get("ur5")
    poses, _ = _ur5_line()
    poses[8:13, 0, 3] += 2.0
    res = solve_path(robot, poses, max_joint_step=0.2)
    np.testing.assert_array_equal(np.flatnonzero(~res.reached), np.arange(8, 13))
    assert res.jump_free, res.reason
    assert "beyond the frame's reach" in res.reason and "collision" not in res.reason


def _panda_line() -> tuple[swarm_ik.RobotModel, np.ndarray]:
    robot = swarm_ik.load_robot("panda")  # (a fresh instance: nothing of it loaded yet)
    start = robot.fk(robot.mid_q())
    poses = np.repeat(start[None], 20, axis=0)
    poses[:, :3, 3] += np.linspace(0, 1, 20)[:, None] * [0, 0.1, 0]
    return robot, poses


def _box(poses: np.ndarray, dz: float) -> Scene:
    return Scene([Box((0.05, 0.05, 0.05), tuple(poses[0, :3, 3] + [0.1, 0.2, dz]), name="b")])


@timed()
def test_time_s_of_a_first_timed_path_with_a_scene_is_its_wall_time() -> None:
    """A robot's first timed path, with a scene: its kernels, the scene's sphere model (the
    robot's self-collision pairs sampled) and coal's checker are loaded before the clock and
    charged to the limit up to half of it, and ``time_s`` counts them (it said 0.013 s of a
    0.44 s call)."""
    robot, poses = _panda_line()
    swarm_ik.solve(swarm_ik.IKProblem(robot, poses[0]), time_limit=0.5)
    robot.collision_model()
    t0 = time.perf_counter()
    res = solve_path(robot, poses, time_limit=0.02, scene=_box(poses, -0.2))
    wall = time.perf_counter() - t0
    assert res.time_s == pytest.approx(wall, abs=5e-3), (res.time_s, wall)
    assert res.reached[0]


@timed()
def test_a_new_scene_is_loaded_before_the_clock() -> None:
    """The robot's path kernels loaded, then a path with its first scene: the sphere model
    (0.2–0.6 s) is made before the clock and charged up to half the limit, so the path gets
    the other half (before, the loading used the whole limit: only waypoint 0 was solved);
    a second scene keeps the limit."""
    robot, poses = _panda_line()
    solve_path(robot, poses[:3], time_limit=1.0)  # (the robot's kernels: the first timed path)
    res = solve_path(robot, poses, time_limit=0.1, scene=_box(poses, -0.2))
    assert int(res.reached.sum()) >= 3, res.reason
    t0 = time.perf_counter()
    res = solve_path(robot, poses, time_limit=0.05, scene=_box(poses, -0.21))
    wall = time.perf_counter() - t0
    assert wall < 0.05 + 0.03 and res.time_s == pytest.approx(wall, abs=5e-3)


def test_branches_rejected_by_other_goals_are_named_with_them() -> None:
    """Closed-form branches within the limits that a goal added at every waypoint rejects (a
    tool position 1 m off the poses): the reason names that goal, not 'none meets it within
    the joint limits' (the pose alone has its branches), and the complete sets make it a
    proof."""
    from swarm_ik.goals import Position

    robot = get("ur5")
    poses, _ = _ur5_line()
    res = solve_path(robot, poses[:4], goals=[Position("tool0", [0.0, 0.0, 0.3])])
    assert not res.reached.any()
    assert "no IK solution meeting Position(tool0)" in res.reason, res.reason
    assert "fails it; each set complete: a proof" in res.reason
    assert "none meets it within the joint limits" not in res.reason
    assert res.exhaustive


@timed()
def test_a_path_among_obstacles_ends_within_its_time_limit() -> None:
    """The check at the end verifies each waypoint with coal (with distances where one is left
    in contact): 15-32 ms for 60 waypoints, kept out of the limit at 20 µs a waypoint, so a
    50 ms limit took 80 ms."""
    import time

    from swarm_ik.path import solve_path
    from swarm_ik.scene import Box, Scene, Sphere

    r = swarm_ik.load_robot("panda")
    t = r.fk(r.mid_q())
    poses = np.repeat(t[None], 60, 0)
    poses[:, :3, 3] += np.linspace(0, 1, 60)[:, None] * [0.6, -0.5, 0.3]
    scene = Scene([Box([0.3] * 3, [0.5, 0.3, 0.3]), Sphere(0.1, t[:3, 3] + [0.1, -0.1, 0.05])])
    solve_path(r, poses[:2], time_limit=10, scene=scene)  # (the scene and kernels loaded)
    for limit in (0.05, 0.1):
        t0 = time.perf_counter()
        solve_path(r, poses, time_limit=limit, scene=scene)
        assert time.perf_counter() - t0 <= limit + 0.01
