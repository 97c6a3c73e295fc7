"""Bad input is refused with a clear message; degenerate targets give an honest Result.

Every bad input listed in ``docs/robustness.md`` has a test here.  Bad URDFs are written to
``tmp_path``; no test data files are needed.
"""

from __future__ import annotations

import json
import re
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import FROM_Q, cli_error, cli_json, timed, urdf_joint, urdf_text
from conftest import URDF_LIMIT as LIMIT

import swarm_ik
from swarm_ik import IKProblem, errors
from swarm_ik.cli import main
from swarm_ik.fitness import FITNESS
from swarm_ik.solvers import base

SOLVERS = swarm_ik.solvers.search_names()
POP_SOLVERS = [n for n in SOLVERS if "pop_size" in base.get(n).params]
ITER_SOLVERS = [n for n in SOLVERS if "iterations" in base.get(n).params]

GOOD = urdf_text("a b c", ("j1", "a", "b"), ("j2", "b", "c"))

BAD_URDFS: dict[str, tuple[str, str]] = {
    # id: (file text, regex the message must match)
    "empty file": ("", r"not a valid XML file"),
    "not XML": ("this is <<< not xml", r"not a valid XML file"),
    "XML but not URDF": ("<sdf><model/></sdf>", r"not a URDF \(root element is <sdf>"),
    "loop (cycle)": (
        urdf_text("a b c", ("j1", "a", "b"), ("j2", "b", "c"), ("j3", "c", "a")),
        r"exactly one root link, found none \(a loop",
    ),
    "loop (two parents)": (
        urdf_text("a b c", ("j1", "a", "b"), ("j2", "b", "c"), ("j3", "a", "c")),
        r"link 'c' is the child of two joints \(a kinematic loop\)",
    ),
    "missing parent link": (
        urdf_text("a b", ("j1", "nowhere", "b")),
        r"joint 'j1' names parent link 'nowhere', which is not defined",
    ),
    "missing child element": (
        urdf_text(
            "a b", '<joint name="j1" type="revolute"><parent link="a"/>' + LIMIT + "</joint>"
        ),
        r"joint 'j1' names child link None",
    ),
    "two root links": (
        urdf_text("a b c", ("j1", "a", "b")),
        r"exactly one root link, found \['a', 'c'\]",
    ),
    "unknown joint type": (
        urdf_text("a b", ("j1", "a", "b", "screw")),
        r"joint 'j1' has unknown type 'screw'; valid types: revolute, continuous, prismatic",
    ),
    "NaN limit": (
        urdf_text("a b", urdf_joint("j1", "a", "b", limit=LIMIT.replace('"-1"', '"nan"'))),
        r"joint 'j1' has non-finite limits \[nan, 1.0\]",
    ),
    "inf limit": (
        urdf_text(
            "a b", urdf_joint("j1", "a", "b", "prismatic", limit=LIMIT.replace('"1"', '"inf"', 1))
        ),
        r"joint 'j1' has non-finite limits",
    ),
    "lower > upper": (
        urdf_text("a b", urdf_joint("j1", "a", "b", limit=LIMIT.replace('"-1"', '"2"'))),
        r"joint 'j1' has lower limit 2.0 > upper limit 1.0",
    ),
    "non-numeric limit": (
        urdf_text("a b", urdf_joint("j1", "a", "b", limit=LIMIT.replace('"-1"', '"abc"'))),
        r"joint 'j1' has non-numeric limits \['abc', '1'\]",
    ),
    "revolute without limit": (
        urdf_text("a b", urdf_joint("j1", "a", "b", limit="")),
        r"revolute joint 'j1' has no <limit.*use type 'continuous'",
    ),
    "no movable joint (fixed only)": (
        urdf_text("a b", urdf_joint("j1", "a", "b", "fixed", limit="")),
        r"no movable joint between the root and frame 'b'",
    ),
    "no joint at all": (urdf_text("a"), r"no movable joint between the root and frame 'a'"),
    "no link at all": (urdf_text(""), r"the URDF is empty: <robot name=.bad.> defines no <link>"),
    "zero axis": (
        urdf_text("a b", urdf_joint("j1", "a", "b", axis='<axis xyz="0 0 0"/>')),
        r"joint 'j1' has a zero axis",
    ),
    "NaN axis": (
        urdf_text("a b", urdf_joint("j1", "a", "b", axis='<axis xyz="nan 0 1"/>')),
        r"joint 'j1': <axis xyz='nan 0 1'> must be 3 finite numbers",
    ),
    "malformed origin": (
        urdf_text("a b", urdf_joint("j1", "a", "b", origin='<origin xyz="0 0"/>')),
        r"joint 'j1': <origin xyz='0 0'> must be 3 finite numbers",
    ),
    "duplicate joint name": (
        urdf_text("a b c", ("j1", "a", "b"), ("j1", "b", "c")),
        r"joint name\(s\) \['j1'\] defined more than once",
    ),
    "duplicate link name": (
        urdf_text("a a b", ("j1", "a", "b")),
        r"link name\(s\) \['a'\] defined more than once",
    ),
    "floating joint on the chain": (
        urdf_text("a b c", urdf_joint("j0", "a", "b", "floating", limit=""), ("j1", "b", "c")),
        r"joint 'j0' on the chain to 'c': .*not supported.*supported: revolute, continuous",
    ),
    "planar joint on the chain": (
        urdf_text("a b c", urdf_joint("j0", "a", "b", "planar", limit=""), ("j1", "b", "c")),
        r"joint 'j0' on the chain to 'c': .*Planar.*not supported",
    ),
}


def _write(tmp_path: Path, text: str, name: str = "robot.urdf") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# ------------------------------------------------------------------------- error hierarchy
@pytest.mark.parametrize(
    ("cls", "builtin"),
    [
        (errors.RobotFileNotFoundError, FileNotFoundError),
        (errors.RobotModelError, ValueError),
        (errors.UnknownNameError, KeyError),
        (errors.InvalidTargetError, ValueError),
        (errors.InvalidArgumentError, ValueError),
    ],
)
def test_every_error_is_a_swarmik_error_and_its_builtin(cls: type, builtin: type) -> None:
    assert issubclass(cls, errors.SwarmIKError) and issubclass(cls, builtin)
    assert getattr(swarm_ik, cls.__name__) is cls


def test_unknown_name_error_prints_its_message_not_a_repr() -> None:
    err = swarm_ik.errors.unknown("fitness", "l2", FITNESS)
    # KeyError would print "'unknown fitness ...'" with quotes; the plural is spelled right
    assert str(err) == "unknown fitness 'l2'; valid fitnesses: euler-zyz, paper-l1, paper-pso, se3"


