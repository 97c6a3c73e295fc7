"""Tolerance goals: ``Pose(..., tolerance=(tx, ty, tz, rx, ry, rz))`` (bounds in the target
frame) and ``Position(..., radius=r)`` (a ball).  Dead-zone residuals zero inside and
continuous across the bounds, the compiled rows equal to the numpy reference, Jacobians against
central differences, solves judged by ``success`` and ``goal_errors``, bad input refused, the
JSON round trip."""

from __future__ import annotations

import json
import math

import numpy as np
import pinocchio as pin
import pytest
from conftest import robot

import swarm_ik
from swarm_ik import goals as G
from swarm_ik.api import conflicting_goals
from swarm_ik.branches import pose_errors
from swarm_ik.solvers.hybrid import Polisher

BOX = (0.01, 0.02, 0.005, 0.05, 0.1, 0.2)
"""Position half-widths [m] along the target's axes, then rotation-vector bounds [rad]."""
Z_FREE = (0.0, 0.0, 0.0, 0.0, 0.0, math.pi)


def _exp3(phi) -> np.ndarray:  # type: ignore[no-untyped-def]
    """The rotation ``exp([φ]×)`` (3, 3) of a rotation vector (Pinocchio's)."""
    return np.array(pin.exp3(np.asarray(phi, dtype=float)))


def _within(pose: np.ndarray, tol: tuple[float, ...], rng: np.random.Generator) -> np.ndarray:
    """A target whose bounds ``tol`` hold ``pose`` strictly inside (at most 60 % of each)."""
    t = np.asarray(tol)
    delta = np.eye(4)
    delta[:3, 3] = rng.uniform(-0.6, 0.6, 3) * t[:3]
    delta[:3, :3] = _exp3(rng.uniform(-0.6, 0.6, 3) * np.minimum(t[3:], 1.0))
    return np.asarray(pose @ np.linalg.inv(delta))  # T*⁻¹·pose = delta


def _bounded_goals(r: swarm_ik.RobotModel, pose: np.ndarray) -> list[G.Goal]:
    f = r.ee_frame
    return [
        G.Pose(f, pose, tolerance=BOX),
        G.Pose(f, pose, tolerance=Z_FREE),
        G.Pose(f, pose, tolerance=(0.0,) * 6),
        G.Pose(f, pose, tolerance=(0.3, 0.3, 0.3, 1.0, 1.0, 1.0)),
        G.Position(f, pose[:3, 3], radius=0.05),
        G.Position(f, pose[:3, 3], radius=0.0),
        G.Position(f, pose[:3, 3], radius=0.4),
    ]


# ----------------------------------------------------------------------- the residual
def test_residual_is_zero_inside_the_bounds() -> None:
    r = robot("panda")
    rng = np.random.default_rng(0)
    for _ in range(5):
        q = r.random_q(rng)
        pose = r.fk(q)
        state = G.State(r, q)
        for tol in (BOX, (0.1, 0.1, 0.1, 0.5, 0.5, 0.5)):
            goal = G.Pose(r.ee_frame, _within(pose, tol, rng), tolerance=tol)
            np.testing.assert_array_equal(goal.residual(state), np.zeros(6))
            assert goal.errors(state) == (0.0, 0.0)
        # z free: any turn about the target's z axis (zero bounds elsewhere: round-off only)
        turned = pose.copy()
        turned[:3, :3] = pose[:3, :3] @ _exp3([0.0, 0.0, rng.uniform(-3.1, 3.1)])
        goal = G.Pose(r.ee_frame, turned, tolerance=Z_FREE)
        np.testing.assert_allclose(goal.residual(state), np.zeros(6), atol=1e-14)
        np.testing.assert_allclose(goal.errors(state), (0.0, 0.0), atol=1e-14)
        near = pose[:3, 3] + rng.normal(size=3) * 0.01
        ball = G.Position(r.ee_frame, near, radius=float(np.linalg.norm(near - pose[:3, 3])) + 1e-9)
        np.testing.assert_array_equal(ball.residual(state), np.zeros(3))
        assert ball.errors(state)[0] == 0.0


