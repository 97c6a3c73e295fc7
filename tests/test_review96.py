"""Review 96 (the command line, held out): a number past Python's digit cap in a goals file,
the batch's time limit charged with drawing its targets, and a Ctrl-C a paper solver's loop
lost raised again at its next evaluation."""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import cli_error

import swarm_ik
import swarm_ik.batch
from swarm_ik import cli, kernels


def test_a_goals_file_with_an_integer_past_the_digit_cap_is_refused_by_name(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Python's int() refuses more than 4,300 digits: an internal error (exit 3) before."""
    path = tmp_path / "goals.json"
    weight = "1" + "0" * 5000
    path.write_text(
        '[{"type": "Position", "frame": "panda_hand_tcp", "point": [0.4, 0, 0.4], '
        f'"weight": {weight}}}]'
    )
    msg = cli_error(capsys, "solve", "--robot", "panda", "--goals", str(path))
    assert "weight" in msg and "inf" in msg


def test_the_batch_time_limit_is_charged_with_drawing_the_targets(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Drawing FK targets came before the limit's clock (1 s took 5.8 s for a million)."""
    seen: dict[str, Any] = {}
    real_batch = swarm_ik.batch.solve_batch
    real_fk = swarm_ik.RobotModel.fk

    def slow_fk(self: Any, q: Any) -> Any:
        time.sleep(0.15)  # (drawing the targets takes a while)
        return real_fk(self, q)

    def recording(*args: Any, **kwargs: Any) -> Any:
        seen["time_limit"] = kwargs["time_limit"]
        return real_batch(*args, **kwargs)

    monkeypatch.setattr(swarm_ik.RobotModel, "fk", slow_fk)
    monkeypatch.setattr(swarm_ik.batch, "solve_batch", recording)
    out = tmp_path / "b.npz"
    argv = ["batch", "--robot", "panda", "--random", "50", "--time-limit", "1.0"]
    assert cli.main([*argv, "--out", str(out), "--no-progress"]) in (0, 1)
    assert 0.5 <= seen["time_limit"] <= 1.0 - 0.15


def test_a_lost_ctrl_c_ends_a_paper_solver_at_its_next_evaluation(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A Ctrl-C counted but lost on its way (in a clock read or an extension) ran a paper
    solver's loop on to its budget (1 of 25 Ctrl-Cs of a PSO solve); the evaluator raises it
    again."""
    robot = swarm_ik.load_robot("panda")
    problem = swarm_ik.IKProblem(robot, robot.fk(robot.random_q(np.random.default_rng(0))))
    monkeypatch.setattr(kernels, "SIGINTS", [1])
    with pytest.raises(KeyboardInterrupt):
        swarm_ik.solve(problem, "pso", max_evals=10_000, iterations=50)


def test_warmup_fresh_clears_the_cache_before_loading_a_kernel(
    planar2_urdf: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A cache file damaged so that loading it aborts the process inside LLVM (no Python
    handler sees it) is remedied by ``swarm-ik warmup --fresh``: the files removed before
    anything loads from them (here the removal is recorded, not done: this process's own
    kernels stay cached)."""
    calls: list[bool] = []
    real_load = swarm_ik.load_robot

    def recording_clear() -> list[str]:
        calls.append(True)
        return ["a.nbc", "a.nbi"]

    def load_after_clear(*args: Any, **kwargs: Any) -> Any:
        assert calls, "a robot (and its kernels) loaded before the cache was cleared"
        return real_load(*args, **kwargs)

    monkeypatch.setattr(kernels, "clear_cache", recording_clear)
    monkeypatch.setattr(swarm_ik, "load_robot", load_after_clear)
    assert cli.main(["warmup", "--fresh", "--robot", planar2_urdf]) == 0
    captured = capsys.readouterr()
    assert calls == [True]
    assert captured.err.splitlines()[0] == "removed 2 numba cache file(s)"
    assert "kernels ready" in captured.out


def test_clear_cache_removes_every_cache_file_of_swarm_ik(tmp_path: Path) -> None:
    """In a process whose numba cache is ``tmp_path``: each of swarm_ik's cache files there
    is removed, and nothing else."""
    import subprocess
    import sys

    code = (
        "import os, pickle, sys\n"
        "import swarm_ik.kernels as k\n"
        "folders = k.cache_folders(sys.argv[1])\n"
        "for d in folders[:2]:\n"
        "    os.makedirs(d, exist_ok=True)\n"
        "    for name in ('f-1.py311.nbi', 'f-1.py311.1.nbc', 'keep.txt'):\n"
        "        open(os.path.join(d, name), 'wb').write(pickle.dumps(1))\n"
        "removed = k.clear_cache()\n"
        "left = sorted(n for d in folders[:2] for n in os.listdir(d))\n"
        "print(len(removed), left)\n"
    )
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    out = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path)],
        capture_output=True, text=True, timeout=300, env=env,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert out.stdout.split(maxsplit=1) == ["4", "['keep.txt', 'keep.txt']\n"]