# ------------------------------------------------------------------------------- URDF files
@pytest.mark.parametrize("case", list(BAD_URDFS))
def test_bad_urdf_is_refused_with_a_message_naming_the_problem(
    case: str, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    text, message = BAD_URDFS[case]
    path = _write(tmp_path, text)
    with pytest.raises(errors.RobotModelError, match=message) as info:
        swarm_ik.RobotModel.from_urdf(path)
    assert str(path) in str(info.value)  # the message names the file
    # the user sees one message: nothing printed by urdfdom / Pinocchio on the side
    assert capfd.readouterr().err == ""
    # load_robot (the entry point of the CLI) refuses it the same way
    with pytest.raises(errors.RobotModelError, match=message):
        swarm_ik.load_robot(path)


def test_the_valid_reference_urdf_loads(tmp_path: Path) -> None:
    # the bad cases above are small edits of this file: make sure the base itself is fine
    robot = swarm_ik.RobotModel.from_urdf(_write(tmp_path, GOOD))
    assert robot.nq == 2 and robot.ee_frame == "c"
    np.testing.assert_array_equal(robot.lower, [-1.0, -1.0])


def test_mimic_joint_off_the_chain_is_accepted(tmp_path: Path) -> None:
    # a gripper finger mimicking another one is locked (off the chain): no reason to refuse
    text = urdf_text(
        "a b c f1 f2",
        ("j1", "a", "b"),
        ("j2", "b", "c"),
        ("finger1", "c", "f1", "prismatic"),
        urdf_joint("finger2", "c", "f2", "prismatic", extra='<mimic joint="finger1"/>'),
    )
    robot = swarm_ik.RobotModel.from_urdf(_write(tmp_path, text), ee_frame="c")
    assert robot.joint_names == ("j1", "j2")
    assert set(robot.locked_joints) == {"finger1", "finger2"}


def test_missing_file_is_refused(tmp_path: Path) -> None:
    missing = tmp_path / "nothere.urdf"
    with pytest.raises(errors.RobotFileNotFoundError, match=r"URDF file not found: .*nothere.urdf"):
        swarm_ik.RobotModel.from_urdf(missing)
    with pytest.raises(FileNotFoundError, match="nothere.urdf"):  # the built-in still catches
        swarm_ik.load_robot(str(missing))


def test_a_path_that_is_not_a_regular_file_is_refused_as_such(tmp_path: Path) -> None:
    """A folder or a device as the URDF is not "not found": the message says what it is."""
    for path in (tmp_path, Path("/dev/null")):
        with pytest.raises(errors.RobotModelError, match="is not a regular file"):
            swarm_ik.load_robot(str(path))


def test_unknown_robot_name_lists_the_robots() -> None:
    with pytest.raises(errors.UnknownNameError) as info:
        swarm_ik.load_robot("yumi")
    msg = str(info.value)
    assert msg.startswith("unknown robot 'yumi'; did you mean 'yumi_left'? valid robots: ")
    for name in ("yumi_left", "loading_manipulator", "panda", "ur5"):
        assert name in msg


def test_unknown_end_effector_frame_lists_the_frames(tmp_path: Path) -> None:
    with pytest.raises(errors.UnknownNameError) as info:
        swarm_ik.RobotModel.from_urdf(_write(tmp_path, GOOD), ee_frame="tool1")
    assert str(info.value) == "unknown frame 'tool1'; valid frames: a, b, c"
    with pytest.raises(KeyError):  # a built-in KeyError too
        swarm_ik.load_robot("yumi_left", ee_frame="tool1")


# ----------------------------------------------------------------------------------- targets
@pytest.fixture(scope="module")
def yumi() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot("yumi_left")


def _pose_with(change: object) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, 3] = [0.3, 0.1, 0.4]
    change(pose)  # type: ignore[operator]
    return pose


BAD_TARGETS: dict[str, tuple[object, str]] = {
    "NaN in the matrix": (
        _pose_with(lambda p: p.__setitem__((0, 3), np.nan)),
        r"NaN or infinite values at \(row, column\) \[\(0, 3\)\]",
    ),
    "inf in the matrix": (
        _pose_with(lambda p: p.__setitem__((1, 1), np.inf)),
        r"NaN or infinite values",
    ),
    "3x3 matrix": (np.eye(3), r"4x4 matrix.*got shape \(3, 3\)"),
    "3 numbers": ([0.1, 0.2, 0.3], r"got shape \(3,\)"),
    "None": (None, r"got None"),
    "a string": ("abc", r"target must be numbers, got 'abc'"),
    "strings in a matrix": ([["a"] * 4] * 4, r"target must be numbers"),
    "scaled rotation (not orthonormal)": (
        _pose_with(lambda p: p.__setitem__((slice(0, 3), slice(0, 3)), 1.01 * np.eye(3))),
        r"not orthonormal: max\|RᵀR − I\| = 0.0201.*tolerance 1e-06.*project_to_se3",
    ),
    "reflection (det -1)": (
        _pose_with(lambda p: p.__setitem__((2, 2), -1.0)),
        r"not orthonormal: .*det = -1",
    ),
    "bottom row not 0 0 0 1": (
        _pose_with(lambda p: p.__setitem__((3, 2), 1.0)),
        r"bottom row must be \[0, 0, 0, 1\]",
    ),
    "zero quaternion": (([0.3, 0.1, 0.4], [0, 0, 0, 0]), r"quaternion has zero norm"),
    "zero quaternion (7 numbers)": ([0.3, 0.1, 0.4, 0, 0, 0, 0], r"quaternion has zero norm"),
    "NaN in the quaternion": (
        ([0.3, 0.1, 0.4], [0, 0, np.nan, 1]),
        r"quaternion must be 4 finite numbers",
    ),
    "3-number quaternion": (([0.3, 0.1, 0.4], [0, 0, 1]), r"quaternion must be 4 finite numbers"),
    "2-number position": (([0.3, 0.1], [0, 0, 0, 1]), r"position must be 3 finite numbers"),
    "NaN in the position": (
        ([0.3, np.nan, 0.4], [0, 0, 0, 1]),
        r"position must be 3 finite numbers",
    ),
}


@pytest.mark.parametrize("case", list(BAD_TARGETS))
def test_bad_target_is_refused(case: str, yumi: swarm_ik.RobotModel) -> None:
    target, message = BAD_TARGETS[case]
    with pytest.raises(errors.InvalidTargetError, match=message):
        IKProblem(yumi, target)


def test_rotation_within_tolerance_is_accepted_and_beyond_is_refused(
    yumi: swarm_ik.RobotModel,
) -> None:
    pose = yumi.fk(yumi.mid_q())
    slightly = pose.copy()
    slightly[:3, :3] *= 1 + 1e-8  # a rounded matrix: within the default tolerance 1e-6
    IKProblem(yumi, slightly)
    rounded = np.round(pose, 3)  # printed with 3 decimals, as the [HLFOA] paper's target
    with pytest.raises(errors.InvalidTargetError, match="not orthonormal"):
        IKProblem(yumi, rounded)
    IKProblem(yumi, rounded, orth_tol=1e-2)  # the user may raise the tolerance...
    fixed = swarm_ik.project_to_se3(rounded)  # ...or project the matrix onto SE(3)
    np.testing.assert_allclose(fixed[:3, :3].T @ fixed[:3, :3], np.eye(3), atol=1e-12)
    IKProblem(yumi, fixed)
    for bad in (np.nan, -1.0, "1e-3"):
        with pytest.raises(errors.InvalidArgumentError, match="orth_tol must be a finite"):
            IKProblem(yumi, pose, orth_tol=bad)  # type: ignore[arg-type]


# --------------------------------------------------------------------- problem arguments
def test_bad_problem_arguments_are_refused(yumi: swarm_ik.RobotModel) -> None:
    pose = yumi.fk(yumi.mid_q())
    with pytest.raises(
        errors.UnknownNameError, match="unknown fitness 'l2'; valid fitnesses: euler-zyz"
    ):
        IKProblem(yumi, pose, fitness="l2")
    with pytest.raises(errors.UnknownNameError, match=r"unknown fitness \['se3'\]"):
        IKProblem(yumi, pose, fitness=["se3"])  # type: ignore[arg-type]
    for label in ("w_rot", "lam", "mu"):
        for bad in (-1.0, np.nan, np.inf, "a", None):
            with pytest.raises(
                errors.InvalidArgumentError, match=f"{label} must be a finite non-neg"
            ):
                IKProblem(yumi, pose, **{label: bad})  # type: ignore[arg-type]
    with pytest.raises(errors.InvalidArgumentError, match="robot must be a RobotModel"):
        IKProblem("yumi_left", pose)  # type: ignore[arg-type]
    with pytest.raises(errors.InvalidArgumentError, match="lower bounds exceed upper bounds"):
        IKProblem(yumi, pose, lower=yumi.mid_q() + 0.1, upper=yumi.mid_q())
    with pytest.raises(
        errors.InvalidArgumentError, match="bounds may only narrow the joint limits; joint"
    ):
        IKProblem(yumi, pose, lower=yumi.lower - 1.0)
    with pytest.raises(errors.InvalidArgumentError, match="upper must hold 7 values"):
        IKProblem(yumi, pose, upper=[1.0, 2.0])


# ---------------------------------------------------------------------- solve arguments
@pytest.fixture(scope="module")
def problem(yumi: swarm_ik.RobotModel) -> IKProblem:
    return IKProblem(yumi, yumi.fk(yumi.mid_q() + 0.2))


