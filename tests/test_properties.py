"""Property-based tests over random serial chains (hypothesis).

A chain has 1-9 joints, each revolute, prismatic or continuous, with a random origin (xyz, rpy),
a random axis (often a signed coordinate axis, otherwise any unit vector), random limits
(sometimes of zero width), optional fixed joints in between and an optional side branch that
must be locked off the chain.  It is written to URDF and loaded like any user's file.

The number of examples comes from the hypothesis profile (``tests/conftest.py`` loads "ci": 15
examples, no deadline); the solver-sweep test runs a third of them, as it calls every solver.
"""

from __future__ import annotations

import math
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import swarm_ik
from swarm_ik.api import DEFAULT_SOLVER
from swarm_ik.fitness import FITNESS
from swarm_ik.problem import largest_errors

KINDS = ("revolute", "prismatic", "continuous")
N_EXAMPLES = settings().max_examples  # from the loaded profile


@dataclass(frozen=True)
class JointSpec:
    kind: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]
    axis: tuple[float, float, float]
    lower: float
    upper: float
    fixed_before: bool


@dataclass(frozen=True)
class ChainSpec:
    joints: tuple[JointSpec, ...]
    tool_xyz: tuple[float, float, float]
    tool_rpy: tuple[float, float, float]
    branch_at: int | None


def _vec(lo: float, hi: float) -> st.SearchStrategy[tuple[float, float, float]]:
    f = st.floats(lo, hi, allow_nan=False, allow_infinity=False)
    return st.tuples(f, f, f)


_AXES = [tuple(float(v) for v in s * np.eye(3)[i]) for i in range(3) for s in (1, -1)]


@st.composite
def _axis(draw: st.DrawFn) -> tuple[float, float, float]:
    if draw(st.booleans()):
        return draw(st.sampled_from(_AXES))  # type: ignore[return-value]
    v = np.array(draw(_vec(-1.0, 1.0)))
    n = float(np.linalg.norm(v))
    if n < 0.1:
        return (0.0, 0.0, 1.0)
    return tuple(float(x) for x in v / n)  # type: ignore[return-value]


@st.composite
def _joint(draw: st.DrawFn) -> JointSpec:
    kind = draw(st.sampled_from(KINDS))
    if kind == "prismatic":
        lo = draw(st.floats(-0.5, 0.0))
        hi = draw(st.floats(0.01, 0.5))
    else:
        lo = draw(st.floats(-math.pi, -0.05))
        hi = draw(st.floats(0.05, math.pi))
    if kind != "continuous" and draw(st.integers(0, 7)) == 0:
        hi = lo  # a zero-width range: a joint locked by its limits
    return JointSpec(
        kind=kind,
        xyz=draw(_vec(-0.4, 0.4)),
        rpy=draw(_vec(-math.pi, math.pi)),
        axis=draw(_axis()),
        lower=lo,
        upper=hi,
        fixed_before=draw(st.integers(0, 4)) == 0,
    )


@st.composite
def chains(draw: st.DrawFn, max_joints: int = 9) -> ChainSpec:
    """Random serial chains of 1 to ``max_joints`` joints."""
    joints = tuple(draw(st.lists(_joint(), min_size=1, max_size=max_joints)))
    branch = draw(st.one_of(st.none(), st.integers(0, len(joints) - 1)))
    return ChainSpec(joints, draw(_vec(-0.2, 0.2)), draw(_vec(-math.pi, math.pi)), branch)


