"""CenterOfMass: the centre of mass and its Jacobian against Pinocchio and finite differences,
the support-polygon inequality, balanced whole-body solves, bad input refused."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import swarm_ik
from swarm_ik import goals
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.goals import CenterOfMass
from swarm_ik.goals.base import State
from swarm_ik.kernels import lm

FRAMES = ["left_sole_link", "right_sole_link", "gripper_left_base_link", "gripper_right_base_link"]
SQUARE = [[-0.1, -0.1], [0.1, -0.1], [0.1, 0.1], [-0.1, 0.1]]

L_SHAPE = [[-0.1, -0.1], [2.0, -0.1], [2.0, 0.1], [0.1, 0.1], [0.1, 2.0], [-0.1, 2.0]]
"""An L of arms 0.2 m wide: its largest inscribed circle (in the corner, touching both outer
edges and the inner vertex) has radius 0.1·(1 + (√2 − 1)/(√2 + 1)) ≈ 0.117 m."""


@pytest.fixture(scope="module")
def talos() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot(
        "talos", FRAMES, floating_base=True, locked={"torso_1_joint": 0.0, "torso_2_joint": 0.0}
    )


def _kernel_rows(robot: swarm_ik.RobotModel, goal: CenterOfMass, q: np.ndarray) -> tuple:
    """Residual rows, step Jacobian and errors of the compiled kernel at ``q``."""
    problem = swarm_ik.IKProblem(robot, goals=[goal])
    m = goal.rows(robot)
    res, jac, err = np.zeros((1, m)), np.zeros((1, m, robot.nq)), np.zeros((1, 1, 2))
    lm.residuals_batch(
        q[None], problem.tree, problem.table(None), goals.kernels(), problem.bounds, True,
        res, jac, err,
    )  # fmt: skip
    return res[0], jac[0], err[0, 0]


@pytest.mark.parametrize("name", ["talos", "panda", "panda-locked", "talos-fixed"])
def test_center_and_jacobian_match_pinocchio(name: str, talos: swarm_ik.RobotModel) -> None:
    """Against ``pinocchio.centerOfMass`` on the whole URDF, including the links a held joint
    next to a fixed base carries (panda's joint 1 locked; a fixed-base Talos's legs, off the
    paths to its default frames), which the reduced model merges into its world body."""
    robot = {
        "talos": lambda: talos,
        "panda": lambda: swarm_ik.load_robot("panda"),
        "panda-locked": lambda: swarm_ik.load_robot("panda", locked={"panda_joint1": 0.5}),
        "talos-fixed": lambda: swarm_ik.load_robot("talos"),
    }[name]()
    goal = CenterOfMass(point=[0.1, -0.2, 0.3], axes="xyz")
    rng = np.random.default_rng(0)
    full = robot.full_model
    for _ in range(4):
        q = robot.random_q(rng)
        qf = robot.full_configuration(q)
        c_ref = np.array(pin.centerOfMass(full, full.createData(), qf))
        np.testing.assert_allclose(goal.center(robot, q), c_ref, atol=1e-12)
        res, jac, _ = _kernel_rows(robot, goal, q)
        np.testing.assert_allclose(res, goal.point - c_ref, atol=1e-12)
        jc = np.array(pin.jacobianCenterOfMass(full, full.createData(), qf))
        if not robot.floating_base:  # (the same joints, in the same order: a direct check)
            cols = [full.joints[full.getJointId(n)].idx_v for n in robot.joint_names]
            np.testing.assert_allclose(jac, jc[:, cols], atol=1e-12)
        np.testing.assert_allclose(-jac, goal.jacobian(State(robot, q)), atol=1e-12)
        np.testing.assert_allclose(goal.residual(State(robot, q)), goal.point - c_ref, atol=1e-12)
        h = 1e-6
        num = np.empty((3, robot.nq))
        for k in range(robot.nq):
            dq = np.zeros(robot.nq)
            dq[k] = h
            num[:, k] = (goal.center(robot, q + dq) - goal.center(robot, q - dq)) / (2 * h)
        np.testing.assert_allclose(jac, num, atol=1e-7)


def test_support_row_zero_inside_continuous_and_exact_outside(talos: swarm_ik.RobotModel) -> None:
    q = talos.mid_q()
    c = CenterOfMass(point=[0, 0, 0]).center(talos, q)
    for dx, expect in [(0.0, 0.0), (0.1 - 1e-9, 0.0), (0.1 + 1e-9, 1e-9), (0.3, 0.2)]:
        square = np.array(SQUARE) + c[:2] - [dx, 0.0]  # c at dx from the square's centre
        goal = CenterOfMass(support=square)
        res, _, err = _kernel_rows(talos, goal, q)
        assert res[0] == pytest.approx(-expect, abs=1e-12)
        assert err[0] == pytest.approx(expect, abs=1e-12)
        np.testing.assert_allclose(res, goal.residual(State(talos, q)), atol=1e-12)
    goal = CenterOfMass(support=np.array(SQUARE) + c[:2] - [0.05, 0.0], margin=0.08)
    assert _kernel_rows(talos, goal, q)[0][0] == pytest.approx(-0.03, abs=1e-12)


def test_support_jacobian_outside_matches_finite_differences(talos: swarm_ik.RobotModel) -> None:
    rng = np.random.default_rng(4)
    q = talos.random_q(rng)
    c = CenterOfMass(point=[0, 0, 0]).center(talos, q)
    goal = CenterOfMass(support=np.array(SQUARE) + c[:2] + [0.3, 0.2])  # c outside a corner
    _, jac, _ = _kernel_rows(talos, goal, q)
    state = State(talos, q)
    np.testing.assert_allclose(-jac, goal.jacobian(state), atol=1e-12)
    h = 1e-6
    for k in range(talos.nq):
        dq = np.zeros(talos.nq)
        dq[k] = h
        num = (goal.residual(State(talos, q + dq)) - goal.residual(State(talos, q - dq))) / (2 * h)
        np.testing.assert_allclose(-jac[:, k], num, atol=1e-7)


def test_non_convex_polygon() -> None:
    """An L-shaped support: its notch is outside."""
    from swarm_ik.goals.center_of_mass import _polygon_distance

    ell = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)
    vx, vy = ell[:, 0].copy(), ell[:, 1].copy()
    assert _polygon_distance(0.5, 0.5, vx, vy)[0] == pytest.approx(-0.5)
    assert _polygon_distance(1.5, 1.5, vx, vy)[0] == pytest.approx(0.5)
    assert _polygon_distance(1.5, 0.5, vx, vy)[0] == pytest.approx(-0.5)


def test_balanced_whole_body_solved_on_reachable_targets(talos: swarm_ik.RobotModel) -> None:
    rng = np.random.default_rng(9)
    full = talos.full_model
    for k in range(6):
        q = talos.random_q(rng)
        q[:6] = 0.0
        poses = talos.fk_all(q)
        c = CenterOfMass(point=[0, 0, 0]).center(talos, q)
        support = np.array(SQUARE) + c[:2]
        problem = swarm_ik.IKProblem(
            talos,
            goals=[goals.Pose(f, poses[i]) for i, f in enumerate(talos.frames)]
            + [CenterOfMass(support=support, margin=0.01)],
        )
        res = swarm_ik.solve(problem, seed=k, time_limit=1.0)
        assert res.success, res.reason
        c_new = np.array(pin.centerOfMass(full, full.createData(), talos.full_configuration(res.q)))
        assert np.all(np.abs(c_new[:2] - c[:2]) <= 0.1 - 0.01 + 1e-6)


def test_com_point_goal_moves_the_centre(talos: swarm_ik.RobotModel) -> None:
    q = talos.mid_q()
    poses = talos.fk_all(q)
    c = CenterOfMass(point=[0, 0, 0]).center(talos, q)
    want = c + [0.03, -0.02, -0.05]
    problem = swarm_ik.IKProblem(
        talos,
        goals=[goals.Pose(f, poses[i]) for i, f in enumerate(talos.frames[:2])]
        + [CenterOfMass(point=want, axes="xyz")],
    )
    res = swarm_ik.solve(problem, seed=0, time_limit=1.0)
    assert res.success
    np.testing.assert_allclose(CenterOfMass(point=[0, 0, 0]).center(talos, res.q), want, atol=1e-5)


def test_json_round_trip() -> None:
    goal = CenterOfMass(support=SQUARE, margin=0.02)
    again = goals.goal_from_dict(goals.goal_to_dict(goal))
    assert isinstance(again, CenterOfMass)
    np.testing.assert_array_equal(again.support, goal.support)
    assert again.margin == 0.02 and again.point is None


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({}, "needs a point"),
        ({"support": [[0, 0], [1, 0]]}, "at least 3"),
        ({"support": [[0, 0], [2, 2], [2, 0], [0, 1]]}, "self-intersecting"),
        # (a bow-tie whose halves cancel: named as what it is, not "zero area"; review 90)
        ({"support": [[0, 0], [1, 1], [1, 0], [0, 1]]}, "self-intersecting"),
        ({"support": [[0, 0], [1, 0], [float("nan"), 1]]}, "finite"),
        ({"support": [[0, 0], [1, 0], [2, 0]]}, "zero area"),
        ({"support": [[0, 0], [1, 0], [1, 1], [1, 0]]}, "repeats"),
        ({"support": "square"}, "vertices"),
        ({"point": [0, 0]}, "3 numbers"),
        ({"point": [0, 0, 0], "axes": "xw"}, "axes"),
        ({"point": [0, 0, 0], "axes": "xx"}, "axes"),
        ({"support": SQUARE, "margin": -0.1}, "margin"),
    ],
)
def test_bad_input_refused(kwargs: dict, words: str) -> None:
    with pytest.raises(InvalidArgumentError, match=words):
        CenterOfMass(**kwargs)


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"support": L_SHAPE, "margin": 0.15}, "deeper than its support polygon allows"),
        ({"point": [2.0, 0.0, 0.0], "support": SQUARE}, r"outside its support polygon"),
        ({"point": [0.0, 0.0, 0.0], "support": L_SHAPE, "margin": 0.11}, "less than the margin"),
    ],
)
def test_a_centre_of_mass_goal_no_configuration_meets_is_known_before_the_search(
    kwargs: dict, words: str
) -> None:
    """Such goals searched their whole budget and ended with a seed-dependent reason; the
    goal now says why it is infeasible (a primary one's solve ends 'unreachable'), within
    the tolerances only: a point 2 µm off the polygon is met."""
    goal = CenterOfMass(**kwargs)
    why = goal.infeasible(None, 1e-5, 1e-5)  # type: ignore[arg-type]  # (no robot read)
    assert why is not None and words in why
    near = CenterOfMass(point=[0.1 + 2e-6, 0.0, 0.0], support=SQUARE)
    assert near.infeasible(None, 1e-5, 1e-5) is None  # type: ignore[arg-type]


def test_the_deepest_point_bound_holds_and_a_feasible_margin_is_kept() -> None:
    """The bound on the inscribed radius is never below the true one and at most 1e-5 m
    above it (a square: half its side; a 3-4-5 triangle: 1; a 2 m × 0.1 m rectangle, whose
    deepest points fill a segment: 0.05; the L: its corner circle); margins
    up to the true radius are not called infeasible."""
    from swarm_ik.goals.center_of_mass import deepest_inside

    sq = np.array(SQUARE, dtype=float)
    side = float(np.ptp(sq[:, 0]))
    cases = [
        (sq, side / 2),
        (np.array([[0, 0], [3, 0], [0, 4]], dtype=float), 1.0),
        (np.array([[0, 0], [2, 0], [2, 0.1], [0, 0.1]], dtype=float), 0.05),
    ]
    for poly, radius in cases:
        assert radius <= deepest_inside(poly) <= radius + 1e-5, poly
    corner = 0.1 * (1 + (2**0.5 - 1) / (2**0.5 + 1))  # (L_SHAPE's docstring)
    assert corner <= deepest_inside(np.array(L_SHAPE, dtype=float)) <= corner + 1e-5
    for goal in (
        CenterOfMass(support=SQUARE, margin=0.999 * side / 2),
        CenterOfMass(support=L_SHAPE, margin=0.099),
        CenterOfMass(point=[0.0, 1.0, 0.0], support=L_SHAPE, margin=0.099),
    ):
        assert goal.infeasible(None, 1e-5, 1e-5) is None  # type: ignore[arg-type]


def test_a_margin_just_beyond_the_inscribed_radius_is_infeasible() -> None:
    """An L whose arms are 0.1 m wide holds no point deeper than about 0.0586 m: a margin of
    0.06 is refused before any search (the grid bound said 0.062 and let the search run its
    whole time limit)."""
    corner = [[0, 0], [0.4, 0], [0.4, 0.1], [0.1, 0.1], [0.1, 0.4], [0, 0.4]]
    why = CenterOfMass(support=corner, margin=0.06).infeasible(None, 1e-5, 1e-5)  # type: ignore[arg-type]
    assert why is not None and "deeper than its support polygon allows" in why
    assert CenterOfMass(support=corner, margin=0.058).infeasible(None, 1e-5, 1e-5) is None  # type: ignore[arg-type]


def test_a_point_on_one_ground_axis_outside_the_polygons_range_is_infeasible() -> None:
    """``axes="x"`` with x beyond the feet's range ran its whole time limit (the proof looked
    only at points on both ground axes)."""
    feet = [[-0.105, -0.15], [0.105, -0.15], [0.105, 0.15], [-0.105, 0.15]]
    far = CenterOfMass(point=[0.5, 0, 0], axes="x", support=feet)
    why = far.infeasible(None, 1e-5, 1e-5)  # type: ignore[arg-type]
    assert why is not None and "outside its support polygon's range" in why
    deep = CenterOfMass(point=[0, 0.12, 0], axes="y", support=feet, margin=0.05)
    assert deep.infeasible(None, 1e-5, 1e-5) is not None  # type: ignore[arg-type]
    inside = CenterOfMass(point=[0.05, 0, 0], axes="xz", support=feet, margin=0.05)
    assert inside.infeasible(None, 1e-5, 1e-5) is None  # type: ignore[arg-type]


def test_urdf_without_masses_is_refused(tmp_path) -> None:  # type: ignore[no-untyped-def]
    links = "".join(f'<link name="l{i}"/>' for i in range(3))
    joints = "".join(
        f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>'
        f'<limit lower="-2" upper="2" effort="1" velocity="1"/></joint>'
        for i in range(2)
    )
    path = tmp_path / "massless.urdf"
    path.write_text(f'<robot name="massless">{links}{joints}</robot>')
    robot = swarm_ik.load_robot(path, "l2")
    with pytest.raises(swarm_ik.errors.RobotModelError, match="no link masses"):
        swarm_ik.IKProblem(robot, goals=[CenterOfMass(point=[0, 0, 0.3])])


def test_a_margin_within_the_polygon_is_answered_by_a_deep_enough_point() -> None:
    """The whole bound of a foot's rectangle took 8.6 ms, paid by every solve of a new
    goal (a standing humanoid's median solve went from 5 to 11 ms); the question asked,
    "is any point ``margin`` deep?", is answered as soon as one is found: a depth at least
    ``enough`` (feasible), or the bound (when none is that deep)."""
    from swarm_ik.goals.center_of_mass import deepest_inside

    rect = np.array([[0.0, 0.0], [0.25, 0.0], [0.25, 0.35], [0.0, 0.35]])
    assert 0.03 <= deepest_inside(rect, enough=0.03) <= 0.125
    assert 0.125 <= deepest_inside(rect, enough=0.2) <= 0.125 + 1e-5  # (none that deep)
    assert CenterOfMass(support=rect.tolist(), margin=0.03).infeasible(None, 1e-5, 1e-5) is None  # type: ignore[arg-type]
    assert CenterOfMass(support=rect.tolist(), margin=0.13).infeasible(None, 1e-5, 1e-5)  # type: ignore[arg-type]
