"""Review 102 (examples and the viewer, held out): refusals that were missing or came as bare
Python errors, and output paths checked before the work."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import cli_error

import swarm_ik
from swarm_ik.errors import SwarmIKError

pytest.importorskip("meshcat")
from swarm_ik import viz  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
Q = [0.3, -0.5, 0.2, -2.0, 0.1, 1.6, 0.7]


@pytest.mark.parametrize("value", ["-1", "nan"])
def test_show_refuses_a_bad_min_distance_with_a_solver_too(
    value: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """With --solver the check was skipped: -1 gave the same answer three times as "distinct"
    solutions, NaN one solution where three were asked for."""
    argv = ["show", "--robot", "panda", "--from-q", *map(str, Q), "--solutions", "3"]
    argv += ["--min-distance", value, "--solver", "dls", "--html", str(tmp_path / "p.html")]
    assert "min_distance" in cli_error(capsys, *argv)


@pytest.mark.parametrize("command", ["show", "solve"])
def test_an_empty_html_path_is_refused(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    """``--html ""`` was taken as no page: show opened the live viewer, solve drew nothing."""
    msg = cli_error(capsys, command, "--robot", "panda", "--from-q", *map(str, Q), "--html", "")
    assert "--html" in msg and "folder" in msg


@pytest.mark.parametrize(
    ("example", "option"),
    [("04_compare_solvers.py", "--out"), ("07_dual_arm.py", "--html")],
)
def test_an_example_refuses_an_unwritable_output_before_the_work(example: str, option: str) -> None:
    """The examples ran every solve, then died in a traceback writing to a missing folder."""
    suffix = ".png" if option == "--out" else ".html"
    out = subprocess.run(
        [sys.executable, str(ROOT / "examples" / example), option, f"/nonexistent/x{suffix}"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "folder '/nonexistent' does not exist" in out.stderr.splitlines()[-1]
    assert out.stdout == ""  # (nothing solved)


def _calls() -> list[tuple[str, Any]]:
    robot = swarm_ik.load_robot("yumi_left")
    q = robot.mid_q()
    trace = viz.Trace(np.stack([q, q]), np.zeros(2), 0)
    empty = viz.Trace(np.zeros((0, robot.nq)), np.zeros(0), 0)
    scene = viz.show_pose(robot, q)
    two = [q, q]
    return [
        ("spacing", lambda: viz.show_configurations(robot, two, spacing=float("nan"))),
        ("spacing", lambda: viz.show_configurations(robot, two, spacing="a")),
        ("hold_s", lambda: viz.show_configurations(robot, two, layout="steps", hold_s=np.nan)),
        ("hold_s", lambda: viz.animate_trace(scene, robot, trace, hold_s=float("nan"))),
        ("fps", lambda: viz.animate_trace(scene, robot, trace, fps=0)),
        ("nope", lambda: viz.animate_trace(scene, robot, trace, name="nope")),
        ("trace", lambda: viz.animate_trace(scene, robot, empty)),
    ]


def test_bad_viewer_values_are_refused_by_name() -> None:
    """NaN and infinite spacings and hold times raised a bare ValueError (or wrote NaN into the
    page), fps 0 made an animation of 0 frames per second, an unknown drawing a KeyError and an
    empty trace an IndexError."""
    for word, call in _calls():
        with pytest.raises(SwarmIKError, match=word):
            call()


def test_scene_and_view_arguments_of_the_wrong_kind_are_refused_by_name() -> None:
    """The lower-level drawing calls took None for a robot (AttributeError), colours and
    offsets of the wrong length (IndexError, ValueError), a 3x3 or NaN triad pose, a negative
    triad length, an opacity of 2, and a camera with no point or a zero direction."""
    robot = swarm_ik.load_robot("yumi_left")
    q = robot.mid_q()
    scene = viz.Scene()
    calls: list[tuple[str, Any]] = [
        ("robot", lambda: viz.show_pose(None, q)),  # type: ignore[arg-type]
        ("result", lambda: viz.error_lines(None)),  # type: ignore[arg-type]
        ("color", lambda: scene.add_robot(robot, q, color=[1, 2])),
        ("color", lambda: scene.add_robot(robot, q, color=[2, 0, 0, 1])),
        ("offset", lambda: scene.add_robot(robot, q, offset=[1, 2])),
        ("pose", lambda: scene.add_triad("t", np.eye(3))),
        ("pose", lambda: scene.add_triad("t", np.full((4, 4), np.nan))),
        ("length", lambda: scene.add_triad("t", np.eye(4), length=-1)),
        ("opacity", lambda: scene.add_triad("t", np.eye(4), opacity=2)),
        ("sphere", lambda: scene.add_triad("t", np.eye(4), sphere=[1])),
        ("points", lambda: scene.frame_camera(np.zeros((0, 3)))),
        ("direction", lambda: scene.frame_camera(np.zeros((2, 3)), direction=(0, 0, 0))),
    ]
    for word, call in calls:
        with pytest.raises(SwarmIKError, match=word):
            call()
    scene.add_robot(robot, q, color=viz.GHOST_COLOR, offset=[0.1, 0, 0])  # (good ones drawn)
    scene.add_triad("t", np.eye(4), sphere=(1.0, 0.85, 0.1, 0.45))