def test_unknown_solver_lists_every_solver(problem: IKProblem) -> None:
    with pytest.raises(errors.UnknownNameError) as info:
        swarm_ik.solve(problem, "abc")
    every = ", ".join(swarm_ik.solvers.names())
    assert str(info.value) == f"unknown solver 'abc'; valid solvers: {every}"
    with pytest.raises(errors.UnknownNameError, match="unknown solver"):
        swarm_ik.solve(problem, ["dls"])  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("q0", "message"),
    [
        ([0.0, 0.0], r"q0 must hold 7 values \(one per joint: yumi_joint_1, .*got shape \(2,\)"),
        (np.zeros((7, 1)), r"q0 must hold 7 values .*got shape \(7, 1\)"),
        ([np.nan] * 7, r"q0 contains NaN or infinite values"),
        ([0, 0, 0, np.inf, 0, 0, 0], r"q0 contains NaN or infinite values"),
        ("abc", r"q0 must be 7 numbers \(one per joint\), got 'abc'"),
    ],
)
def test_bad_q0_is_refused(problem: IKProblem, q0: object, message: str) -> None:
    with pytest.raises(errors.InvalidArgumentError, match=message):
        swarm_ik.solve(problem, "dls", q0=q0, max_evals=10)


def test_q0_outside_the_limits_is_clipped_with_a_warning(
    problem: IKProblem, yumi: swarm_ik.RobotModel
) -> None:
    q0 = yumi.mid_q().copy()
    q0[1] = yumi.upper[1] + 0.5
    q0[4] = yumi.lower[4] - 2.0
    given = q0.copy()
    with pytest.warns(
        UserWarning,
        match=r"q0 lies outside the joint limits at \['yumi_joint_2', "
        r"'yumi_joint_5'\]; clipped into them",
    ):
        # one evaluation: dls's first point is the (clipped) start itself
        res = swarm_ik.solve(problem, "dls", q0=q0, max_evals=1)
    np.testing.assert_array_equal(res.q, np.clip(q0, yumi.lower, yumi.upper))
    assert res.within_limits and res.n_evals == 1
    np.testing.assert_array_equal(q0, given)  # the caller's array is not modified
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a q0 within the limits: no warning
        swarm_ik.solve(problem, "dls", q0=yumi.mid_q(), max_evals=1)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"max_evals": 0}, r"max_evals must be a positive integer, got 0"),
        ({"max_evals": -5}, r"max_evals must be a positive integer, got -5"),
        ({"max_evals": 1.5}, r"max_evals must be a positive integer, got 1.5"),
        ({"max_evals": True}, r"max_evals must be a positive integer, got True"),
        ({"time_limit": 0}, r"time_limit must be a positive number of seconds, got 0"),
        ({"time_limit": -1.0}, r"time_limit must be a positive number of seconds, got -1.0"),
        ({"time_limit": float("nan")}, r"time_limit must be a positive number of seconds"),
        ({"time_limit": float("inf")}, r"time_limit must be a positive number of seconds"),
        ({"time_limit": "1"}, r"time_limit must be a positive number of seconds, got '1'"),
        ({"seed": -1}, r"seed must be in \[0, 2\*\*63\), got -1"),
        ({"seed": 1.5}, r"seed must be a non-negative integer, got 1.5"),
        ({"seed": "7"}, r"seed must be a non-negative integer, got '7'"),
        ({"tol_pos": 0.0}, r"tol_pos must be a positive number, got 0.0"),
        ({"tol_rot": -1e-3}, r"tol_rot must be a positive number"),
    ],
)
def test_bad_budget_seed_or_tolerance_is_refused(
    problem: IKProblem, kwargs: dict[str, object], message: str
) -> None:
    with pytest.raises(errors.InvalidArgumentError, match=message):
        swarm_ik.solve(problem, "gwo", **kwargs)  # type: ignore[arg-type]


def test_problem_must_be_an_ikproblem(yumi: swarm_ik.RobotModel) -> None:
    with pytest.raises(
        errors.InvalidArgumentError, match="problem must be an IKProblem, got ndarray"
    ):
        swarm_ik.solve(yumi.fk(yumi.mid_q()))  # type: ignore[arg-type]


@pytest.mark.parametrize("name", POP_SOLVERS)
def test_population_below_four_is_refused_for_every_population_solver(
    name: str, problem: IKProblem
) -> None:
    for bad in (3, 0, -1):
        with pytest.raises(errors.InvalidArgumentError, match=rf"pop_size must be >= 4 .*{name!r}"):
            swarm_ik.solve(problem, name, pop_size=bad, max_evals=50)
    for bad in (4.5, 1e9, "8", True):  # (1e9 was "must be >= 4": it is; it is not an integer)
        with pytest.raises(
            errors.InvalidArgumentError, match=rf"pop_size must be an integer .*{name!r}, got"
        ):
            swarm_ik.solve(problem, name, pop_size=bad, max_evals=50)
    res = swarm_ik.solve(problem, name, pop_size=4, max_evals=50)  # the smallest one runs
    assert 0 < res.n_evals <= 50 and res.within_limits


@pytest.mark.parametrize("name", ITER_SOLVERS)
def test_non_positive_iterations_are_refused(name: str, problem: IKProblem) -> None:
    for bad in (0, -3):
        with pytest.raises(
            errors.InvalidArgumentError, match=rf"iterations must be >= 1 .*{name!r}"
        ):
            swarm_ik.solve(problem, name, iterations=bad)
    with pytest.raises(
        errors.InvalidArgumentError, match=rf"iterations must be an integer .*{name!r}"
    ):
        swarm_ik.solve(problem, name, iterations=2.5)


@pytest.mark.parametrize("name", SOLVERS)
def test_unknown_solver_parameter_lists_the_valid_ones(name: str, problem: IKProblem) -> None:
    with pytest.raises(errors.InvalidArgumentError) as info:
        swarm_ik.solve(problem, name, popsize=10, max_evals=10)
    msg = str(info.value)
    valid = ", ".join(sorted(base.get(name).params)) or "(none)"
    assert msg == f"unknown parameter(s) 'popsize' for solver {name!r}; its parameters: {valid}"


def test_minimize_refuses_bad_objectives_bounds_and_starts() -> None:
    def sphere(x: np.ndarray) -> np.ndarray:
        return (x**2).sum(axis=1)

    lo, hi = [-1.0, -1.0], [1.0, 1.0]
    with pytest.raises(errors.InvalidArgumentError, match="objective must be a callable"):
        swarm_ik.minimize(3, lo, hi)  # type: ignore[arg-type]
    with pytest.raises(
        errors.InvalidArgumentError, match=r"returned shape \(30, 2\) for 30 points"
    ):
        swarm_ik.minimize(lambda x: x, lo, hi, "gwo", max_evals=60)
    with pytest.raises(errors.InvalidArgumentError, match=r"lower > upper at indices \[0, 1\]"):
        swarm_ik.minimize(sphere, hi, lo)
    with pytest.raises(
        errors.InvalidArgumentError, match="non-empty finite arrays of the same shape"
    ):
        swarm_ik.minimize(sphere, [], [])
    with pytest.raises(
        errors.InvalidArgumentError, match="non-empty finite arrays of the same shape"
    ):
        swarm_ik.minimize(sphere, [-1.0, np.nan], hi)
    with pytest.raises(
        errors.InvalidArgumentError, match="non-empty finite arrays of the same shape"
    ):
        swarm_ik.minimize(sphere, [-1.0], hi)
    with pytest.raises(
        errors.InvalidArgumentError, match="lower and upper must be arrays of numbers"
    ):
        swarm_ik.minimize(sphere, ["a", "b"], hi)
    with pytest.raises(errors.InvalidArgumentError, match=r"x0 must hold 2 finite numbers"):
        swarm_ik.minimize(sphere, lo, hi, x0=[0.0, 0.0, 0.0])
    with pytest.raises(errors.InvalidArgumentError, match="f_target must be a finite number"):
        swarm_ik.minimize(sphere, lo, hi, f_target=float("nan"))
    with pytest.raises(errors.InvalidArgumentError, match="needs an IK problem"):
        swarm_ik.minimize(sphere, lo, hi, "dls")
    with pytest.raises(errors.InvalidArgumentError, match="pop_size must be >= 4"):
        swarm_ik.minimize(sphere, lo, hi, "gwo", pop_size=3)
    with pytest.warns(UserWarning, match=r"x0 lies outside the bounds at indices \[0\]"):
        res = swarm_ik.minimize(sphere, lo, hi, "gwo", x0=[5.0, 0.0], max_evals=1, pop_size=4)
    np.testing.assert_array_equal(res.x, [1.0, 0.0])  # the clipped start, evaluated first