def chain_urdf(spec: ChainSpec) -> str:
    """URDF text of a chain: base -> j0 -> ... -> tool (numbers written with full precision)."""

    def f(v: tuple[float, ...]) -> str:
        return " ".join(repr(float(x)) for x in v)

    out = ['<?xml version="1.0"?>', '<robot name="random_chain">', '  <link name="base"/>']
    parent = "base"
    for i, j in enumerate(spec.joints):
        if j.fixed_before:
            out.append(f'  <link name="fx{i}"/>')
            out.append(
                f'  <joint name="fixed{i}" type="fixed"><parent link="{parent}"/>'
                f'<child link="fx{i}"/><origin xyz="0 0 0.05" rpy="0 0 0.3"/></joint>'
            )
            parent = f"fx{i}"
        limit = (
            ""
            if j.kind == "continuous"
            else f'<limit lower="{j.lower!r}" upper="{j.upper!r}" effort="1" velocity="1"/>'
        )
        out.append(f'  <link name="l{i}"/>')
        out.append(
            f'  <joint name="j{i}" type="{j.kind}"><parent link="{parent}"/><child link="l{i}"/>'
            f'<origin xyz="{f(j.xyz)}" rpy="{f(j.rpy)}"/><axis xyz="{f(j.axis)}"/>{limit}</joint>'
        )
        if spec.branch_at == i:  # a side branch off the chain (locked when loading)
            out.append(f'  <link name="side{i}"/>')
            out.append(
                f'  <joint name="side_j{i}" type="revolute"><parent link="{parent}"/>'
                f'<child link="side{i}"/><origin xyz="0.1 0 0"/><axis xyz="1 0 0"/>'
                '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
            )
        parent = f"l{i}"
    out.append('  <link name="tool"/>')
    out.append(
        f'  <joint name="tool_joint" type="fixed"><parent link="{parent}"/><child link="tool"/>'
        f'<origin xyz="{f(spec.tool_xyz)}" rpy="{f(spec.tool_rpy)}"/></joint>'
    )
    out.append("</robot>")
    return "\n".join(out)