def test_residual_is_the_part_beyond_the_bounds_and_continuous_across_them() -> None:
    r = robot("panda")
    rng = np.random.default_rng(1)
    q = r.random_q(rng)
    pose = r.fk(q)
    target = _within(pose, (0.05, 0.05, 0.05, 0.3, 0.3, 0.3), rng)
    exact = G.Pose(r.ee_frame, target, tolerance=(0.0,) * 6)
    e0 = -exact.residual(G.State(r, q))  # the offsets e, φ at q
    # bounds at exactly |e|, |φ|: q lies on every boundary at once
    on = G.Pose(r.ee_frame, target, tolerance=tuple(np.abs(e0)))
    direction = rng.normal(size=r.nq)
    direction /= np.linalg.norm(direction)
    steps = np.linspace(-1e-3, 1e-3, 41)
    rows = np.array([on.residual(G.State(r, q + s * direction)) for s in steps])
    np.testing.assert_allclose(rows[20], 0.0, atol=1e-15)  # on the boundary
    # no jump: neighbouring samples differ by at most the rows' Lipschitz bound × the step
    assert np.max(np.abs(np.diff(rows, axis=0))) < 5.0 * (steps[1] - steps[0])
    # beyond the bounds the row is −sign(e)·(|e| − t); each row is zero on one side
    assert np.all((rows[:20] == 0.0) | (rows[21:][::-1] == 0.0))
    for s, row in zip(steps, rows, strict=True):
        e = -exact.residual(G.State(r, q + s * direction))
        np.testing.assert_allclose(
            row, -np.sign(e) * np.maximum(np.abs(e) - np.abs(e0), 0.0), atol=1e-15
        )
    # the ball: −(‖d‖ − ρ)·u outside, continuous at the sphere
    rho = float(np.linalg.norm(pose[:3, 3] - target[:3, 3]))
    ball = G.Position(r.ee_frame, target[:3, 3], radius=rho)
    rows = np.array([ball.residual(G.State(r, q + s * direction)) for s in steps])
    np.testing.assert_allclose(rows[20], 0.0, atol=1e-15)
    assert np.max(np.abs(np.diff(rows, axis=0))) < 5.0 * (steps[1] - steps[0])
    for s, row in zip(steps, rows, strict=True):
        d = r.fk(q + s * direction)[:3, 3] - target[:3, 3]
        n = np.linalg.norm(d)
        np.testing.assert_allclose(row, -max(n - rho, 0.0) * d / n, atol=1e-15)
        assert ball.errors(G.State(r, q + s * direction))[0] == pytest.approx(
            max(n - rho, 0.0), abs=1e-15
        )


def test_zero_bounds_and_zero_radius_measure_as_the_exact_goals() -> None:
    r = robot("panda")
    rng = np.random.default_rng(2)
    q, pose = r.random_q(rng), r.fk(r.random_q(rng))
    state = G.State(r, q)
    exact, zero = G.Pose(r.ee_frame, pose), G.Pose(r.ee_frame, pose, tolerance=(0,) * 6)
    np.testing.assert_allclose(zero.errors(state), exact.errors(state), atol=1e-12)
    # the same rows in the target's axes: R*ᵀ(p* − p) and −log(R*ᵀ R) = R*ᵀ log(R* Rᵀ)
    rt = pose[:3, :3].T
    r_exact = exact.residual(state)
    np.testing.assert_allclose(
        zero.residual(state), np.concatenate([rt @ r_exact[:3], rt @ r_exact[3:]]), atol=1e-12
    )
    ball, point = (
        G.Position(r.ee_frame, pose[:3, 3], radius=0.0),
        G.Position(r.ee_frame, pose[:3, 3]),
    )
    np.testing.assert_allclose(ball.residual(state), point.residual(state), atol=1e-15)
    np.testing.assert_allclose(ball.jacobian(state), point.jacobian(state), atol=1e-15)


