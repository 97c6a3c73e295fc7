"""swarm_ik.reach: the grid size is checked before allocating, the HTML page is the viewer's
scene (point cloud, robot, colour legend), and the command line (swarm_ik.cli.reach) refuses
missing extras before computing (its bad output paths are tested with the other commands'
in ``tests/test_cli.py``)."""

from __future__ import annotations

import argparse
import base64
import re
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import swarm_ik
from swarm_ik import reach
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


def test_html_is_the_scene_with_robot_and_legend(yumi: swarm_ik.RobotModel, tmp_path: Path) -> None:
    pytest.importorskip("meshcat")
    import umsgpack

    rmap = reach.reach_map(yumi, resolution=0.25, n_orientations=2, max_starts=4)
    html = reach.export_html(rmap, tmp_path / "m.html").read_text()
    page = html[html.index("new MeshCat.Viewer") :]
    cmds = [
        umsgpack.unpackb(base64.b64decode(b))
        for b in re.findall(r'base64,([A-Za-z0-9+/=]+)"', page)
    ]
    objects = {c["path"]: c for c in cmds if c["type"] == "set_object"}
    cloud = objects["/meshcat/swarm_ik/reachability/voxels"]["object"]["geometries"][0]
    n_points = len(cloud["data"]["attributes"]["position"]["array"].data) // (4 * 3)
    assert n_points == int((rmap.index > 0).sum())
    assert any(p.startswith("/meshcat/swarm_ik/robot/visuals/") for p in objects)  # the robot
    assert "/meshcat/swarm_ik/legend/shape" in objects  # the colour legend
    with pytest.raises(InvalidArgumentError, match="does not exist"):
        reach.export_html(rmap, tmp_path / "nowhere" / "m.html")


def test_cli_defaults_to_no_scheduler() -> None:
    assert _parse("--robot", "yumi_left").scheduler == "none"


def test_cli_missing_matplotlib_is_refused_first(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(reach_cli, "has_module", lambda name: name != "matplotlib")
    monkeypatch.setattr(reach, "reach_map", lambda *a, **k: pytest.fail("computed"))
    with pytest.raises(InvalidArgumentError, match=r"swarm_ik\[plot\].*--no-png"):
        reach_cli.run(_parse("--robot", "yumi_left", "--out", str(tmp_path / "m.npz")))


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
    if reach_cli.has_module("meshcat"):
        assert "MeshCat.Viewer" in out.with_suffix(".html").read_text()
    np.testing.assert_array_equal(rmap.index, rmap.hits.mean(axis=-1))
