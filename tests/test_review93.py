"""Review 93 (a new user on a fresh clone): example 04 without matplotlib, joint values beyond
the limits given for a target (degrees?), a Ctrl-C while kernels load taken for a damaged
cache, and the hint of a frame the robot does not have."""

from __future__ import annotations

import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import robot

import swarm_ik
from swarm_ik import kernels
from swarm_ik.cli import main
from swarm_ik.errors import UnknownNameError
from swarm_ik.goals import Position

EXAMPLE_04 = Path(__file__).resolve().parents[1] / "examples" / "04_compare_solvers.py"

BLOCK_MATPLOTLIB = f"""
import runpy, sys
class Block:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] == "matplotlib":
            raise ImportError("blocked")
sys.meta_path.insert(0, Block())
sys.argv = ["04"]
runpy.run_path({str(EXAMPLE_04)!r}, run_name="__main__")
"""


def test_example_04_prints_its_table_without_matplotlib() -> None:
    out = subprocess.run(
        [sys.executable, "-c", BLOCK_MATPLOTLIB], capture_output=True, text=True, timeout=600,
        env={**__import__("os").environ, "SWARM_IK_QUICK": "1"},
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert "swarm" in out.stdout and "plot skipped" in out.stdout and "[plot]" in out.stdout
    assert "Traceback" not in out.stderr


def test_a_target_from_joint_values_beyond_the_limits_warns() -> None:
    r = robot("panda")
    degrees = np.degrees(r.mid_q() + 0.3)
    with pytest.warns(UserWarning, match="outside the joint limits .*degrees"):
        swarm_ik.IKProblem.from_q(r, degrees)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        swarm_ik.IKProblem.from_q(r, r.mid_q())  # (within them: nothing said)


def test_the_cli_says_from_q_lies_beyond_the_limits(capsys) -> None:
    code = main(["solve", "--robot", "yumi_left", "--from-q", "17", "-46", "23", "34", "-29",
                 "69", "40"])  # fmt: skip
    err = capsys.readouterr().err
    assert code in (0, 1) and "--from-q lies outside the joint limits" in err
    assert len(err.strip().splitlines()) == 1


def test_a_counted_ctrl_c_while_kernels_load_is_no_damaged_cache(monkeypatch) -> None:
    """An error of numba's cache loader after a Ctrl-C (``RuntimeError: no compiled object
    yet``) is the interruption: ``KeyboardInterrupt``, and no cache file removed."""
    removed: list[object] = []
    monkeypatch.setattr(kernels, "drop_cache_files", lambda folders: removed.append(1) or [1])
    monkeypatch.setattr(kernels, "_raised_loading_a_cache", lambda exc: True)
    monkeypatch.setattr(kernels, "SIGINTS", [1])

    def load() -> None:
        raise RuntimeError("no compiled object yet for <Library '_search_state'>")

    with pytest.raises(KeyboardInterrupt):
        kernels.loaded_despite_damage(load)
    assert not removed


def test_a_frame_the_robot_does_not_have_is_called_unknown() -> None:
    """``tool0`` on a Panda: not "load the robot with every goal frame" (which fails next)."""
    r = robot("panda")
    with pytest.raises(UnknownNameError, match="unknown frame 'tool0'") as info:
        swarm_ik.IKProblem(r, goals=[Position("tool0", [0.4, 0.0, 0.4])])
    assert "--frame" not in str(info.value)
    with pytest.raises(UnknownNameError, match="not a goal frame .* --frame panda_link3"):
        swarm_ik.IKProblem(r, goals=[Position("panda_link3", [0.4, 0.0, 0.4])])