# ----------------------------------------------------------------------- kernel = reference
@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_kernel_rows_equal_the_numpy_reference(name: str) -> None:
    r = robot(name)
    rng = np.random.default_rng(3)
    for k in range(4):
        q_t, q = r.random_q(rng), r.random_q(rng)
        pose = r.fk(q_t) if k % 2 else _within(r.fk(q), BOX, rng)  # far, or q inside BOX
        state = G.State(r, q)
        for goal in _bounded_goals(r, pose):
            prob = swarm_ik.IKProblem(r, goals=[goal])
            res, jac, _, _ = Polisher.from_problem(prob).residual(q)
            np.testing.assert_allclose(goal.residual(state), res, atol=1e-12, err_msg=str(goal))
            np.testing.assert_allclose(-goal.jacobian(state), jac, atol=1e-12, err_msg=str(goal))
            err = prob.goal_errors(q)[0, 0]
            check = prob.verify(q)[0]
            np.testing.assert_allclose(
                [check.position_error, check.rotation_error], err, atol=1e-10, equal_nan=True
            )
            # the vectorised check of many answers (solve_many) agrees with verify
            dp, dr = pose_errors(prob, q[None])
            assert dp[0] == pytest.approx(check.position_error, abs=1e-12)


def test_exact_forms_keep_their_parameter_layout() -> None:
    r = robot("panda")
    pose = r.fk(r.mid_q())
    enc = G.Pose(r.ee_frame, pose).encode(r, None)
    assert enc.par.shape == (12,) and enc.ipar.tolist() == [0] and enc.rows == 6
    np.testing.assert_array_equal(enc.par, G.Pose.params(pose))
    checked = G.Pose.checked(r.ee_frame, pose)
    assert checked.tolerance is None and checked.encode(r, None).par.shape == (12,)
    bounded = G.Pose(r.ee_frame, pose, tolerance=BOX)
    enc = bounded.encode(r, None)
    assert enc.ipar.tolist() == [0] and enc.rows == 6
    assert bounded.kernel_of() is not checked.kernel_of()  # (each form its own kernel)
    np.testing.assert_array_equal(enc.par[:12], G.Pose.params(pose))
    np.testing.assert_array_equal(enc.par[12:], BOX)
    enc = G.Position(r.ee_frame, pose[:3, 3]).encode(r, None)
    assert enc.par.shape == (3,) and enc.ipar.tolist() == [0]
    enc = G.Position(r.ee_frame, pose[:3, 3], radius=0.1).encode(r, None)
    assert enc.par.tolist() == [*pose[:3, 3], 0.1] and enc.ipar.tolist() == [0, 1]