def load_chain(spec: ChainSpec) -> swarm_ik.RobotModel:
    """Write the chain to a temporary URDF and load it as a user would."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "chain.urdf"
        path.write_text(chain_urdf(spec))
        return swarm_ik.load_robot(path, ee_frame="tool")


def _rng(seed: int) -> np.random.Generator:
    return np.random.default_rng(seed)


SEEDS = st.integers(0, 2**32 - 1)


# ------------------------------------------------------------------------------ the model
@given(spec=chains(), seed=SEEDS)
def test_chain_is_read_back_as_written(spec: ChainSpec, seed: int) -> None:
    robot = load_chain(spec)
    assert robot.nq == len(spec.joints)
    assert robot.joint_names == tuple(f"j{i}" for i in range(len(spec.joints)))
    assert robot.joint_kinds == tuple(j.kind for j in spec.joints)
    lower = [-math.pi if j.kind == "continuous" else j.lower for j in spec.joints]
    upper = [math.pi if j.kind == "continuous" else j.upper for j in spec.joints]
    np.testing.assert_array_equal(robot.lower, lower)
    np.testing.assert_array_equal(robot.upper, upper)
    if spec.branch_at is not None:
        assert robot.locked_joints == (f"side_j{spec.branch_at}",)
    q = robot.random_q(_rng(seed))
    assert robot.within_limits(q)
    back = robot.from_pinocchio(robot.to_pinocchio(q))  # continuous: through (cos, sin)
    np.testing.assert_allclose(robot.wrap(back - q), 0.0, atol=1e-12)


@given(spec=chains(), seed=SEEDS)
def test_batched_fk_and_jacobian_equal_pinocchio(spec: ChainSpec, seed: int) -> None:
    robot = load_chain(spec)
    rng = _rng(seed)
    q_batch = robot.random_q(rng, 8)
    q_batch[0] = robot.lower
    q_batch[1] = robot.upper
    poses, jacs = robot.fk_jacobian(q_batch)
    np.testing.assert_array_equal(robot.fk(q_batch), poses)
    for q, pose, jac in zip(q_batch, poses, jacs, strict=True):
        np.testing.assert_allclose(pose, robot.fk_pinocchio(q), rtol=0, atol=1e-12)
        np.testing.assert_allclose(jac, robot.jacobian_pinocchio(q), rtol=0, atol=1e-12)
        # one q: Pinocchio's FK (nothing to compile), within 1e-12 of the batch of one
        np.testing.assert_allclose(robot.fk(q), pose, rtol=0, atol=1e-12)


# ---------------------------------------------------------------------------- the fitness
@given(spec=chains(), seed=SEEDS)
def test_fitness_is_zero_at_fk_of_q_and_positive_elsewhere(spec: ChainSpec, seed: int) -> None:
    robot = load_chain(spec)
    rng = _rng(seed)
    q = robot.random_q(rng)
    others = robot.random_q(rng, 6)
    poses = robot.fk(others)
    target = robot.fk(q)
    moved = np.abs(poses - target).max(axis=(1, 2)) > 1e-9
    for name in FITNESS:
        problem = swarm_ik.IKProblem.from_q(robot, q, name)
        assert problem.fitness(q[None])[0] == pytest.approx(0.0, abs=1e-12), name
        f = problem.fitness(others)
        assert f.shape == (6,) and np.all(np.isfinite(f)) and np.all(f >= 0), name
        assert np.all(f[moved] > 0), (name, f, moved)
    # Pinocchio agrees that FK(q) is reached exactly
    dp, dr = largest_errors(swarm_ik.verify(swarm_ik.IKProblem.from_q(robot, q), q))
    assert dp <= 1e-12 and dr <= 1e-7


def _zyz_singular(poses: np.ndarray) -> np.ndarray:
    """Whether the ZYZ angle β of poses ``(..., 4, 4)`` is exactly 0 or π."""
    return np.hypot(poses[..., 2, 0], poses[..., 2, 1]) == 0.0


def test_euler_zyz_fitness_sees_a_yaw_error_at_its_singularity() -> None:
    # found by the property test above: at β = 0 or π the ZYZ split of the yaw is arbitrary
    # a tool pointing straight down (β = π), as a top-down grasp target: turning it about the
    # vertical axis must cost something
    down = swarm_ik.make_pose([0.3, 0.0, 0.2], [1.0, 0.0, 0.0, 0.0])
    turned = swarm_ik.make_pose([0.3, 0.0, 0.2], [np.cos(0.25), np.sin(0.25), 0.0, 0.0])
    assert _zyz_singular(down) and _zyz_singular(turned)
    assert FITNESS["euler-zyz"](turned[None], down)[0] > 0.4  # a 0.5 rad yaw error
    up = np.eye(4)  # β = 0
    yawed = swarm_ik.make_pose([0.0, 0.0, 0.0], [0.0, 0.0, np.sin(0.25), np.cos(0.25)])
    assert FITNESS["euler-zyz"](yawed[None], up)[0] > 0.4


# ------------------------------------------------------------------------------ the solvers
@settings(max_examples=max(3, N_EXAMPLES // 3), suppress_health_check=[HealthCheck.too_slow])
@given(spec=chains(), seed=SEEDS, fitness=st.sampled_from(sorted(FITNESS)), reach=st.booleans())
def test_every_solver_result_lies_within_limits(
    spec: ChainSpec, seed: int, fitness: str, reach: bool
) -> None:
    robot = load_chain(spec)
    rng = _rng(seed)
    if reach:
        target = robot.fk(robot.random_q(rng))
    else:  # any pose, usually out of reach
        target = swarm_ik.make_pose(rng.uniform(-2, 2, 3), rng.normal(size=4))
    problem = swarm_ik.IKProblem(robot, target, fitness)
    for name in swarm_ik.solvers.search_names():
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            res = swarm_ik.solve(problem, name, seed=seed, max_evals=300)
        assert res.within_limits, (name, res)
        assert np.all(res.q >= robot.lower) and np.all(res.q <= robot.upper), (name, res)
        assert np.all(np.isfinite(res.q)) and np.isfinite(res.fitness), (name, res)
        assert 0 < res.n_evals <= 300, (name, res)


@pytest.mark.parametrize("name", swarm_ik.solvers.search_names())
def test_every_solver_on_one_joint(name: str) -> None:
    # found by the property test above: eigenpy returns a (6, 1) Jacobian as a (6,) vector,
    # which crashed dls on one-joint chains
    spec = ChainSpec(
        (
            JointSpec(
                "revolute", (0.0, 0.0, 0.1), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), -2.0, 2.0, False
            ),
        ),
        (0.5, 0.0, 0.0),
        (0.0, 0.0, 0.0),
        None,
    )
    robot = load_chain(spec)
    for w_rot in (1.0, 0.0):  # full pose, and position only
        problem = swarm_ik.IKProblem.from_q(robot, [1.0], w_rot=w_rot)
        res = swarm_ik.solve(problem, name, seed=0, max_evals=300)
        assert res.within_limits and np.isfinite(res.fitness) and 0 < res.n_evals <= 300


@given(spec=chains(), seed=SEEDS)
def test_default_solver_solves_fk_targets(spec: ChainSpec, seed: int) -> None:
    # FK-sampled targets are reachable exactly, whatever the number of joints (< 6 included)
    robot = load_chain(spec)
    q = robot.random_q(_rng(seed))
    problem = swarm_ik.IKProblem.from_q(robot, q)
    res = swarm_ik.solve(problem, seed=seed, max_evals=20000)
    assert res.solver == DEFAULT_SOLVER
    assert res.success, (robot, q.tolist(), res)
    assert res.position_error <= 1e-5 and res.rotation_error <= 1e-5 and res.within_limits