# ------------------------------------------------------------------------------ time limit
class _SlowProblem(IKProblem):
    """An IK problem whose every fitness / Jacobian call takes ``DELAY`` seconds longer."""

    DELAY = 0.01

    def fitness(self, q_batch: np.ndarray) -> np.ndarray:
        time.sleep(self.DELAY)
        return super().fitness(q_batch)

    def fitness_of_poses(self, poses: np.ndarray) -> np.ndarray:
        time.sleep(self.DELAY)
        return super().fitness_of_poses(poses)

    def residual_jacobian(self, q_batch: np.ndarray) -> tuple[np.ndarray, ...]:  # type: ignore[override]
        time.sleep(self.DELAY)
        return super().residual_jacobian(q_batch)


@pytest.mark.parametrize("name", SOLVERS)
@timed()
def test_time_limit_is_honoured_within_ten_percent_on_a_slow_fitness(
    name: str, yumi: swarm_ik.RobotModel
) -> None:
    target = yumi.fk(yumi.mid_q())
    target[:3, 3] += 1.0  # out of reach: nothing stops the run but the clock
    slow = _SlowProblem(yumi, target)
    limit = 0.4
    # an iteration count that would run for minutes: only the time limit can end the run
    params = {"iterations": 10**6} if "iterations" in base.get(name).params else {}
    # (the first solve of a process loads the compiled kernels, once: not this test's point)
    swarm_ik.solve(swarm_ik.IKProblem(yumi, target), name, max_evals=5)
    t0 = time.perf_counter()
    res = swarm_ik.solve(slow, name, time_limit=limit, **params)  # type: ignore[arg-type]
    wall = time.perf_counter() - t0
    assert wall <= 1.1 * limit, f"{name} ran {wall:.3f} s for a {limit} s limit"
    assert res.n_evals > 0 and not res.success and np.isfinite(res.fitness)


# ------------------------------------------------------------ unreachable / degenerate targets
@pytest.fixture(scope="module")
def planar(planar2_urdf: str) -> swarm_ik.RobotModel:
    """Two links of 1 m and 0.8 m about z: reach 1.8 m, stretched = singular."""
    return swarm_ik.load_robot(planar2_urdf)


def _planar_pose(radius: float, angle: float = 0.7) -> np.ndarray:
    """Pose at ``radius`` from the base, arm pointing outwards (the stretched orientation)."""
    c, s = np.cos(angle), np.sin(angle)
    pose = np.eye(4)
    pose[:2, :2] = [[c, -s], [s, c]]
    pose[:2, 3] = [radius * c, radius * s]
    return pose


def _degenerate_cases(yumi: swarm_ik.RobotModel, planar: swarm_ik.RobotModel):  # noqa: ANN202
    far = yumi.fk(yumi.mid_q())
    far[:3, 3] = [5.0, 5.0, 5.0]
    one_free_lo = np.r_[yumi.mid_q()[:6], yumi.lower[6]]
    one_free_hi = np.r_[yumi.mid_q()[:6], yumi.upper[6]]
    turned = yumi.fk(np.r_[yumi.mid_q()[:6], 0.5 * yumi.upper[6]])
    return {
        # id: (problem, reachable?)
        "yumi: 5 m away": (IKProblem(yumi, far), False),
        "yumi: 5 m away, paper-l1": (IKProblem(yumi, far, "paper-l1"), False),
        "yumi: 5 m away, euler-zyz": (IKProblem(yumi, far, "euler-zyz"), False),
        "yumi: 5 m away, paper-pso": (IKProblem(yumi, far, "paper-pso"), False),
        "yumi: stretched (q = 0, singular)": (IKProblem.from_q(yumi, np.zeros(7)), True),
        "planar: on the boundary (singular)": (IKProblem(planar, _planar_pose(1.8)), True),
        "planar: 1 mm beyond the boundary": (IKProblem(planar, _planar_pose(1.801)), False),
        "planar: beyond, position only": (IKProblem(planar, _planar_pose(1.801), w_rot=0), False),
        "planar: folded to the joint limit (inner boundary)": (
            IKProblem.from_q(planar, [0.7, 3.1]),
            True,
        ),
        "yumi: all joints fixed but one, reachable": (
            IKProblem(yumi, turned, lower=one_free_lo, upper=one_free_hi),
            True,
        ),
        "yumi: all joints fixed but one, unreachable": (
            IKProblem(yumi, far, lower=one_free_lo, upper=one_free_hi),
            False,
        ),
        "yumi: every joint fixed": (
            IKProblem(yumi, far, lower=yumi.mid_q(), upper=yumi.mid_q()),
            False,
        ),
    }


@pytest.mark.parametrize("name", SOLVERS)
def test_unreachable_and_degenerate_targets_give_an_honest_result(
    name: str, yumi: swarm_ik.RobotModel, planar: swarm_ik.RobotModel
) -> None:
    for case, (prob, reachable) in _degenerate_cases(yumi, planar).items():
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no RuntimeWarning (0/0, overflow...) either
            # (numba's note on first-class functions, when this test happens to compile them)
            warnings.filterwarnings("ignore", message="First-class function type feature")
            res = swarm_ik.solve(prob, name, seed=1, max_evals=300)
        where = f"{name} on {case}: {res}"
        assert isinstance(res, swarm_ik.Result), where
        values = [res.fitness, res.position_error, res.rotation_error, res.time_s]
        assert np.all(np.isfinite(res.q)) and np.all(np.isfinite(values)), where
        assert np.all(np.isfinite(res.history)) and 0 < res.n_evals <= 300, where
        assert res.within_limits and np.all(res.q >= prob.lower), where
        assert np.all(res.q <= prob.upper), where
        # the best found is reported honestly: its fitness is recomputed from q...
        recomputed = float(prob.fitness(res.q[None])[0])
        assert res.fitness == pytest.approx(recomputed, rel=1e-9, abs=1e-12), where
        # ...and success is checked, never claimed
        dp, dr = swarm_ik.problem.largest_errors(swarm_ik.verify(prob, res.q))
        ok = dp <= 1e-5 and (prob.position_only or dr <= 1e-5)
        assert res.success == ok, where
        if not reachable:
            assert not res.success, where