# ----------------------------------------------------------------------- Jacobians
def _central(fn, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    cols = []
    for j in range(q.shape[0]):
        e = np.zeros(q.shape[0])
        e[j] = h
        cols.append((fn(q + e) - fn(q - e)) / (2 * h))
    return np.stack(cols, axis=-1)


@pytest.mark.parametrize("name", ["panda", "kinova"])
def test_jacobians_match_central_differences_away_from_the_bounds(name: str) -> None:
    r = robot(name)
    f = r.ee_frame
    rng = np.random.default_rng(4)
    checked = 0
    for _ in range(6):
        q = r.random_q(rng)
        pose = r.fk(r.random_q(rng))
        for tol in (BOX, Z_FREE, (0.3, 0.3, 0.3, 1.0, 1.0, 1.0)):
            goal = G.Pose(f, pose, tolerance=tol)
            e, phi = goal.offsets(r.fk(q))
            off = np.concatenate([e, phi])
            if np.linalg.norm(phi) > 2.5:
                continue  # log3's branch cut at π
            t = np.asarray(tol)
            margin = np.abs(np.abs(off) - t)
            if margin.min() < 1e-4:
                continue  # too near a bound for a difference quotient
            jac = goal.jacobian(G.State(r, q))
            num = _central(lambda x, g=goal: g.residual(G.State(r, x)), q)
            active = np.abs(off) > t
            np.testing.assert_allclose(jac[active], num[active], atol=3e-7)
            # inside: the residual is flat; the step Jacobian is the offset's derivative
            # (a row at rest holds its offset), zero on a free axis
            np.testing.assert_allclose(num[~active], 0.0, atol=1e-12)
            d_off = _central(lambda x, g=goal: np.concatenate(g.offsets(r.fk(x))), q)
            held = ~active & (t < math.pi)
            np.testing.assert_allclose(jac[held], -d_off[held], atol=3e-7)
            np.testing.assert_array_equal(jac[~active & (t >= math.pi)], 0.0)
            checked += int(active.sum())
        for rho in (0.0, 0.05, 0.5):
            ball = G.Position(f, pose[:3, 3], radius=rho)
            n = float(np.linalg.norm(r.fk(q)[:3, 3] - pose[:3, 3]))
            if abs(n - rho) < 1e-4:
                continue
            jac = ball.jacobian(G.State(r, q))
            if n > rho:
                num = _central(lambda x, g=ball: g.residual(G.State(r, x)), q)
                np.testing.assert_allclose(jac, num, atol=3e-7)
            else:  # inside: the radial rows hold the distance, −u·∂‖d‖/∂q
                d = r.fk(q)[:3, 3] - pose[:3, 3]
                dist = _central(lambda x, c=pose[:3, 3]: np.linalg.norm(r.fk(x)[:3, 3] - c), q)
                np.testing.assert_allclose(jac, -np.outer(d / n, dist), atol=3e-7)
    assert checked > 20  # the active rows were exercised


# ----------------------------------------------------------------------- solves
def test_a_target_perturbed_within_the_bounds_is_met_at_once() -> None:
    r = robot("panda")
    rng = np.random.default_rng(5)
    for k in range(4):
        q_t = r.random_q(rng)
        target = _within(r.fk(q_t), BOX, rng)
        prob = swarm_ik.IKProblem(r, goals=[G.Pose(r.ee_frame, target, tolerance=BOX)])
        res = swarm_ik.solve(prob, q0=q_t, seed=k, time_limit=0.5)
        assert res.success and res.reason == "converged"
        assert res.n_evals <= 2  # met at the start
        (err,) = res.goal_errors
        assert err.met and err.position_error == 0.0 and err.rotation_error == 0.0
        np.testing.assert_allclose(res.q, q_t, atol=1e-12)
        # the exact goal on the same target is not met there
        exact = swarm_ik.IKProblem(r, goals=[G.Pose(r.ee_frame, target)])
        assert not exact.verify(q_t)[0].met


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_a_target_with_the_z_rotation_free_is_solved_with_the_tool_axis_aligned(
    name: str,
) -> None:
    r = robot(name)
    rng = np.random.default_rng(6)
    for k in range(3):
        pose = r.fk(r.random_q(rng))
        target = pose.copy()
        target[:3, :3] = pose[:3, :3] @ _exp3([0.0, 0.0, rng.uniform(-3.0, 3.0)])
        goal = G.Pose(r.ee_frame, target, tolerance=Z_FREE)
        res = swarm_ik.solve(swarm_ik.IKProblem(r, goals=[goal]), seed=k, time_limit=1.0)
        assert res.success, res
        (err,) = res.goal_errors
        assert err.met and err.position_error <= 1e-5 and err.rotation_error <= 1e-5
        got = r.fk_pinocchio(res.q)
        np.testing.assert_allclose(got[:3, 3], target[:3, 3], atol=1e-5)
        np.testing.assert_allclose(got[:3, 2], target[:3, 2], atol=2e-5)


def test_box_bounds_are_met_from_afar_and_reported_as_distance_to_the_bounds() -> None:
    r = robot("panda")
    rng = np.random.default_rng(7)
    tol = (0.02, 0.02, 0.02, 0.1, 0.1, 0.1)
    for k in range(3):
        target = r.fk(r.random_q(rng))
        goal = G.Pose(r.ee_frame, target, tolerance=tol)
        prob = swarm_ik.IKProblem(r, goals=[goal])
        res = swarm_ik.solve(prob, seed=k, time_limit=1.0)
        assert res.success, res
        e, phi = goal.offsets(r.fk_pinocchio(res.q))
        assert np.all(np.abs(e) <= np.asarray(tol[:3]) + 1e-5)
        assert np.all(np.abs(phi) <= np.asarray(tol[3:]) + 1e-5)
        (err,) = res.goal_errors
        excess = np.maximum(np.abs(np.concatenate([e, phi])) - np.asarray(tol), 0.0)
        assert err.position_error == pytest.approx(np.linalg.norm(excess[:3]), abs=1e-12)
        assert err.rotation_error == pytest.approx(np.linalg.norm(excess[3:]), abs=1e-12)
    # far outside its bounds, a start reports how far
    far = G.Pose(r.ee_frame, r.fk(r.mid_q()), tolerance=tol)
    q = r.mid_q() + 0.5
    (err,) = swarm_ik.IKProblem(r, goals=[far]).verify(q)
    assert not err.met and err.position_error > 0.0


def test_position_radius_is_a_ball() -> None:
    r = robot("panda")
    rng = np.random.default_rng(8)
    for k in range(3):
        q_t = r.random_q(rng)
        p = r.fk(q_t)[:3, 3]
        centre = p + 0.04 * rng.normal(size=3)
        rho = 0.03
        goal = G.Position(r.ee_frame, centre, radius=rho)
        prob = swarm_ik.IKProblem(r, goals=[goal])
        res = swarm_ik.solve(prob, seed=k, time_limit=1.0)
        assert res.success, res
        dist = float(np.linalg.norm(r.fk_pinocchio(res.q)[:3, 3] - centre))
        (err,) = res.goal_errors
        assert dist <= rho + 1e-5
        assert err.position_error == pytest.approx(max(dist - rho, 0.0), abs=1e-12)
        assert math.isnan(err.rotation_error)
        # a start inside the ball is met at once
        inside = G.Position(r.ee_frame, p + [0.01, 0, 0], radius=0.02)
        res = swarm_ik.solve(swarm_ik.IKProblem(r, goals=[inside]), q0=q_t, seed=k)
        assert res.success and res.n_evals <= 2 and res.goal_errors[0].position_error == 0.0


def test_bounded_and_exact_forms_of_one_goal_type_do_not_share_a_route() -> None:
    r = robot("panda")
    q_t = r.random_q(np.random.default_rng(9))
    target = _within(r.fk(q_t), BOX, np.random.default_rng(10))
    for goal in (
        G.Pose(r.ee_frame, target),
        G.Pose(r.ee_frame, target, tolerance=BOX),
        G.Pose(r.ee_frame, target),
        G.Position(r.ee_frame, target[:3, 3]),
        G.Position(r.ee_frame, target[:3, 3], radius=0.05),
    ):
        prob = swarm_ik.IKProblem(r, goals=[goal])
        res = swarm_ik.solve(prob, q0=q_t, seed=0, time_limit=1.0)
        assert res.success, (goal, res)
        check = prob.verify(res.q)[0]
        assert res.goal_errors[0].position_error == check.position_error


def test_overlapping_regions_are_not_conflicting_goals() -> None:
    r = robot("panda")
    f = r.ee_frame
    a, b = [0.5, 0.0, 0.4], [0.5, 0.1, 0.4]
    exact = swarm_ik.IKProblem(r, goals=[G.Position(f, a), G.Position(f, b)])
    assert conflicting_goals(exact, 1e-5, 1e-5) is not None
    balls = swarm_ik.IKProblem(
        r, goals=[G.Position(f, a, radius=0.06), G.Position(f, b, radius=0.06)]
    )
    assert conflicting_goals(balls, 1e-5, 1e-5) is None
    res = swarm_ik.solve(balls, seed=0, time_limit=1.0)
    assert res.success, res
    pose = np.eye(4)
    pose[:3, 3] = a
    turned = pose.copy()
    turned[:3, :3] = _exp3([0.0, 0.0, 2.0])
    poses = swarm_ik.IKProblem(r, goals=[G.Pose(f, pose), G.Pose(f, turned)])
    assert conflicting_goals(poses, 1e-5, 1e-5) is not None
    free = swarm_ik.IKProblem(r, goals=[G.Pose(f, pose, tolerance=Z_FREE), G.Pose(f, turned)])
    assert conflicting_goals(free, 1e-5, 1e-5) is None


# ----------------------------------------------------------------------- input
BAD = {
    "negative": (
        {"tolerance": [0.01, -0.01, 0, 0, 0, 0]},
        "Pose.tolerance must be finite and >= 0",
    ),
    "nan": ({"tolerance": [0.01, float("nan"), 0, 0, 0, 0]}, "Pose.tolerance must be finite"),
    "inf": ({"tolerance": [float("inf"), 0, 0, 0, 0, 0]}, "Pose.tolerance must be finite"),
    "five": ({"tolerance": [0.01, 0.01, 0.01, 0.1, 0.1]}, "Pose.tolerance must be 6 numbers"),
    "seven": ({"tolerance": [0.0] * 7}, "Pose.tolerance must be 6 numbers"),
    "nested": ({"tolerance": [[0.0] * 6]}, "Pose.tolerance must be 6 numbers"),
    "text": ({"tolerance": "0.01"}, "Pose.tolerance must be 6 numbers"),
    "words": ({"tolerance": ["a"] * 6}, "Pose.tolerance must be 6 numbers"),
    "over pi": ({"tolerance": [0, 0, 0, 0, 0, 3.2]}, "Pose.tolerance: rotation bounds"),
    "radius negative": ({"radius": -0.1}, "Position.radius must be a finite number >= 0"),
    "radius nan": ({"radius": float("nan")}, "Position.radius"),
    "radius inf": ({"radius": float("inf")}, "Position.radius"),
    "radius text": ({"radius": "1"}, "Position.radius"),
    "radius bool": ({"radius": True}, "Position.radius"),
    "radius list": ({"radius": [0.1]}, "Position.radius"),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_bounds_are_refused_naming_the_field(case: str) -> None:
    extra, message = BAD[case]
    if "radius" in extra:
        data = {"type": "Position", "frame": "panda_hand_tcp", "point": [0.5, 0, 0.3], **extra}
    else:
        data = {"type": "Pose", "frame": "panda_hand_tcp", "target": np.eye(4).tolist(), **extra}
    with pytest.raises(swarm_ik.InvalidArgumentError, match=message):
        G.goal_from_dict(data)
    kind = G.Pose if data["type"] == "Pose" else G.Position
    args = ("panda_hand_tcp", np.eye(4) if kind is G.Pose else [0.5, 0, 0.3])
    with pytest.raises(swarm_ik.InvalidArgumentError, match=message):
        kind(*args, **extra)


def test_bounds_at_their_limits_are_accepted() -> None:
    pose = np.eye(4)
    goal = G.Pose("panda_hand_tcp", pose, tolerance=np.array([0, 0, 0, math.pi, 0, np.pi]))
    assert goal.tolerance == (0.0, 0.0, 0.0, math.pi, 0.0, math.pi)
    assert all(type(x) is float for x in goal.tolerance)
    assert G.Position("panda_hand_tcp", [0, 0, 0], radius=0).radius == 0.0
    with pytest.raises(swarm_ik.InvalidArgumentError, match="positional"):
        G.Pose("panda_hand_tcp", pose, 1e-6, BOX)  # keyword-only  # type: ignore[misc]
    with pytest.raises(swarm_ik.InvalidArgumentError, match="positional"):
        G.Position("panda_hand_tcp", [0, 0, 0], 0.1)  # type: ignore[misc]


def test_json_round_trip_of_the_bounded_goals() -> None:
    r = robot("panda")
    pose = r.fk(r.mid_q())
    goals = [
        G.Pose(r.ee_frame, pose, tolerance=Z_FREE),
        G.Pose(r.ee_frame, pose, tolerance=BOX, weight=2.0),
        G.Pose(r.ee_frame, pose),
        G.Position(r.ee_frame, pose[:3, 3], radius=0.05),
        G.Position(r.ee_frame, pose[:3, 3]),
    ]
    text = json.dumps([G.goal_to_dict(g) for g in goals])
    back = G.load_goals(json.loads(text))
    for a, b in zip(goals, back, strict=True):
        assert type(a) is type(b)
        assert getattr(a, "tolerance", None) == getattr(b, "tolerance", None)
        assert getattr(a, "radius", None) == getattr(b, "radius", None)
        assert a.weight == b.weight
    assert json.loads(text)[0]["tolerance"] == list(Z_FREE)
    assert json.loads(text)[2]["tolerance"] is None
    quat = {
        "type": "Pose",
        "frame": r.ee_frame,
        "target": {"position": [0.4, 0, 0.4], "quaternion": [1, 0, 0, 0]},
        "tolerance": [0.001, 0.001, 0.001, 0, 0, math.pi],
    }
    assert G.goal_from_dict(quat).tolerance[5] == math.pi
    ball = {"type": "Position", "frame": r.ee_frame, "point": [0.4, 0, 0.4], "radius": 0.01}
    assert G.goal_from_dict(ball).radius == 0.01
