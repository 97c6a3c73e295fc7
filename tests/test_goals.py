"""Goal terms: Jacobians against finite differences, numpy twins against the kernel, each goal
solved on reachable targets, secondary goals never costing primary accuracy, bad input."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from conftest import robot

import swarm_ik
from swarm_ik import goals as G
from swarm_ik.solvers.hybrid import Polisher


def _goal_set(r: swarm_ik.RobotModel, q: np.ndarray) -> list[G.Goal]:
    """One goal of every frame type on the first frame, derived from FK(q) (reachable)."""
    f = r.ee_frame
    pose = r.fk(q)
    rng = np.random.default_rng(0)
    return [
        G.Pose(f, pose),
        G.Position(f, pose[:3, 3]),
        G.Orientation(f, pose[:3, :3]),
        G.Axis(f, [0, 0, 1], pose[:3, 2]),
        G.LookAt(f, [0, 0, 1], pose[:3, 3] + 0.7 * pose[:3, 2]),
        G.Posture(r.random_q(rng), primary=True),
        G.JointValue(r.joint_names[1], float(q[1])),
        G.CenterJoints(primary=True),
        G.MinimalDisplacement(primary=True),
    ]


CHECKED_ELSEWHERE = {
    G.CenterOfMass: "test_center_of_mass.py (against Pinocchio and finite differences)",
    G.AvoidCollisions: "test_avoid_collisions.py (central differences of the sphere rows)",
}
"""Compiled goals whose kernels other files hold to their numpy twins and derivatives."""


def test_every_registered_compiled_goal_has_its_kernel_checked() -> None:
    """A built-in compiled goal's kernel is trusted (the twin check at problem creation runs
    for users' goals only): each registered one is in :func:`_goal_set`, whose kernels the
    tests here hold to their numpy twins and to central differences, or is checked in a file
    of its own.  A new built-in goal missing from both fails here."""
    r = robot("panda")
    covered = {type(g) for g in _goal_set(r, r.mid_q())} | set(CHECKED_ELSEWHERE)
    compiled = {cls for cls in G.GOALS.values() if getattr(cls, "kernel", None) is not None}
    assert not compiled - covered, sorted(c.__name__ for c in compiled - covered)


@pytest.mark.parametrize("name", ["panda", "kinova", "loading_manipulator_long"])
def test_every_goal_jacobian_matches_central_differences(name: str) -> None:
    r = robot(name)
    rng = np.random.default_rng(1)
    h = 1e-6
    for _ in range(3):
        q_t, q = r.random_q(rng), r.random_q(rng)
        for goal in _goal_set(r, q_t):
            prob = swarm_ik.IKProblem(r, goals=[goal])
            pol = Polisher.from_problem(prob)
            res, jac, _dp, dr = pol.residual(q)
            if dr > 2.5 and isinstance(goal, (G.Pose, G.Orientation)):
                continue  # log3's branch cut at π
            for j in range(r.nq):
                e = np.zeros(r.nq)
                e[j] = h
                rp = pol.residual(q + e)[0]
                rm = pol.residual(q - e)[0]
                np.testing.assert_allclose(
                    -(rp - rm) / (2 * h), jac[:, j], atol=3e-7, err_msg=goal.describe()
                )


@pytest.mark.parametrize("name", ["panda", "baxter"])
def test_numpy_twin_equals_the_compiled_residual(name: str) -> None:
    r = robot(name)
    rng = np.random.default_rng(2)
    q_t, q = r.random_q(rng), r.random_q(rng)
    state = G.State(r, q)
    for goal in _goal_set(r, q_t):
        prob = swarm_ik.IKProblem(r, goals=[goal])
        res, jac, _, _ = Polisher.from_problem(prob).residual(q)
        # the numpy residual on Pinocchio's state; the kernel's step Jacobian is −∂r/∂q
        r_np, j_np = goal.residual(state), goal.jacobian(state)
        np.testing.assert_allclose(r_np, res, atol=1e-12, err_msg=goal.describe())
        np.testing.assert_allclose(-j_np, jac, atol=1e-12, err_msg=goal.describe())
        # and the errors the kernel judges equal those of the Pinocchio check
        err = prob.goal_errors(q)[0, 0]
        check = prob.verify(q)[0]
        np.testing.assert_allclose(
            [check.position_error, check.rotation_error], err, atol=1e-10, equal_nan=True
        )


@pytest.mark.parametrize("name", ["panda", "ur5", "xarm7"])
def test_each_frame_goal_is_solved_on_reachable_targets(name: str) -> None:
    r = robot(name)
    rng = np.random.default_rng(3)
    for k in range(4):
        q_t = r.random_q(rng)
        pose = r.fk(q_t)
        f = r.ee_frame
        for goal in [
            G.Position(f, pose[:3, 3]),
            G.Orientation(f, pose[:3, :3]),
            G.Axis(f, [0, 0, 1], pose[:3, 2]),
            G.LookAt(f, [0, 0, 1], pose[:3, 3] + 0.5 * pose[:3, 2]),
        ]:
            res = swarm_ik.solve(swarm_ik.IKProblem(r, goals=[goal]), seed=k, time_limit=0.5)
            assert res.success, (goal.describe(), res)
            assert res.within_limits and len(res.goal_errors) == 1


def test_axis_goal_leaves_the_rotation_about_it_free() -> None:
    r = robot("panda")
    f = r.ee_frame
    # a reachable position with the tool pointing down: the "ready" posture (tool down
    # within 0.1 rad) turned about the base
    q_t = np.array([0.7, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785])
    p = r.fk(q_t)[:3, 3]
    down = G.Axis(f, [0, 0, 1], [0, 0, -1])
    prob = swarm_ik.IKProblem(r, goals=[G.Position(f, p), down])
    res = swarm_ik.solve(prob, seed=0, time_limit=0.5)
    assert res.success
    pose = r.fk_pinocchio(res.q)
    np.testing.assert_allclose(pose[:3, 2], [0, 0, -1], atol=2e-5)
    np.testing.assert_allclose(pose[:3, 3], p, atol=1e-5)


def test_two_arm_pose_goals_on_baxter() -> None:
    r = robot("baxter")
    rng = np.random.default_rng(5)
    for k in range(5):
        left, right = r.fk_all(r.random_q(rng))
        prob = swarm_ik.IKProblem(
            r, goals=[G.Pose("left_gripper", left), G.Pose("right_gripper", right)]
        )
        res = swarm_ik.solve(prob, seed=k, time_limit=0.5)
        assert res.success and res.reason == "converged"
        assert [e.goal for e in res.goal_errors] == ["Pose(left_gripper)", "Pose(right_gripper)"]
        assert all(e.position_error <= 1e-5 and e.rotation_error <= 1e-5 for e in res.goal_errors)


def test_joint_value_and_a_pose_together() -> None:
    r = robot("panda")
    q_t = r.random_q(np.random.default_rng(6))
    prob = swarm_ik.IKProblem(r, r.fk(q_t), goals=[G.JointValue(r.joint_names[2], float(q_t[2]))])
    res = swarm_ik.solve(prob, seed=0, time_limit=0.5)
    assert res.success and abs(res.q[2] - q_t[2]) <= 1e-5


def test_secondary_posture_moves_the_answer_closer_without_costing_accuracy() -> None:
    r = robot("panda")
    rng = np.random.default_rng(7)
    closer = 0
    for k in range(10):
        q_t = r.random_q(rng)
        q_ref = np.clip(q_t + rng.normal(0, 0.4, r.nq), r.lower, r.upper)
        target = r.fk(q_t)
        plain = swarm_ik.solve(swarm_ik.IKProblem(r, target), seed=k, time_limit=0.2)
        with_posture = swarm_ik.solve(
            swarm_ik.IKProblem(r, target, goals=[G.Posture(q_ref)]), seed=k, time_limit=0.2
        )
        assert plain.success and with_posture.success
        assert with_posture.position_error <= 1e-5 and with_posture.rotation_error <= 1e-5
        d_plain = np.linalg.norm(plain.q - q_ref)
        d_post = np.linalg.norm(with_posture.q - q_ref)
        closer += d_post < d_plain - 1e-9 or d_post < 1e-3
    assert closer >= 8


def test_contradictory_goals_return_the_best_found_with_success_false() -> None:
    r = robot("panda")
    f = r.ee_frame
    prob = swarm_ik.IKProblem(
        r, goals=[G.Position(f, [0.5, 0.0, 0.4]), G.Position(f, [0.5, 0.0, 0.6])]
    )
    res = swarm_ik.solve(prob, seed=0, max_evals=3000)
    assert not res.success and res.reason == "conflicting_goals"
    # the best compromise sits between the two points
    assert all(e.position_error == pytest.approx(0.1, abs=1e-3) for e in res.goal_errors)


@pytest.mark.parametrize(
    "case",
    ["pose+opposite axis", "orientation+axis", "one axis two ways", "look behind a pose",
     "look behind position+orientation"],
)  # fmt: skip
def test_contradictory_axis_goals_end_as_conflicting_goals(case: str) -> None:
    """An Axis or LookAt that no rotation meeting the frame's other goals can meet is
    reported as such at once (it ran the whole limit and said "time_limit" before)."""
    r = robot("panda")
    f = r.ee_frame
    target = r.fk(r.random_q(np.random.default_rng(1)))
    z, p = target[:3, 2], target[:3, 3]
    back = G.Axis(f, axis=[0, 0, 1], direction=-z)
    goals = {
        "pose+opposite axis": [G.Pose(f, target), back],
        "orientation+axis": [G.Orientation(f, target[:3, :3]), back],
        "one axis two ways": [
            G.Axis(f, axis=[0, 0, 1], direction=[0, 0, 1]),
            G.Axis(f, axis=[0, 0, 1], direction=[1, 0, 0]),
        ],
        "look behind a pose": [G.Pose(f, target), G.LookAt(f, axis=[0, 0, 1], point=p - 0.3 * z)],
        "look behind position+orientation": [
            G.Position(f, p),
            G.Orientation(f, target[:3, :3]),
            G.LookAt(f, axis=[0, 0, 1], point=p - 0.3 * z),
        ],  # fmt: skip
    }[case]
    res = swarm_ik.solve(swarm_ik.IKProblem(r, goals=goals), seed=0, time_limit=0.5)
    assert not res.success and res.reason == "conflicting_goals"
    assert res.time_s < 0.2  # (capped at api.UNREACHABLE_BUDGET's 0.05 s search)


def test_compatible_axis_goals_are_not_called_conflicting() -> None:
    r = robot("panda")
    f = r.ee_frame
    target = r.fk(r.random_q(np.random.default_rng(1)))
    z, p = target[:3, 2], target[:3, 3]
    for goals in (
        [G.Pose(f, target), G.Axis(f, axis=[0, 0, 1], direction=z)],
        [G.Pose(f, target), G.LookAt(f, axis=[0, 0, 1], point=p + 0.3 * z)],
        [
            G.Axis(f, axis=[0, 0, 1], direction=[0, 0, -1]),
            G.Axis(f, axis=[1, 0, 0], direction=[1, 0, 0]),
        ],
    ):
        res = swarm_ik.solve(swarm_ik.IKProblem(r, goals=goals), seed=0, time_limit=0.5)
        assert res.success and res.reason == "converged"


def test_unreachable_goal_is_reported_as_such() -> None:
    r = robot("panda")
    res = swarm_ik.solve(
        swarm_ik.IKProblem(r, goals=[G.Position(r.ee_frame, [3.0, 0, 0])]), max_evals=500
    )
    assert not res.success and res.reason == "unreachable"


def test_a_paper_optimiser_minimises_a_two_arm_goal_set() -> None:
    r = robot("baxter")
    left, right = r.fk_all(r.mid_q() + 0.1)
    prob = swarm_ik.IKProblem(
        r, goals=[G.Pose("left_gripper", left), G.Pose("right_gripper", right)]
    )
    start = float(prob.fitness(r.mid_q()[None])[0])
    res = swarm_ik.solve(prob, "mgwo", seed=0, max_evals=4000)
    assert res.fitness < 0.5 * start


BAD_GOALS = {
    "unknown type": ({"type": "Teleport", "frame": "x"}, "unknown goal type 'Teleport'"),
    "unknown field": (
        {"type": "Position", "frame": "panda_hand_tcp", "point": [0, 0, 0], "colour": 1},
        r"unknown field\(s\) \['colour'\]; valid fields: frame, point",
    ),
    "missing field": ({"type": "Position", "frame": "panda_hand_tcp"}, r"missing field"),
    "zero axis": (
        {"type": "Axis", "frame": "panda_hand_tcp", "axis": [0, 0, 0], "direction": [0, 0, 1]},
        "must not be the zero vector",
    ),
    "non-finite point": (
        {"type": "Position", "frame": "panda_hand_tcp", "point": [0, float("nan"), 0]},
        "must be finite",
    ),
    "negative weight": (
        {"type": "Position", "frame": "panda_hand_tcp", "point": [0, 0, 0], "weight": -1},
        "weight must be a positive",
    ),
}


@pytest.mark.parametrize("case", list(BAD_GOALS))
def test_bad_goal_input_is_refused_with_its_message(case: str) -> None:
    data, message = BAD_GOALS[case]
    with pytest.raises(swarm_ik.SwarmIKError, match=message):
        G.goal_from_dict(data)


def test_goal_on_a_frame_that_is_not_a_goal_frame_lists_the_goal_frames() -> None:
    r = robot("panda")
    with pytest.raises(swarm_ik.UnknownNameError, match="goal frames: panda_hand_tcp"):
        swarm_ik.IKProblem(r, goals=[G.Position("panda_link3", [0, 0, 0])])
    with pytest.raises(swarm_ik.UnknownNameError, match="unknown joint"):
        swarm_ik.IKProblem(r, goals=[G.JointValue("elbow", 0.0)])


def test_only_secondary_goals_and_paper_fitness_on_goal_sets_are_refused() -> None:
    r = robot("panda")
    with pytest.raises(swarm_ik.InvalidArgumentError, match="at least one goal must be primary"):
        swarm_ik.IKProblem(r, goals=[G.CenterJoints()])
    with pytest.raises(swarm_ik.InvalidArgumentError, match="single-pose form"):
        swarm_ik.IKProblem(r, goals=[G.Position(r.ee_frame, [0.4, 0, 0.4])], fitness="paper-l1")


def test_goals_json_round_trip(tmp_path) -> None:
    r = robot("panda")
    pose = r.fk(r.mid_q())
    goals = [
        G.Pose(r.ee_frame, pose),
        G.Axis(r.ee_frame, [0, 0, 1], [0, 0, -1]),
        G.Posture(r.mid_q().tolist()),
    ]
    path = tmp_path / "goals.json"
    path.write_text(json.dumps([G.goal_to_dict(g) for g in goals]))
    back = G.load_goals(path)
    assert [type(g) for g in back] == [type(g) for g in goals]
    np.testing.assert_allclose(back[0].target, pose)
    quat = {
        "type": "Pose",
        "frame": r.ee_frame,
        "target": {"position": [0.4, 0, 0.4], "quaternion": [1, 0, 0, 0]},
    }
    assert G.load_goals([quat])[0].target[2, 2] == pytest.approx(-1.0)
    with pytest.raises(swarm_ik.InvalidArgumentError, match="non-empty JSON list"):
        G.load_goals([])


def test_weight_and_primary_are_keyword_only_fields_of_every_goal() -> None:
    f = "panda_hand_tcp"
    pose = np.eye(4)
    for positional_weight in (
        lambda: G.Axis(f, [0, 0, 1], [0, 0, -1], 2.0),
        lambda: G.Pose(f, pose, 2.0),  # (not taken as orth_tol)
        lambda: G.Orientation(f, pose[:3, :3], 2.0),
        lambda: G.Posture([0.0] * 7, 2.0),  # (not taken as joint_weights)
        lambda: G.AvoidCollisions(None, True, 0.0, 5),  # (not taken as max_rows)
    ):
        with pytest.raises(swarm_ik.InvalidArgumentError, match="takes .* positional"):
            positional_weight()  # type: ignore[misc]
    assert list(G.goal_to_dict(G.Pose(f, pose))) == [
        "type", "frame", "target", "weight", "primary", "orth_tol", "tolerance",
    ]  # fmt: skip
    axis = G.Axis(f, [0, 0, 2], [0, 0, -1], weight=2.0, primary=False)
    assert (axis.weight, axis.primary) == (2.0, False)
    np.testing.assert_array_equal(axis.axis, [0.0, 0.0, 1.0])  # a direction is normalised
    # the JSON form and the error messages list the positional fields first
    assert list(G.goal_to_dict(axis)) == ["type", "frame", "axis", "direction", "weight", "primary"]
    assert [G.Posture([0.0]).primary, G.CenterJoints().primary] == [False, False]
    assert [G.JointValue("j", 0.0).primary, G.Position(f, [0, 0, 0]).primary] == [True, True]
    with pytest.raises(swarm_ik.InvalidArgumentError, match="LookAt.point must be finite"):
        G.LookAt(f, [0, 0, 1], [0, math.inf, 0])
    with pytest.raises(swarm_ik.InvalidArgumentError, match="Axis.direction must not be the zero"):
        G.Axis(f, [0, 0, 1], [0, 0, 0])
    with pytest.raises(swarm_ik.InvalidArgumentError, match="weight must be a positive"):
        G.CenterJoints(weight=0.0)


@pytest.mark.parametrize("bad", [-1.0, 1e200])
def test_posture_joint_weights_outside_the_weight_range_are_refused(bad: float) -> None:
    """A joint weight of 1e200 overflowed the stacked rows: a reachable primary Position then
    failed (``stopped``) beside its secondary Posture; now refused as a goal weight is."""
    r = robot("panda")
    jw = np.ones(7)
    jw[3] = bad
    goals = [G.Position(r.ee_frame, r.fk(r.mid_q())[:3, 3]), G.Posture(r.mid_q(), joint_weights=jw)]
    with pytest.raises(
        swarm_ik.errors.InvalidArgumentError,
        match=r"Posture\.joint_weights must be between 0 and 1e\+06",
    ):
        swarm_ik.IKProblem(r, goals=goals)


def test_a_primary_joint_value_beyond_the_limits_ends_unreachable_at_once() -> None:
    """Panda's joint 1 spans ±2.90 rad: a primary JointValue at 10 rad searched a whole
    5 s limit (3.4 million evaluations) and ended 'time_limit'; it ends 'unreachable' within
    the cap for such goals.  Within the tolerance of a limit it is met; a secondary one only
    pulls the joint."""
    import time

    r = robot("panda")
    point = G.Position(r.ee_frame, r.fk(r.mid_q())[:3, 3])
    t0 = time.perf_counter()
    res = swarm_ik.solve(
        swarm_ik.IKProblem(r, goals=[point, G.JointValue("panda_joint1", 10.0)]),
        seed=0, time_limit=5.0,
    )  # fmt: skip
    assert not res.success and res.reason == "unreachable"
    assert time.perf_counter() - t0 < 2.0
    near = G.JointValue("panda_joint1", float(r.upper[0]) + 2e-6)
    res = swarm_ik.solve(swarm_ik.IKProblem(r, goals=[point, near]), seed=0)
    assert res.success
    soft = G.JointValue("panda_joint1", 10.0, primary=False)
    res = swarm_ik.solve(swarm_ik.IKProblem(r, goals=[point, soft]), seed=0)
    assert res.success and res.q[0] == pytest.approx(r.upper[0], abs=1e-6)