# ------------------------------------------------------------------------------------ CLI
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--robot", "yumi"], "unknown robot 'yumi'; did you mean 'yumi_left'? valid robots:"),
        (["--robot", "{bad}"], "not a valid XML file"),
        (["--robot", "{missing}"], "URDF file not found"),
        (["--robot", "yumi_left", "--frame", "tool1"], "unknown frame 'tool1'; valid frames:"),
        (["--robot", "yumi_left", "--fitness", "l2"], "unknown fitness 'l2'; valid fitnesses:"),
        (["--robot", "yumi_left", "--solver", "nope"], "unknown solver 'nope'; valid solvers:"),
        (["--robot", "yumi_left", "--param", "popsize=3"], "its parameters: "),
        (["--robot", "yumi_left", "--solver", "pso", "--param", "pop_size=2"], "pop_size must be"),
        (["--robot", "yumi_left", "--max-evals", "0"], "max_evals must be a positive integer"),
        (["--robot", "yumi_left", "--time-limit", "-1"], "time_limit must be a positive"),
        (["--robot", "yumi_left", "--q0", "1", "2"], "q0 must hold 7 values"),
        (["--robot", "yumi_left", "--seed", "-1"], "seed must be in"),
        (
            ["--robot", "yumi_left", "--pose", "0.3", "0", "0.3", "0", "0", "0", "0"],
            "quaternion has zero norm",
        ),
        (
            ["--robot", "yumi_left", "--pose", "nan", "0", "0.3", "0", "0", "0", "1"],
            "position must be 3 finite numbers",
        ),
        # the model options (--lock, --base-box, --floating-base)
        (["--robot", "panda", "--lock", "no_such_joint=0"], "unknown joint 'no_such_joint'"),
        (["--robot", "panda", "--lock", "panda_joint4=abc"], "expected JOINT=VALUE"),
        (["--robot", "panda", "--lock", "panda_joint4=0.5"], "outside its limits"),
        (
            ["--robot", "panda", "--lock", "panda_joint4=-1", "--lock", "panda_joint4=-2"],
            "more than once",
        ),
        (["--robot", "panda", "--base-box", "2"], "--base-box needs --floating-base"),
        (["--robot", "panda", "--floating-base", "--base-box", "1", "2"], "one number or three"),
        (["--robot", "panda", "--floating-base", "--base-box", "-1"], "base_box"),
    ],
)
def test_cli_turns_every_error_into_one_line_and_exit_code_2(
    args: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = _write(tmp_path, "not xml", "bad.urdf")
    args = [a.format(bad=bad, missing=tmp_path / "missing.urdf") for a in args]
    if "--pose" not in args:
        args += FROM_Q
    line = cli_error(capsys, "solve", *args)
    assert re.match(r"swarm-ik( solve)?: error: ", line), line  # (a usage error names solve)
    assert message in line


# =================================================================== issue 16: any input
# ---------------------------------------------------------- item 8: every solver parameter
def _params(kind: str) -> list[tuple[str, str]]:
    """(solver, parameter) for every parameter of that constraint kind ("float", "int")."""
    return [
        (name, key)
        for name in SOLVERS
        for key, con in base.get(name).constraints.items()
        if con.kind == kind
    ]


def test_every_numeric_parameter_of_every_solver_has_a_constraint() -> None:
    for name in SOLVERS:
        spec = base.get(name)
        for key, default in spec.params.items():
            if isinstance(default, (int, float)):
                assert key in spec.constraints, (name, key)
                ok, _ = spec.constraints[key].convert(default)
                assert ok, (name, key, default)  # the defaults satisfy their constraints


@pytest.mark.parametrize(("name", "key"), _params("float"))
@pytest.mark.parametrize("value", [float("nan"), float("inf"), -float("inf"), "a", True, None])
def test_float_parameter_refuses_nan_inf_strings_and_booleans(
    name: str, key: str, value: object
) -> None:
    with pytest.raises(
        errors.InvalidArgumentError, match=rf"parameter {key} of solver '{name}' must"
    ):
        base.get(name).resolve({key: value})


@pytest.mark.parametrize(("name", "key"), _params("float"))
def test_float_parameter_refuses_values_just_outside_its_range(name: str, key: str) -> None:
    con = base.get(name).constraints[key]
    outside = []
    if np.isfinite(con.lo):
        outside.append(con.lo if con.lo_open else np.nextafter(con.lo, -np.inf))
    if np.isfinite(con.hi):
        outside.append(con.hi if con.hi_open else np.nextafter(con.hi, np.inf))
    for v in outside:
        with pytest.raises(
            errors.InvalidArgumentError, match=rf"parameter {key} of solver '{name}'"
        ):
            base.get(name).resolve({key: float(v)})
    # an integer value is a number too, converted to float
    default = base.get(name).params[key]
    assert isinstance(base.get(name).resolve({key: default})[key], float)


@pytest.mark.parametrize(("name", "key"), _params("int"))
@pytest.mark.parametrize("value", [1.5, "3", True, float("nan")])
def test_integer_parameter_refuses_non_integers(name: str, key: str, value: object) -> None:
    with pytest.raises(errors.InvalidArgumentError, match=rf"{key}"):
        base.get(name).resolve({key: value})


@pytest.mark.parametrize(
    ("solver", "params", "message"),
    [
        # the cases of issue 16: lam0=0 hung forever, v_max=inf raised a bare OverflowError
        ("swarm", {"lam0": 0}, r"parameter lam0 of solver 'swarm' must be a number in \(0, "),
        ("swarm", {"lam0": -1.0}, r"parameter lam0 of solver 'swarm'"),
        ("swarm", {"max_step": float("nan")}, r"parameter max_step of solver 'swarm'"),
        ("swarm", {"stall_rel": 2.0}, r"stall_rel of solver 'swarm' must be a number in \[0, 1\]"),
        ("pso", {"w": float("nan")}, r"parameter w of solver 'pso' must be a finite number >= 0"),
        ("pso", {"v_max": float("inf")}, r"parameter v_max of solver 'pso'"),
        ("dls", {"damping": -1.0}, r"parameter damping of solver 'dls' must be a finite number >"),
        ("cs", {"beta": 2.0}, r"parameter beta of solver 'cs' must be a number in \(0, 2\)"),
        ("mgwo", {"gamma": 1.0}, r"parameter gamma of solver 'mgwo'"),
        ("foa", {"step": 0.0}, r"parameter step of solver 'foa'"),
    ],
)
def test_bad_solver_parameters_are_refused_before_running(
    problem: IKProblem, solver: str, params: dict, message: str
) -> None:
    t0 = time.perf_counter()
    with pytest.raises(errors.InvalidArgumentError, match=message):
        swarm_ik.solve(problem, solver, time_limit=0.5, **params)
    assert time.perf_counter() - t0 < 0.5  # refused at the door, not after a (hung) run


@pytest.mark.parametrize(
    "params",
    [
        {"lam0": 1e12},
        {"lam0": 1e-300},
        {"max_step": 1e-300},
        {"stall_rel": 0.0},
        {"stall_rel": 1.0},
    ],
)
@timed()
def test_extreme_accepted_swarm_parameters_still_honour_the_budget(
    problem: IKProblem, params: dict
) -> None:
    t0 = time.perf_counter()
    res = swarm_ik.solve(problem, "swarm", time_limit=0.3, **params)
    assert time.perf_counter() - t0 < 1.0
    res = swarm_ik.solve(problem, "swarm", max_evals=500, **params)
    assert res.n_evals <= 500


def test_constraint_specs_parse_and_refuse_unknown_ones() -> None:
    con = base.Constraint.parse("(0, 1]")
    assert (con.lo, con.hi, con.lo_open, con.hi_open) == (0.0, 1.0, True, False)
    assert con.describe() == "a number in (0, 1]"
    assert base.Constraint.parse("int>=2").convert(2) == (True, 2)
    assert base.Constraint.parse("int>=2").convert(1)[0] is False
    with pytest.raises(
        errors.InvalidArgumentError, match=r"prefer of solver 'swarm' must be one of"
    ):
        base.get("swarm").resolve({"prefer": "closest"})
    with pytest.raises(errors.InvalidArgumentError, match="unknown parameter constraint 'huge'"):
        base.Constraint.parse("huge")


def test_register_refuses_constraints_for_missing_parameters() -> None:
    def run(ev: object, rng: object, *, a: float = 1.0) -> None:
        return None

    with pytest.raises(errors.InvalidArgumentError, match=r"constraints for \['b'\] given"):
        base.register("_test_bad_constraints", run, constraints={"b": "positive"})
    assert "_test_bad_constraints" not in SOLVERS


# ---------------------------------------------------------- item 9: quaternion of huge norm
@pytest.mark.parametrize("scale", [1e200, 1e-5, 1e307])
def test_quaternion_of_any_finite_norm_is_normalised_exactly(scale: float) -> None:
    from swarm_ik.pose import make_pose

    q = np.array([1.0, 0.0, 0.0, 0.0])  # tool pointing down: 180° about x
    np.testing.assert_allclose(make_pose([0.4, 0.1, 0.5], q * scale)[:3, :3], np.diag([1, -1, -1]))
    q = np.array([0.1, -0.7, 0.3, 0.5])
    np.testing.assert_allclose(
        make_pose([0, 0, 0], q * scale), make_pose([0, 0, 0], q / np.linalg.norm(q)), atol=1e-15
    )


def test_cli_pose_with_huge_quaternion_points_the_tool_down(
    capsys: pytest.CaptureFixture[str],
) -> None:
    target = ["--pose", "0.4", "0.1", "0.5", "1e200", "0", "0", "0"]
    out = cli_json(capsys, "solve", "--robot", "panda", *target)
    assert out["success"]
    pose = swarm_ik.load_robot("panda").fk(np.array(out["q"]))
    np.testing.assert_allclose(pose[:3, 2], [0, 0, -1], atol=1e-4)  # z axis down, not up


# ---------------------------------------------------------- item 10: population memory
def test_population_larger_than_the_cap_is_refused_before_allocating(problem: IKProblem) -> None:
    with pytest.raises(errors.InvalidArgumentError, match=r"pop_size must be <= 1000000"):
        swarm_ik.solve(problem, "pso", pop_size=20_000_000)
    with pytest.raises(errors.InvalidArgumentError, match=r"exceeds the cap of 10000000"):
        base.get("pso").resolve({"pop_size": 1_000_000}, dim=20)
    # through minimize: 600 000 x 20 variables = 1.2e7 values, refused by the evaluator
    lower, upper = -np.ones(20), np.ones(20)
    t0 = time.perf_counter()
    with pytest.raises(errors.InvalidArgumentError, match=r"pop_size 600000 x 20 joints"):
        swarm_ik.minimize(lambda x: (x**2).sum(axis=1), lower, upper, "pso", pop_size=600_000)
    assert time.perf_counter() - t0 < 2.0


# ---------------------------------------------------------- items 11, 12, 14: the CLI
def test_cli_reads_negative_numbers_in_exponent_notation(
    capsys: pytest.CaptureFixture[str],
) -> None:
    q = ["-1e-3", "-.5", "2E-1", "0.3", "-2.5e-1", "0.4", "-1e0"]
    assert cli_json(capsys, "solve", "--robot", "yumi_left", "--from-q", *q)["success"]


@pytest.mark.parametrize(
    "args",
    [
        ["solve", "--robot", "yumi_left", "--pose", "1", "2"],
        ["solve", "--robot", "yumi_left"],
        ["solve", "--robot", "yumi_left", *FROM_Q, "--seed", "x"],
        ["nosuchcommand"],
        ["batch", "--robot", "yumi_left", "--random", "3"],
    ],
)
def test_cli_usage_errors_are_one_line_exit_2(
    args: list[str], capsys: pytest.CaptureFixture[str]
) -> None:
    rc = main(args)
    captured = capsys.readouterr()
    assert rc == 2
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and ": error: " in lines[0] and "--help" in lines[0], captured.err
    assert captured.out == ""


def test_cli_errors_are_json_with_json(capsys: pytest.CaptureFixture[str]) -> None:
    rc = main(["solve", "--robot", "yumi_left", *FROM_Q, "--json", "--param", "lam0=0"])
    captured = capsys.readouterr()
    assert rc == 2 and captured.err == ""
    d = json.loads(captured.out)
    assert d["exit_code"] == 2 and d["kind"] == "InvalidArgumentError"
    assert "parameter lam0 of solver 'swarm'" in d["error"]
    rc = main(["solve", "--robot", "yumi_left", "--json", "--pose", "1"])  # a usage error
    d = json.loads(capsys.readouterr().out)
    assert rc == 2 and d["kind"] == "UsageError" and "expected 7 arguments" in d["error"]


def test_cli_unexpected_error_exits_3_with_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def boom(*args: object, **kwargs: object) -> None:
        raise RuntimeError("something broke\ninside")

    monkeypatch.setattr(swarm_ik, "solve", boom)
    monkeypatch.delenv("SWARM_IK_DEBUG", raising=False)
    rc = main(["solve", "--robot", "yumi_left", *FROM_Q])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 3 and len(err) == 1
    assert "internal error (RuntimeError: something broke inside)" in err[0]

    def oom(*args: object, **kwargs: object) -> None:
        raise MemoryError

    monkeypatch.setattr(swarm_ik, "solve", oom)
    assert main(["solve", "--robot", "yumi_left", *FROM_Q]) == 3
    assert "out of memory" in capsys.readouterr().err
    monkeypatch.setenv("SWARM_IK_DEBUG", "1")  # developers get the traceback
    with pytest.raises(MemoryError):
        main(["solve", "--robot", "yumi_left", *FROM_Q])


@pytest.mark.parametrize(
    ("command", "option", "make", "message"),
    [
        ("batch", "--out", lambda d: d, "is a folder"),
        ("batch", "--out", lambda d: d / "no" / "r.npz", "does not exist"),
        ("batch", "--out", lambda d: d / "r.txt", "valid: .csv, .npz"),
        ("reach", "--out", lambda d: d / "no" / "m.npz", "does not exist"),
        ("reach", "--png", lambda d: d, "is a folder"),
        ("solve", "--html", lambda d: d / "no" / "s.html", "does not exist"),
        ("solve", "--html", lambda d: d, "is a folder"),
    ],
)
@pytest.mark.usefixtures("no_robot_loading")
def test_cli_output_paths_are_checked_before_computing(
    command: str,
    option: str,
    make: object,
    message: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    path = make(tmp_path)  # type: ignore[operator]
    extra = {"batch": ["--random", "3"], "reach": [], "solve": FROM_Q}[command]
    rc = main([command, "--robot", "yumi_left", *extra, option, str(path)])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert option in err[0] and message in err[0]


@pytest.mark.parametrize(
    ("name", "write"),
    [
        ("corrupt.npz", lambda p: p.write_bytes(b"PK\x03\x04 this is not a zip")),
        ("objects.npy", lambda p: np.save(p, np.array([{"a": 1}, None], dtype=object))),
        ("garbage.npy", lambda p: p.write_bytes(b"\x93NUMPY garbage")),
        ("empty.npz", lambda p: p.write_bytes(b"")),
        ("text.csv", lambda p: p.write_bytes(b"\xff\xfe\x00garbage")),
    ],
)
def test_cli_batch_unreadable_targets_file_exits_2(
    name: str, write: object, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / name
    write(path)  # type: ignore[operator]
    rc = main(
        [
            "batch",
            "--robot",
            "yumi_left",
            "--targets",
            str(path),
            "--out",
            str(tmp_path / "r.npz"),
            "--scheduler",
            "none",
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert str(path) in err[0]
    assert not (tmp_path / "r.npz").exists()


def test_cli_batch_ctrl_c_keeps_finished_chunks(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    import swarm_ik.batch as batch_mod

    real = batch_mod._run_chunk
    calls = []

    def interrupted_third(*args: object) -> object:
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(batch_mod, "_run_chunk", interrupted_third)
    out = tmp_path / "r.npz"
    rc = main(
        [
            "batch",
            "--robot",
            "yumi_left",
            "--random",
            "200",
            "--out",
            str(out),
            "--scheduler",
            "none",
            "--chunk-size",
            "64",
            "--seed",
            "5",
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 130
    assert len(err) == 1 and "interrupted; writing the 128 finished targets (of 200)" in err[0]
    saved = np.load(out)
    assert saved["q"].shape == (128, 7) and saved["targets"].shape == (128, 4, 4)
    # the rows kept are exactly what solve_batch gives for these targets
    monkeypatch.setattr(batch_mod, "_run_chunk", real)
    robot = swarm_ik.load_robot("yumi_left")
    targets = robot.fk(robot.random_q(np.random.default_rng(5), 200))
    ref = swarm_ik.solve_batch(robot, targets, seed=5, chunk_size=64)
    np.testing.assert_array_equal(saved["q"], ref.q[:128])
    np.testing.assert_array_equal(saved["targets"], targets[:128])


def test_cli_interrupt_elsewhere_exits_130_with_one_line(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def ctrl_c(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(swarm_ik, "solve", ctrl_c)
    assert main(["solve", "--robot", "yumi_left", *FROM_Q]) == 130
    assert capsys.readouterr().err.strip() == "swarm-ik: interrupted"


# ---------------------------------------------------------- item 11: API input helpers
def test_validate_helpers_name_the_bad_input(yumi: swarm_ik.RobotModel) -> None:
    from swarm_ik import _validate

    with pytest.raises(
        errors.InvalidTargetError, match=r"targets must be an array of numbers, got 'abc'"
    ):
        _validate.float_array("abc")
    with pytest.raises(errors.InvalidTargetError, match="got None"):
        _validate.float_array(None)
    with pytest.raises(errors.InvalidTargetError, match="array of numbers"):
        _validate.float_array([[1, 2], [3]])
    for bad in ("a", float("nan"), 0, -1.0, True, None):
        with pytest.raises(errors.InvalidArgumentError, match="tol_pos must be a positive number"):
            _validate.positive_float(bad, "tol_pos")
    assert _validate.positive_float(1, "tol_pos") == 1.0
    with pytest.raises(errors.InvalidArgumentError, match="q must hold 7 values"):
        _validate.joint_vector(yumi, [0, 0])


@pytest.mark.parametrize("case", ["targets", "tol_pos"])
def test_api_refuses_bad_input_with_a_swarmik_error(
    case: str, yumi: swarm_ik.RobotModel, problem: IKProblem
) -> None:
    with pytest.raises(errors.SwarmIKError):
        if case == "targets":
            swarm_ik.solve_batch(yumi, "abc")
        elif case == "tol_pos":
            swarm_ik.solve_batch(yumi, yumi.fk(yumi.mid_q())[None], tol_pos="a")


def test_verify_refuses_a_bad_joint_vector(problem: IKProblem) -> None:
    with pytest.raises(errors.SwarmIKError, match="q must"):
        swarm_ik.verify(problem, [0, 0])


# ---------------------------------------------------------- item 10: reach grid size
@pytest.mark.parametrize(
    ("resolution", "message"),
    [
        ("0.002", r"more than max_targets=5000000; use a coarser resolution \(at least"),
        ("1e-4", r"more than max_targets=5000000"),
        ("0", r"--resolution must be a positive number, got 0.0"),
        ("nan", r"--resolution must be a positive number"),
    ],
)
def test_cli_reach_refuses_a_grid_too_large_before_allocating(
    resolution: str, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    t0 = time.perf_counter()
    rc = main(
        [
            "reach",
            "--robot",
            "yumi_left",
            "--resolution",
            resolution,
            "--out",
            str(tmp_path / "m.npz"),
            "--scheduler",
            "none",
        ]
    )
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and re.search(message, err[0]), err
    assert time.perf_counter() - t0 < 10.0  # refused, not killed for memory
    assert not (tmp_path / "m.npz").exists()


def test_grid_size_check_counts_without_allocating() -> None:
    from swarm_ik._validate import check_grid_size, grid_cells
    from swarm_ik.reach import grid_axes

    lo, hi = np.array([-0.3, -0.2, 0.0]), np.array([0.4, 0.25, 0.9])
    for res in (0.1, 0.07, 0.3):
        x, y, z = grid_axes(lo, hi, res)
        assert grid_cells(lo, hi, res) == x.size * y.size * z.size
        assert check_grid_size(lo, hi, res) == x.size * y.size * z.size
    with pytest.raises(errors.InvalidArgumentError, match=r"use --resolution 0.0"):
        check_grid_size(lo, hi, 1e-4)


def test_mobile_base_with_virtual_joints_of_a_million_metres_is_solved(tmp_path: Path) -> None:
    """Issue 16 item 6: restarts sample a ±999999 m range in a window around the seed
    (swarm_ik.urdf.sampling_bounds), in solve and in solve_batch."""
    lim = '<limit lower="{lo}" upper="{hi}" effort="1" velocity="1"/>'

    def j(n: str, p: str, c: str, t: str, ax: str, lo: float, hi: float, xyz: str) -> str:
        return (
            f'<joint name="{n}" type="{t}"><parent link="{p}"/><child link="{c}"/>'
            f'<origin xyz="{xyz}"/><axis xyz="{ax}"/>' + lim.format(lo=lo, hi=hi) + "</joint>"
        )

    urdf = (
        '<robot name="mobile">'
        + "".join(f'<link name="l{i}"/>' for i in range(7))
        + j("x", "l0", "l1", "prismatic", "1 0 0", -999999, 999999, "0 0 0")
        + j("y", "l1", "l2", "prismatic", "0 1 0", -999999, 999999, "0 0 0")
        + j("th", "l2", "l3", "revolute", "0 0 1", -3.14, 3.14, "0 0 0")
        + j("a1", "l3", "l4", "revolute", "0 1 0", -2, 2, "0 0 0.2")
        + j("a2", "l4", "l5", "revolute", "0 1 0", -2, 2, "0 0 0.4")
        + j("a3", "l5", "l6", "revolute", "1 0 0", -2, 2, "0 0 0.4")
        + "</robot>"
    )
    path = tmp_path / "mobile.urdf"
    path.write_text(urdf)
    r = swarm_ik.load_robot(path, "l6")
    rng = np.random.default_rng(0)
    qs = r.mid_q() + np.c_[rng.uniform(-3, 3, (10, 2)), rng.uniform(-1, 1, (10, 4))]
    ok = sum(
        swarm_ik.solve(IKProblem(r, r.fk(q)), seed=k, time_limit=0.2).success
        for k, q in enumerate(qs)
    )
    assert ok == 10
    assert swarm_ik.solve_batch(r, r.fk(qs)).success.all()


@pytest.mark.parametrize(
    "kwargs, name",
    [({"w_rot": -1.0}, "w_rot"), ({"lam": float("nan")}, "lam"), ({"mu": "a"}, "mu"),
     ({"w_rot": 1.0, "lam": 2.0, "mu": float("inf")}, "mu")],
)  # fmt: skip
def test_problem_refuses_bad_fitness_weights(kwargs: dict, name: str) -> None:
    robot = swarm_ik.load_robot("panda")
    with pytest.raises(
        errors.InvalidArgumentError, match=rf"^{name} must be a finite non-negative"
    ):
        IKProblem(robot, robot.fk(robot.mid_q()), **kwargs)


@pytest.mark.parametrize("solver", ["swarm", "pso"])
def test_target_beyond_reach_returns_at_once_whatever_the_budget(solver: str) -> None:
    """A target proven out of reach costs at most api.UNREACHABLE_BUDGET, not time_limit."""
    from swarm_ik.api import UNREACHABLE_BUDGET

    robot = swarm_ik.load_robot("panda")
    target = np.eye(4)
    target[:3, 3] = [5.0, 0.0, 0.3]
    problem = IKProblem(robot, target)
    swarm_ik.solve(problem, solver, time_limit=0.01)  # (compiled before the clock)
    t0 = time.perf_counter()
    res = swarm_ik.solve(problem, solver, time_limit=1e9, max_evals=10**12)
    assert time.perf_counter() - t0 < 10 * UNREACHABLE_BUDGET[0] + 1.0
    assert not res.success and res.reason == "unreachable"
    t0 = time.perf_counter()
    res = swarm_ik.IKSolver(robot, time_limit=1e9).solve(target)
    assert time.perf_counter() - t0 < 10 * UNREACHABLE_BUDGET[0] + 1.0
    assert res.reason == "unreachable"


def test_the_cap_is_smaller_with_a_goal_written_in_python() -> None:
    """Beyond reach with a Python goal and no time limit: at most
    api.UNREACHABLE_PYTHON_EVALS evaluations (3,000 took 35 s with a 10 ms goal: a held-out
    review), the answer still the best point found and the reason 'unreachable'."""
    from dataclasses import dataclass

    from swarm_ik.api import UNREACHABLE_PYTHON_EVALS
    from swarm_ik.goals import Goal, Position

    @dataclass(frozen=True)
    class Level(Goal):
        """The tool's z axis horizontal (one row)."""

        frame: str

        def residual(self, state):
            return np.array([state.pose(self.frame)[2, 2]])

        def jacobian(self, state):
            z = state.pose(self.frame)[:3, 2]
            return np.cross(state.jacobian(self.frame)[3:].T, z).T[2][None]

    robot = swarm_ik.load_robot("ur5")
    ee = robot.frames[0]
    problem = IKProblem(robot, goals=[Position(ee, [3.0, 0.0, 0.3]), Level(ee)])
    res = swarm_ik.solve(problem, seed=0)
    assert res.reason == "unreachable" and not res.success
    assert 0 < res.n_evals <= UNREACHABLE_PYTHON_EVALS


@pytest.mark.parametrize("budget", [{}, {"max_evals": 100_000}, {"time_limit": 1.0}])
def test_the_cap_holds_for_default_budgets_and_the_collision_first_tries(budget: dict) -> None:
    """A goal point inside an obstacle: at most api.UNREACHABLE_BUDGET's evaluations with the
    solver's default budget too, and the tries without the collision goal share the capped
    budget (13,625 evaluations with no budget given, 21,001 with max_evals=100,000 before)."""
    from swarm_ik.api import UNREACHABLE_BUDGET
    from swarm_ik.goals import AvoidCollisions
    from swarm_ik.scene import Cylinder, Scene

    robot = swarm_ik.load_robot("panda")
    target = np.diag([1.0, -1.0, -1.0, 1.0])
    target[:3, 3] = [0.5, 0.0, 0.3]
    scene = Scene([Cylinder(0.04, 0.6, [0.5, 0.0, 0.3])])
    problem = IKProblem(robot, target, goals=[AvoidCollisions(scene)])
    far = np.eye(4)
    far[:3, 3] = [5.0, 0.0, 0.3]
    for p in (problem, IKProblem(robot, far)):
        res = swarm_ik.solve(p, seed=0, **budget)
        assert not res.success and res.reason == "unreachable"
        assert res.n_evals <= UNREACHABLE_BUDGET[1]


def test_goals_proven_contradictory_return_within_the_same_cap() -> None:
    """Two goals of one frame 10 cm apart: proven contradictory before the search, so the
    solve ends at api.UNREACHABLE_BUDGET with reason "conflicting_goals", not at time_limit."""
    from swarm_ik.api import UNREACHABLE_BUDGET
    from swarm_ik.goals import Position

    robot = swarm_ik.load_robot("panda")
    p = robot.fk(robot.mid_q())[:3, 3]
    goals = [Position(robot.ee_frame, p), Position(robot.ee_frame, p + [0.1, 0.0, 0.0])]
    problem = IKProblem(robot, goals=goals)
    swarm_ik.solve(problem, time_limit=0.01)  # (compiled before the clock)
    t0 = time.perf_counter()
    res = swarm_ik.solve(problem, time_limit=30.0, max_evals=10**9)
    assert time.perf_counter() - t0 < 10 * UNREACHABLE_BUDGET[0] + 1.0
    assert not res.success and res.reason == "conflicting_goals"
    assert res.n_evals <= UNREACHABLE_BUDGET[1]


def test_thousands_of_obstacles_stay_within_the_solve_budget() -> None:
    """3,000 obstacles: the exact checker is built in coal's broad phase (a Pinocchio model
    holding them grew quadratically: 28 s for a 0.1 s solve) and the check still equals the
    pair-by-pair one on a configuration in contact and one free."""
    import coal

    from swarm_ik import goals
    from swarm_ik.scene import Scene, Sphere

    robot = swarm_ik.load_robot("panda")
    rng = np.random.default_rng(0)
    pts = rng.uniform([-2.0, -2.0, -1.0], [2.0, 2.0, 2.0], (6000, 3))
    pts = pts[np.linalg.norm(pts, axis=1) > 1.3][:3000]
    scene = Scene([Sphere(0.02, p, name=f"s{i}") for i, p in enumerate(pts)])
    problem = IKProblem(
        robot, goals=[goals.Pose(robot.ee_frame, robot.fk(robot.mid_q())),
                      goals.AvoidCollisions(scene)],
    )  # fmt: skip
    t0 = time.perf_counter()
    res = swarm_ik.solve(problem, time_limit=0.1)
    assert time.perf_counter() - t0 < 0.1 + 2.0  # (was 28 s)
    assert res.success
    rc = robot.collision_model()
    inside = Scene([*scene, Sphere(0.05, robot.fk(robot.mid_q())[:3, 3], name="at_hand")])
    for sc, free in ((scene, True), (inside, False)):
        rep = rc.check(robot.mid_q(), sc, self_collision=False)
        assert rep.collision_free is free
        assert rc.collides(robot.mid_q(), sc, self_collision=False) is not free
    # the clearance is the smallest body-obstacle distance, pair by pair
    data = robot.model.createData()
    import pinocchio as pin

    pin.forwardKinematics(robot.model, data, robot.to_pinocchio(robot.mid_q()))
    best = np.inf
    for g in rc.geom_model.geometryObjects:
        body = coal.CollisionObject(g.geometry, data.oMi[g.parentJoint] * g.placement)
        for _, obj in scene.coal_objects():
            d = coal.distance(body, obj, coal.DistanceRequest(), coal.DistanceResult())
            best = min(best, d)
    rep = rc.check(robot.mid_q(), scene, self_collision=False)
    assert rep.clearance == pytest.approx(best, abs=1e-9)


def test_batch_limits_named_before_any_work(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--random 10**12 (out of memory before), max_starts=10**9 (hours per unreachable
    target), complex targets (imaginary part dropped before) and too many CSV rows."""
    from swarm_ik import batch

    rc = main(
        ["batch", "--robot", "panda", "--random", str(10**12), "--out", str(tmp_path / "o.npz")]
    )
    assert rc == 2 and "MAX_TARGETS" in capsys.readouterr().err
    robot = swarm_ik.load_robot("panda")
    with pytest.raises(errors.InvalidArgumentError, match="max_starts must be at most"):
        swarm_ik.solve_batch(robot, np.eye(4)[None], max_starts=10**9)
    with pytest.raises(errors.InvalidTargetError, match="complex"):
        swarm_ik.solve_batch(robot, np.zeros((2, 7), dtype=complex))
    np.save(tmp_path / "c.npy", np.zeros((2, 7), dtype=complex) + 1j)
    with pytest.raises(errors.InvalidTargetError, match="complex"):
        batch.read_targets_file(tmp_path / "c.npy")
    csv_path = tmp_path / "t.csv"
    csv_path.write_text("0.4,0,0.4,0,0,0,1\n" * 4)
    assert batch.read_targets_file(csv_path).shape == (4, 4, 4)
    csv_path.write_text("0.4,0,0.4,0,0,0,1\n0.4,0,0.4,0,0,0\n")
    with pytest.raises(errors.InvalidArgumentError, match="row 2 has 6 columns"):
        batch.read_targets_file(csv_path)
    original = batch.MAX_TARGETS
    try:
        batch.MAX_TARGETS = 3
        csv_path.write_text("0.4,0,0.4,0,0,0,1\n" * 4)
        with pytest.raises(errors.InvalidArgumentError, match="more than 3 rows"):
            batch.read_targets_file(csv_path)
    finally:
        batch.MAX_TARGETS = original


@pytest.mark.parametrize(
    "call",
    ["IKProblem", "IKSolver", "solve_path", "Position", "Orientation", "q0", "Posture", "fk"],
)
def test_complex_arrays_are_refused_everywhere(call: str) -> None:
    """A complex array wherever floats are read is refused naming it (numpy dropped the
    imaginary part with a warning: solve_path answered the real part, success=True)."""
    from swarm_ik import goals as G

    robot = swarm_ik.load_robot("ur5")
    q = robot.mid_q()
    target = robot.fk(q).astype(complex)
    target[0, 3] += 0.5j
    calls = {
        "IKProblem": lambda: IKProblem(robot, target),
        "IKSolver": lambda: swarm_ik.IKSolver(robot).solve(target),
        "solve_path": lambda: swarm_ik.solve_path(robot, np.repeat(target[None], 3, 0)),
        "Position": lambda: G.Position("tool0", np.array([0.4, 0.0, 0.4]) + 1j),
        "Orientation": lambda: G.Orientation("tool0", np.eye(3) + 0j),
        "q0": lambda: swarm_ik.solve(IKProblem(robot, robot.fk(q)), q0=q + 1j),
        "Posture": lambda: IKProblem(robot, robot.fk(q), goals=[G.Posture(q + 1j)]),
        "fk": lambda: robot.fk(q + 1j),
    }
    with warnings.catch_warnings():
        warnings.simplefilter("error", np.exceptions.ComplexWarning)
        with pytest.raises(errors.SwarmIKError, match="complex"):
            calls[call]()
