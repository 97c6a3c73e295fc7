"""swarm_ik.reach: the grid size is checked before allocating, the HTML page is the viewer's
scene (point cloud, robot, colour legend), and the command line (swarm_ik.cli.reach) refuses
an output asked for without its extra before computing, and skips one not asked for with a
note (its bad output paths are tested with the other commands' in ``tests/test_cli.py``)."""

from __future__ import annotations

import argparse
import base64
import re
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import never

import swarm_ik
from swarm_ik import cli, reach
from swarm_ik.cli import reach as reach_cli
from swarm_ik.errors import InvalidArgumentError


@pytest.fixture(scope="module")
def yumi() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot("yumi_left")


def _parse(*argv: str) -> argparse.Namespace:
    subparsers = argparse.ArgumentParser().add_subparsers()
    return reach_cli.add_parser(subparsers).parse_args(list(argv))


@pytest.mark.parametrize("resolution", [0.002, 1e-4, 1e-300])
def test_grid_too_fine_is_refused_before_allocating(
    yumi: swarm_ik.RobotModel, resolution: float
) -> None:
    t0 = time.perf_counter()
    with pytest.raises(InvalidArgumentError, match="coarser resolution") as info:
        reach.reach_map(yumi, resolution=resolution)
    assert time.perf_counter() - t0 < 5.0  # refused at once, nothing allocated
    assert "\n" not in str(info.value) and "GB of targets" in str(info.value)


def test_check_grid_size_counts_the_box() -> None:
    assert reach.check_grid_size([0, 0, 0], [1, 1, 1], 0.25, 2, 1000) == 64
    with pytest.raises(InvalidArgumentError, match="at least"):
        reach.check_grid_size([0, 0, 0], [1, 1, 1], 0.25, 2, 100)


def _objects(html: str) -> dict[str, Any]:
    """The ``set_object`` commands of a page exported by meshcat, by path."""
    import umsgpack

    page = html[html.index("new MeshCat.Viewer") :]
    cmds = [
        umsgpack.unpackb(base64.b64decode(b))
        for b in re.findall(r'base64,([A-Za-z0-9+/=]+)"', page)
    ]
    return {c["path"]: c for c in cmds if c["type"] == "set_object"}


def test_html_is_the_scene_with_robot_and_legend(yumi: swarm_ik.RobotModel, tmp_path: Path) -> None:
    pytest.importorskip("meshcat")
    rmap = reach.reach_map(yumi, resolution=0.25, n_orientations=2, max_starts=4)
    objects = _objects(reach.export_html(rmap, tmp_path / "m.html").read_text())
    cloud = objects["/meshcat/swarm_ik/reachability/voxels"]["object"]["geometries"][0]
    n_points = len(cloud["data"]["attributes"]["position"]["array"].data) // (4 * 3)
    assert n_points == int((rmap.index > 0).sum())
    assert any(p.startswith("/meshcat/swarm_ik/robot/visuals/") for p in objects)  # the robot
    assert "/meshcat/swarm_ik/legend/shape" in objects  # the colour legend
    with pytest.raises(InvalidArgumentError, match="does not exist"):
        reach.export_html(rmap, tmp_path / "nowhere" / "m.html")


def test_cli_defaults_to_no_scheduler() -> None:
    assert _parse("--robot", "yumi_left").scheduler == "none"


BLOCK = {"--png": "matplotlib.pyplot", "--html": "meshcat.geometry"}
"""A submodule that each output imports: None in ``sys.modules`` makes its import fail, as
when the extra is missing or broken (the package itself is still found)."""


