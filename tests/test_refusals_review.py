"""Refusals found by a held-out review: goal weights and ``w_rot`` outside [1e-6, 1e6],
``Scene`` given no list of shapes, goals JSON with a key given twice; and what
``Result.rotation_error`` reports for a problem without any rotation goal."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import swarm_ik
from swarm_ik import goals as G
from swarm_ik.cli import main
from swarm_ik.errors import InvalidArgumentError, SwarmIKError
from swarm_ik.problem import largest_errors
from swarm_ik.result import Result

Q = np.array([0.3, -0.2, 0.1, -2.0, 0.1, 1.9, 0.6])
"""A Panda configuration whose forward kinematics is the (reachable) target."""


def _panda() -> tuple[swarm_ik.RobotModel, np.ndarray]:
    from conftest import robot

    panda = robot("panda")
    return panda, panda.fk(Q)


# ------------------------------------------------------------------ 1. extreme weights
@pytest.mark.parametrize(
    "weight, shown",
    [(1e308, "1e+308"), (1e-12, "1e-12"), (1e12, "1000000000000"), (1.5e6, "1500000"),
     (9e-7, "9e-07")],
)  # fmt: skip
def test_goal_weight_outside_the_range_is_refused(weight: float, shown: str) -> None:
    panda, target = _panda()
    with pytest.raises(InvalidArgumentError) as info:
        G.Pose(panda.ee_frame, target, weight=weight)
    assert str(info.value) == (
        f"Pose.weight must be between 1e-6 and 1e6 (weights are relative), got {shown}"
    )
    with pytest.raises(InvalidArgumentError, match=r"^Position\.weight must be between 1e-6"):
        G.Position(panda.ee_frame, target[:3, 3], weight=weight)
    with pytest.raises(InvalidArgumentError, match=r"^CenterJoints\.weight must be between"):
        G.CenterJoints(weight=weight)


def test_weight_1e308_is_refused_and_the_ends_of_the_range_solve() -> None:
    """1e308 ended "time_limit" on this reachable target (its squared rows overflowed); it is
    refused now, and the ends of the range solve the target."""
    panda, target = _panda()
    with pytest.raises(InvalidArgumentError, match=r"^Pose\.weight must be between"):
        swarm_ik.IKProblem(panda, goals=[G.Pose(panda.ee_frame, target, weight=1e308)])
    for weight in (1e-6, 1e6):
        goal = G.Pose(panda.ee_frame, target, weight=weight)
        assert goal.weight == weight
        res = swarm_ik.solve(swarm_ik.IKProblem(panda, goals=[goal]), seed=0, time_limit=5.0)
        assert res.success, (weight, res.reason)


@pytest.mark.parametrize("w_rot", [1e308, 1e7, 1e-9])
def test_w_rot_outside_the_range_is_refused(w_rot: float) -> None:
    """``w_rot=1e308`` overflowed the se3 fitness (``w_rot·θ`` = inf) of the swarm solvers."""
    panda, target = _panda()
    match = r"^w_rot must be 0 \(position only\) or between 1e-6 and 1e6"
    with pytest.raises(InvalidArgumentError, match=match):
        swarm_ik.IKProblem(panda, target, w_rot=w_rot)
    with pytest.raises(InvalidArgumentError, match=match):
        swarm_ik.IKSolver(panda, w_rot=w_rot)
    # 0 stays legal (position only), and so do the ends of the range
    assert swarm_ik.IKProblem(panda, target, w_rot=0.0).position_only
    assert swarm_ik.IKProblem(panda, target, w_rot=1e-6).w_rot == 1e-6
    assert swarm_ik.IKProblem(panda, target, w_rot=1e6).w_rot == 1e6


# ------------------------------------------------------------------ 2. Scene(non-list)
def test_scene_of_none_is_refused_in_one_line() -> None:
    with pytest.raises(InvalidArgumentError) as info:
        swarm_ik.Scene(None)  # type: ignore[arg-type]
    msg = str(info.value)
    assert msg.startswith("Scene takes a list of shapes (Sphere, Box, Capsule, Cylinder, Mesh)")
    assert "got None" in msg and "Scene()" in msg


def test_scene_of_a_dict_points_to_from_dict_and_load() -> None:
    with pytest.raises(InvalidArgumentError) as info:
        swarm_ik.Scene({"obstacles": []})  # type: ignore[arg-type]
    msg = str(info.value)
    assert msg.startswith("Scene takes a list of shapes")
    assert "got a dict" in msg and "Scene.from_dict(data)" in msg and "Scene.load(path)" in msg
    assert "'obstacles'" not in msg  # (it no longer iterates the dict's keys)
    assert swarm_ik.Scene.from_dict({"obstacles": []}) == swarm_ik.Scene([])


@pytest.mark.parametrize("value", ["scene.json", Path("scene.json"), 3])
def test_scene_of_a_path_or_number_is_refused(value: object) -> None:
    with pytest.raises(InvalidArgumentError, match=r"^Scene takes a list of shapes") as info:
        swarm_ik.Scene(value)  # type: ignore[arg-type]
    if not isinstance(value, int):
        assert "Scene.load(path)" in str(info.value)


# ------------------------------------------------------------------ 3. repeated JSON keys
_TWICE = (
    '[{"type": "Position", "frame": "panda_hand_tcp", "frame": "panda_link0", '
    '"point": [0.5, 0.0, 0.3]}]'
)


def test_goals_file_with_a_key_given_twice_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "goals.json"
    path.write_text(_TWICE)
    with pytest.raises(InvalidArgumentError, match="key 'frame' given twice") as info:
        G.load_goals(path)
    assert str(path) in str(info.value)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('[{"type": "Position", "frame": "panda_hand_tcp", "point": [0.5, 0, 0.3], '
         '"weight": 1e308}]',
         "Position.weight must be between 1e-6 and 1e6 (weights are relative)"),
        ('{"goals": [{"type": "Position", "frame": "panda_hand_tcp", '
         '"point": [0.5, 0.0, 0.3], "point": [0.4, 0.0, 0.3]}]}',
         "key 'point' given twice"),
    ],
)  # fmt: skip
def test_bad_goals_files_exit_2_with_one_line(
    text: str, message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A weight outside the range, a key given twice: exit 2, one line naming it."""
    path = tmp_path / "goals.json"
    path.write_text(text)
    assert main(["solve", "--robot", "panda", "--goals", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err


# ------------------------------------------------------------------ 4. rotation_error
def test_rotation_error_without_rotation_goals_is_documented_zero() -> None:
    """The documented convention (``largest_errors``, README, docs/goals.md): the summary
    figure is 0.0 where no primary goal has such an error; ``goal_errors`` holds NaN there."""
    panda, target = _panda()
    problem = swarm_ik.IKProblem(panda, goals=[G.Position(panda.ee_frame, target[:3, 3])])
    res = swarm_ik.solve(problem, seed=0)
    assert res.success
    assert math.isnan(res.goal_errors[0].rotation_error)
    assert res.rotation_error == 0.0
    assert largest_errors(res.goal_errors) == (res.position_error, res.rotation_error)
    assert res.rotation_error < 1e-5  # (a tolerance check still reads as met)
    doc = " ".join((Result.__doc__ or "").split())
    assert "0.0 when no primary goal has an angular error" in doc
    assert "0.0 when no primary goal has a position error" in doc
    goals_md = Path(__file__).resolve().parents[1] / "docs" / "goals.md"
    assert "nothing to measure" in goals_md.read_text()


def test_every_refusal_is_a_swarm_ik_error() -> None:
    panda, target = _panda()
    for make in (
        lambda: G.Orientation(panda.ee_frame, target[:3, :3], weight=1e308),
        lambda: swarm_ik.Scene(None),  # type: ignore[arg-type]
        lambda: G.AvoidCollisions({"obstacles": []}),
    ):
        with pytest.raises(SwarmIKError):
            make()


@pytest.mark.parametrize(
    "call",
    [
        lambda r, T, P: swarm_ik.load_robot("panda", foo=1),
        lambda r, T, P: swarm_ik.IKProblem(r, T, foo=1),
        lambda r, T, P: swarm_ik.IKSolver(r).solve(T, foo=1),
        lambda r, T, P: swarm_ik.solve_many(P, foo=1),
        lambda r, T, P: swarm_ik.solve_batch(r, [T], foo=1),
        lambda r, T, P: swarm_ik.solve_path(r, [T, T], foo=1),
    ],
)
def test_an_unknown_keyword_is_a_swarm_ik_error_at_every_entry_point(call) -> None:
    """``solve`` refused an unknown keyword with InvalidArgumentError, the other entry points
    with Python's bare TypeError (missed by ``except SwarmIKError``)."""
    r = swarm_ik.load_robot("panda")
    T = r.fk(r.mid_q())
    with pytest.raises(
        swarm_ik.errors.InvalidArgumentError,
        match=r"unexpected keyword argument 'foo'; its arguments: ",
    ):
        call(r, T, swarm_ik.IKProblem(r, T))


def test_a_type_error_inside_an_entry_point_is_not_taken_for_a_bad_keyword(monkeypatch) -> None:
    from swarm_ik._validate import keywords_checked

    @keywords_checked
    def inner(x: int) -> int:
        return x + "a"  # type: ignore[operator]

    with pytest.raises(TypeError, match="unsupported operand"):
        inner(1)


def test_an_on_improvement_that_is_not_callable_is_refused_before_the_solve() -> None:
    r = swarm_ik.load_robot("ur5")
    with pytest.raises(
        swarm_ik.errors.InvalidArgumentError, match="on_improvement must be None or a callable"
    ):
        swarm_ik.solve(swarm_ik.IKProblem(r, r.fk(r.mid_q())), on_improvement=5, max_evals=50)


@pytest.mark.parametrize("shape", [(4, 4), (2, 3)])
def test_orientation_given_a_matrix_not_3x3_says_so(shape: tuple[int, int]) -> None:
    """A 4×4 pose given to Orientation was refused as "quaternion must be 4 numbers, got 16
    numbers"; the message now names the matrix (and Pose, for a 4×4)."""
    with pytest.raises(swarm_ik.errors.InvalidTargetError, match=r"\(3, 3\) rotation matrix") as e:
        G.Orientation("panda_hand", np.eye(*shape))
    assert ("use Pose" in str(e.value)) == (shape == (4, 4))
    assert G.Orientation("panda_hand", [[0.0, 0.0, 0.0, 1.0]]).rotation.shape == (3, 3)
