"""Review 109 (held out: the command line, caches, a cold start): counts that could run for
hours or fill the memory are refused first; a batch's bad settings are refused before its
kernels load; the exit code stays the command's when standard error cannot be written; a
help that cannot be written exits 74."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

import swarm_ik
from swarm_ik import batch, many, reach

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _cli(*argv: str, stdout: object = subprocess.PIPE, stderr: object = subprocess.PIPE):
    return subprocess.run(
        [sys.executable, "-m", "swarm_ik.cli", *argv],
        stdout=stdout, stderr=stderr, text=True, timeout=300, cwd=ROOT,
    )  # fmt: skip


@pytest.fixture(scope="module")
def panda() -> swarm_ik.RobotModel:
    return swarm_ik.load_robot("panda")


def test_solve_many_refuses_more_solutions_than_it_can_compare(panda) -> None:
    """n = 10¹² ran for hours without a budget (the branch set is compared as it grows)."""
    problem = swarm_ik.IKProblem(panda, panda.fk(panda.mid_q()))
    with pytest.raises(swarm_ik.InvalidArgumentError, match=r"n must be an integer in \[1, "):
        swarm_ik.solve_many(problem, n=10**12, max_evals=100)  # (the budget: no hang here)
    with pytest.raises(swarm_ik.InvalidArgumentError):
        swarm_ik.solve_many(problem, n=many.MAX_SOLUTIONS + 1, max_evals=100)
    assert len(swarm_ik.solve_many(problem, n=2, max_evals=3000)) >= 1


def test_a_reach_map_refuses_a_cap_beyond_one_batch_before_building_its_grid(panda) -> None:
    with pytest.raises(swarm_ik.InvalidArgumentError, match="max_targets"):
        reach.reach_map(panda, resolution=0.01, max_targets=batch.MAX_TARGETS + 1)
    out = _cli("reach", "--robot", "ur5", "--resolution", "0.0098", "--max-targets",
               "1000000000", "--out", "never/rr.npz", "--no-png", "--no-html")  # fmt: skip
    assert out.returncode == 2 and "--max-targets" in out.stderr, out.stderr
    assert len(out.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("kw", [{"chunk_size": 0}, {"scheduler": "bogus"}])
def test_a_batch_refuses_its_settings_before_loading_kernels(panda, kw, monkeypatch) -> None:
    """They were refused after the kernels loaded (17 s on an empty cache)."""

    def loading(*args: object) -> float:
        raise AssertionError("kernels loaded before the settings were checked")

    monkeypatch.setattr(batch, "_load_kernels", loading)
    with pytest.raises(swarm_ik.InvalidArgumentError):
        swarm_ik.solve_batch(panda, panda.fk(panda.mid_q())[None], **kw)


def test_the_exit_code_is_the_commands_when_standard_error_cannot_be_written() -> None:
    with open(os.devnull, "w") as sink, open("/dev/full", "w") as full:
        bad = _cli("solve", "--robot", "nosuch", "--pose", "0.4", "0.1", "0.5", "1", "0", "0",
                   "0", stdout=sink, stderr=full)  # fmt: skip
        assert bad.returncode == 2
        # (a q outside the limits warns; the warning cannot be written, the solve goes on)
        ok = _cli("solve", "--robot", "panda", "--from-q", "9", "0", "0", "-1", "0", "1", "0",
                  stderr=full)  # fmt: skip
    assert ok.returncode == 0 and "converged" in ok.stdout


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full")
@pytest.mark.parametrize("argv", [["--help"], ["solve", "--help"]])
def test_a_help_that_cannot_be_written_exits_74(argv) -> None:
    with open("/dev/full", "w") as full:
        out = _cli(*argv, stdout=full)
    assert out.returncode == 74 and "cannot write" in out.stderr, out.stderr
    assert _cli(*argv).returncode == 0


def test_an_embedded_dask_cluster_leaves_port_8787_alone(panda) -> None:
    """Review 114: the embedded cluster's scheduler served HTTP on 8787 (dashboard_address=None
    is Dask's default port, not none) and warned in four lines where another program held it."""
    pytest.importorskip("distributed")
    import socket
    import warnings

    held = socket.socket()
    try:
        held.bind(("127.0.0.1", 8787))
    except OSError:
        pytest.skip("port 8787 is taken on this machine")
    held.listen()
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("error", message=".*8787")  # (the port's warning fails)
            res = swarm_ik.solve_batch(panda, panda.fk(panda.mid_q())[None], scheduler="local")
    finally:
        held.close()
    assert res.success.all()


def test_the_resolution_a_refused_reach_map_suggests_is_accepted() -> None:
    """Review 116: the voxels' cap suggested 0.00972 m for a UR5 map, which the poses' cap
    (8 orientations, 5·10⁶ poses) then refused; a map of positions was told to use fewer
    orientations, though it has one."""
    import re

    robot = swarm_ik.load_robot("ur5")
    lo, hi = reach.default_bounds(robot, seed=0)
    for k in (8, 1):
        with pytest.raises(swarm_ik.InvalidArgumentError) as info:
            reach.check_grid_size(lo, hi, 0.005, k, reach.MAX_TARGETS)
        suggested = float(re.search(r"at least ([0-9.e-]+) m", str(info.value)).group(1))
        assert reach.check_grid_size(lo, hi, suggested, k, reach.MAX_TARGETS) > 0
        assert ("fewer orientations" in str(info.value)) == (k > 1)


def test_a_prismatic_mimic_joint_s_travel_counts_in_the_reach_bound(tmp_path) -> None:
    """Review 116: chain_reach_bound left out a mimic follower's stroke, and a map marked
    voxels 0.8-2.3 m away unreachable without solving them (reach_radius counted it)."""
    urdf = tmp_path / "slide.urdf"
    limit = '<limit lower="{}" upper="{}" effort="1" velocity="1"/>'
    urdf.write_text(
        '<robot name="s"><link name="b"/><link name="a"/><link name="c"/><link name="t"/>'
        '<joint name="j0" type="revolute"><parent link="b"/><child link="a"/>'
        '<axis xyz="0 0 1"/>' + limit.format(-3, 3) + "</joint>"
        '<joint name="j1" type="prismatic"><parent link="a"/><child link="c"/>'
        '<origin xyz="0.3 0 0.1"/><axis xyz="1 0 0"/>' + limit.format(0, 0.5) + "</joint>"
        '<joint name="j2" type="prismatic"><parent link="c"/><child link="t"/>'
        '<axis xyz="1 0 0"/>' + limit.format(0, 1.5) + '<mimic joint="j1" multiplier="3"/>'
        "</joint></robot>"
    )
    robot = swarm_ik.load_robot(urdf, "t")
    _, radius = reach.chain_reach_bound(robot)
    tip = robot.fk(robot.upper)[:3, 3]
    assert radius >= float(np.linalg.norm(tip)) - 1e-12 and radius >= 2.3 - 1e-9