@pytest.mark.parametrize("option", ["--png", "--html"])
def test_cli_output_asked_for_without_its_extra_is_refused_first(
    option: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    refused: Callable[..., str],
) -> None:
    """``--png FILE`` / ``--html FILE`` whose extra does not import: exit 2, one line naming
    the extra, before a robot is loaded or any file written (the command solved and wrote
    the map, then failed on the picture)."""
    monkeypatch.setitem(sys.modules, BLOCK[option], None)
    monkeypatch.setattr(reach, "reach_map", never)
    suffix = ".png" if option == "--png" else ".html"
    line = refused(
        "reach", "--robot", "yumi_left", "--out", str(tmp_path / "m.npz"),
        option, str(tmp_path / f"m{suffix}"),
    )  # fmt: skip
    extra = "plot" if option == "--png" else "viz"
    assert option in line and f'pip install "swarm_ik[{extra}]"' in line
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("blocked", [("--png",), ("--html",), ("--png", "--html")])
def test_cli_output_not_asked_for_without_its_extra_is_skipped_with_a_note(
    blocked: tuple[str, ...],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """A picture written by default whose extra does not import is left out, said in one line
    on stderr before the work, and the map is written (it was a failure after the work)."""
    for option in blocked:
        monkeypatch.setitem(sys.modules, BLOCK[option], None)
    said: list[str] = []
    compute = reach.reach_map

    def reach_map(*args: Any, **kwargs: Any) -> reach.ReachMap:
        said.append(capsys.readouterr().err)  # what was said before the work
        return compute(*args, **kwargs)

    monkeypatch.setattr(reach, "reach_map", reach_map)
    out = tmp_path / "m.npz"
    argv = [
        "reach", "--robot", "yumi_left", "--resolution", "0.25", "--orientations", "2",
        "--max-starts", "4", "--out", str(out), "--no-progress",
    ]  # fmt: skip
    assert cli.main(argv) == 0
    err = capsys.readouterr().err
    assert err == "" and len(said) == 1 and len(said[0].strip().splitlines()) == 1
    note = said[0]
    for option, module, extra in (("--png", "matplotlib", "plot"), ("--html", "meshcat", "viz")):
        if option in blocked:
            assert f"needs {module}" in note and f'"swarm_ik[{extra}]"' in note
            assert f"--no-{option[2:]}" in note
    assert reach.ReachMap.load(out).n_orientations == 2
    assert out.with_suffix(".png").exists() == ("--png" not in blocked)
    if "--html" in blocked:
        assert not out.with_suffix(".html").exists()


def test_cli_writes_map_picture_and_page(tmp_path: Path, capsys: Any) -> None:
    out = tmp_path / "yumi.npz"
    args = _parse(
        "--robot", "yumi_left", "--resolution", "0.25", "--orientations", "2",
        "--max-starts", "4", "--out", str(out), "--no-progress",
    )  # fmt: skip
    assert reach_cli.run(args) == 0
    assert "reachable voxels" in capsys.readouterr().out
    rmap = reach.ReachMap.load(out)
    assert rmap.n_orientations == 2
    assert out.with_suffix(".png").stat().st_size > 10_000
    if reach_cli.has_extra("--html"):
        assert "MeshCat.Viewer" in out.with_suffix(".html").read_text()
    np.testing.assert_array_equal(rmap.index, rmap.hits.mean(axis=-1))


def test_a_saved_map_keeps_its_urdf_and_draws_that_robot_not_a_namesake(
    yumi: swarm_ik.RobotModel, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The map kept only the robot's name: a map of a user's URDF was drawn with whatever
    robot that name loads.  It keeps the URDF file and loads from it (a file gone: no
    robot drawn, not a namesake)."""
    rmap = reach.reach_map(yumi, resolution=0.25, n_orientations=2, max_starts=4)
    assert rmap.urdf == str(yumi.urdf_path)
    again = reach.ReachMap.load(rmap.save(tmp_path / "m.npz"))
    assert again.urdf == rmap.urdf
    asked: list[str] = []

    def load_robot(source: Any, **kwargs: Any) -> Any:
        asked.append(str(source))
        raise swarm_ik.errors.RobotFileNotFoundError("gone")

    pytest.importorskip("meshcat")
    monkeypatch.setattr(swarm_ik, "load_robot", load_robot)
    objects = _objects(reach.export_html(again, tmp_path / "m.html").read_text())
    assert asked == [rmap.urdf]
    assert not any("/robot/" in p for p in objects) and any("voxels" in p for p in objects)
