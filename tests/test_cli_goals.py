"""``swarm-ik solve --goals``, repeated ``--frame`` and ``--position-only``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from swarm_ik.cli import main


def _goals(tmp_path: Path, goals: object) -> str:
    path = tmp_path / "goals.json"
    path.write_text(json.dumps(goals))
    return str(path)


def test_goals_file_is_solved(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    f = _goals(tmp_path, [
        {"type": "Position", "frame": "panda_hand_tcp", "point": [0.5, 0.0, 0.3]},
        {"type": "Axis", "frame": "panda_hand_tcp", "axis": [0, 0, 1], "direction": [0, 0, -1]},
    ])  # fmt: skip
    assert main(["solve", "--robot", "panda", "--goals", f, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["success"] and [g["goal"] for g in out["goal_errors"]] == [
        "Position(panda_hand_tcp)", "Axis(panda_hand_tcp)"]  # fmt: skip


def test_repeated_frame_poses_every_frame(capsys: pytest.CaptureFixture[str]) -> None:
    q = ["0.1"] * 14
    code = main(["solve", "--robot", "baxter", "--frame", "left_gripper", "--frame",
                 "right_gripper", "--from-q", *q, "--json"])  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["frames"] == ["left_gripper", "right_gripper"]
    assert len(out["goal_errors"]) == 2


def test_position_only_on_a_short_chain(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["solve", "--robot", "panda", "--position-only", "--pose",
                 "0.4", "0.1", "0.4", "0", "0", "0", "1", "--json"]) == 0  # fmt: skip
    out = json.loads(capsys.readouterr().out)
    # no rotation was asked for, so none is reported (not a measured 0)
    assert out["rotation_error"] is None and out["goal_errors"][0]["goal"].startswith("Position")


@pytest.mark.parametrize(
    "goals,message",
    [
        ([{"type": "Bogus"}], "unknown goal type 'Bogus'"),
        (
            [{"type": "Position", "frame": "nope", "point": [0, 0, 0]}],
            "unknown frame 'nope'; frames of this robot: panda_link0",
        ),
        (
            [{"type": "Position", "frame": "panda_hand_tcp", "point": [0, 0, 0], "x": 1}],
            "unknown field",
        ),
        (
            [
                {
                    "type": "Axis",
                    "frame": "panda_hand_tcp",
                    "axis": [0, 0, 0],
                    "direction": [1, 0, 0],
                }
            ],
            "zero vector",
        ),
        ([{"type": "Position", "frame": "panda_hand_tcp", "point": [0, "nan", 0]}], "text"),
        ([{"type": "Position", "frame": "panda_hand_tcp", "point": [0, 1e400, 0]}], "finite"),
    ],
)
def test_bad_goals_exit_2_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], goals: object, message: str
) -> None:
    assert main(["solve", "--robot", "panda", "--goals", _goals(tmp_path, goals)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_scene_makes_the_answer_collision_free(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from swarm_ik.scene import Box, Scene

    scene = tmp_path / "table.json"
    Scene([Box([0.6, 0.6, 0.04], [0.55, 0.0, -0.02])]).to_json(scene)
    q = ["0.1", "-0.5", "0.3", "-2", "0.2", "1.5", "0.4"]
    assert main(["solve", "--robot", "panda", "--from-q", *q, "--scene", str(scene), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["goal_errors"][-1]["goal"] == "AvoidCollisions" and out["goal_errors"][-1]["met"]
    assert out["goal_errors"][-1]["clearance"] > 0


def test_bad_scene_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.json"
    bad.write_text('{"obstacles": [{"type": "sphere", "radius": -1}]}')
    q = ["0.1", "-0.5", "0.3", "-2", "0.2", "1.5", "0.4"]
    assert main(["solve", "--robot", "panda", "--from-q", *q, "--scene", str(bad)]) == 2
    assert "radius must be a positive" in capsys.readouterr().err


def test_goals_without_a_rotation_report_no_rotation_error(tmp_path, capsys) -> None:
    """A goals file with only a Position goal: the rotation error is "n/a" (text) and null
    (JSON), not 0.0, which reads as a rotation met exactly."""
    f = tmp_path / "goals.json"
    f.write_text(
        '{"goals": [{"type": "Position", "frame": "panda_hand_tcp", "point": [0.5, 0.0, 0.4]}]}'
    )
    assert main(["solve", "--robot", "panda", "--goals", str(f)]) == 0
    out = capsys.readouterr().out
    assert "rotation error n/a (no goal on a rotation)" in out
    assert main(["solve", "--robot", "panda", "--goals", str(f), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["rotation_error"] is None and d["position_error"] < 1e-5


def test_position_only_with_a_goals_file_is_refused(tmp_path, refused) -> None:
    """The flag was ignored there: the file's Pose goals kept their rotation rows, and the
    rotation error that made the solve fail printed as n/a."""
    path = tmp_path / "g.json"
    path.write_text('[{"type": "Position", "frame": "panda_hand_tcp", "point": [0.4, 0, 0.4]}]')
    line = refused("solve", "--robot", "panda", "--goals", str(path), "--position-only")
    assert "--position-only applies to --pose and --from-q" in line


def test_position_only_with_from_q_on_several_frames_solves_positions(capsys) -> None:
    from swarm_ik.cli import main

    q = ["0.1", "-0.5", "0.2", "-2", "0.1", "1.5", "0.3"]
    argv = ["solve", "--robot", "panda", "--frame", "panda_hand_tcp", "--frame", "panda_link4"]
    assert main([*argv, "--from-q", *q, "--position-only", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [g["goal"] for g in out["goal_errors"]] == [
        "Position(panda_hand_tcp)",
        "Position(panda_link4)",
    ]
