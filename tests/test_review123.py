"""Held-out review 123 (examples, viewer, listing): what it found, pinned as behaviour."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import pytest

import swarm_ik
from swarm_ik.errors import InvalidArgumentError, RobotModelError
from swarm_ik.paths import written_in_place_of


def test_a_page_is_never_written_over_a_fifo_or_a_link_to_one(tmp_path: Path) -> None:
    """``Scene.save_html`` followed links and replaced what it found: a device node became
    an 885 kB page.  (A FIFO stands in for a device: making one needs no privilege.)"""
    pytest.importorskip("meshcat")
    from swarm_ik import viz

    fifo = tmp_path / "pipe.html"
    os.mkfifo(fifo)
    (tmp_path / "link.html").symlink_to(fifo)
    robot = swarm_ik.load_robot("yumi_left")
    scene = viz.show_pose(robot, robot.mid_q())
    try:
        for name in ("pipe.html", "link.html"):
            with pytest.raises(InvalidArgumentError, match="is a named pipe"):
                scene.save_html(tmp_path / name)
        with pytest.raises(argparse.ArgumentTypeError, match="is a named pipe"):
            viz.output_file(".html")(str(tmp_path / "link.html"))  # (the examples' --html)
    finally:
        scene.close()
    assert fifo.exists() and not fifo.is_file()


def test_a_write_that_fails_names_the_file_asked_for(tmp_path: Path) -> None:
    """A full disk during a page's write gave ``cannot write (No space left on device)``
    without the file."""
    target = tmp_path / "page.html"
    with pytest.raises(OSError, match="No space left") as info:
        with written_in_place_of(target) as part:
            part.write_text("x")
            raise OSError(28, "No space left on device")
    assert info.value.filename == str(target)
    assert not target.exists() and not list(tmp_path.iterdir())  # (no part left behind)


def test_the_viewer_of_a_script_without_a_terminal_says_so_and_closes() -> None:
    """Examples 07, 09 and 10 printed a viewer's address and exited at once, the server gone."""
    from swarm_ik.viz.scene import served

    closed: list[int] = []

    class _Viewer:
        def close(self) -> None:
            closed.append(1)

    line = served(_Viewer(), _Viewer())  # type: ignore[arg-type]
    assert line.startswith("no terminal to wait on") and closed == [1, 1]


def test_a_free_flying_robot_loaded_without_a_floating_base_is_told_how() -> None:
    with pytest.raises(RobotModelError, match="load it with floating_base=True"):
        swarm_ik.load_robot("iris_simple")
    assert swarm_ik.load_robot("iris_simple", floating_base=True).nq == 6


def test_a_script_asked_for_a_page_without_meshcat_exits_2(monkeypatch, capsys) -> None:  # type: ignore[no-untyped-def]
    """Example 07 with ``--html FILE`` and no meshcat printed "viewer skipped" and exited 0,
    no page written."""
    from swarm_ik.viz import scene as viz_scene

    def missing() -> None:
        raise viz_scene.VizUnavailableError("the viewer needs meshcat")

    monkeypatch.setattr(viz_scene, "require_meshcat", missing)
    assert viz_scene.viewer_for(None) is False
    assert "viewer skipped" in capsys.readouterr().out
    with pytest.raises(SystemExit) as info:
        viz_scene.viewer_for("page.html")
    assert info.value.code == 2 and "cannot write page.html" in capsys.readouterr().err
