"""Review 85 (examples, reach, batch CLI as a user): a Ctrl-C landing in a compiled kernel's
clock read is a KeyboardInterrupt (it was a SystemError, and `batch` lost its finished rows),
reach's suggested resolution fits, a position-only reach map, reach's refusals are the
project's own, and a byte-order mark at the start of a CSV or JSON file is read past."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import WARM_CLI, cli_error, interrupted_when_ready

import swarm_ik
from swarm_ik import _validate, reach
from swarm_ik.batch import read_targets
from swarm_ik.cli import main
from swarm_ik.errors import InvalidArgumentError, SwarmIKError
from swarm_ik.goals import load_goals

posix = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="POSIX signals")


API = """
import time, numpy as np, swarm_ik
robot = swarm_ik.load_robot("panda")
far = np.tile(np.eye(4), (40000, 1, 1)); far[:, :3, 3] = 5.0
T = robot.fk(robot.random_q(np.random.default_rng(0)))
swarm_ik.solve(swarm_ik.IKProblem(robot, T))
swarm_ik.solve_batch(robot, far[:1], max_starts=1)
print("ready", flush=True)
try:
    if MODE == "batch":
        res = swarm_ik.solve_batch(robot, far, chunk_size=200, keep_on_interrupt=True)
        print("returned", res.interrupted, res.q.shape[0] % 200 == 0, 0 < res.q.shape[0] < 40000)
    else:  # a search that never meets its tolerances: it runs to its 30 s limit
        swarm_ik.solve(swarm_ik.IKProblem(robot, T), time_limit=30.0, tol_pos=1e-300,
                       tol_rot=1e-300)
        print("returned")
except BaseException as exc:
    print("raised", type(exc).__name__)
"""


@posix
@pytest.mark.parametrize(
    ("mode", "expected"),
    [("batch", "returned True True True"), ("solve", "raised KeyboardInterrupt")],
)
def test_a_ctrl_c_in_a_kernel_is_a_keyboard_interrupt(
    mode: str, expected: str, tmp_path: Path
) -> None:
    """Targets out of reach make the batch kernel read its clock often (restarts), and a
    Ctrl-C handled there came out as ``SystemError … wall_clock … returned a result with an
    exception set``: ``keep_on_interrupt`` kept nothing, a user's ``except KeyboardInterrupt``
    missed it."""
    script = tmp_path / "run.py"
    script.write_text(f"MODE = {mode!r}\n" + API)
    rc, out, _took = interrupted_when_ready([sys.executable, str(script)], tmp_path)
    assert expected in out, out
    assert "SystemError" not in out


@posix
def test_cli_batch_keeps_its_finished_rows_when_targets_need_restarts(tmp_path: Path) -> None:
    far = tmp_path / "far.csv"
    far.write_text("x,y,z,qx,qy,qz,qw\n" + "5,5,5,0,0,0,1\n" * 12000)
    warm = tmp_path / "warm.py"  # (the command's kernels loaded first, then "ready")
    warm.write_text(WARM_CLI)
    rc, out, _took = interrupted_when_ready(
        [sys.executable, str(warm), "batch", "--robot", "panda", "--targets", str(far),
         "--chunk-size", "200", "--out", str(tmp_path / "b.npz"), "--no-progress"],
        tmp_path, after=2.0,
    )  # fmt: skip
    assert rc == 130, out
    assert "interrupted; writing the " in out, out
    kept = np.load(tmp_path / "b.npz")["q"]
    assert 0 < kept.shape[0] < 12000 and kept.shape[0] % 200 == 0


def test_the_suggested_resolution_passes_the_voxel_cap() -> None:
    lo, hi = [-0.95, -0.95, -0.9], [0.95, 0.95, 1.1]
    with pytest.raises(InvalidArgumentError) as info:
        _validate.check_grid_size(lo, hi, 0.005)
    fit = float(str(info.value).split("--resolution ")[1].split()[0])
    assert _validate.check_grid_size(lo, hi, fit) <= _validate.MAX_GRID_CELLS
    assert _validate.grid_cells(lo, hi, fit * 0.99) > _validate.MAX_GRID_CELLS
    assert _validate.finest_edge([0, 0, 0], [0, 0, 0], 10) is None
    assert _validate.finest_edge([0, 0, 0], [1e300, 1e300, np.inf], 10) is None


def test_a_position_only_map_of_a_five_joint_arm(get_robot, tmp_path: Path) -> None:
    robot = get_robot("so100")
    rmap = reach.reach_map(robot, resolution=0.1, position_only=True)
    assert rmap.position_only and rmap.n_orientations == 1
    assert 0 < int((rmap.index > 0).sum()) < int(rmap.solved.sum())
    # every voxel marked reachable: a joint vector places the frame's origin at its centre
    hit = rmap.centres[rmap.index > 0][:5]
    for c in hit:
        res = swarm_ik.solve(swarm_ik.IKProblem(robot, goals=[
            swarm_ik.goals.Position(robot.ee_frame, c)]), max_evals=20000)  # fmt: skip
        assert res.success
    back = reach.ReachMap.load(rmap.save(tmp_path / "so.npz"))
    assert back.position_only
    np.testing.assert_array_equal(back.index, rmap.index)
    with pytest.raises(InvalidArgumentError, match="one target per voxel"):
        reach.reach_map(robot, resolution=0.1, position_only=True, n_orientations=4)


def test_cli_reach_notes_a_short_arm_and_maps_its_positions(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    common = ["reach", "--robot", "so100", "--resolution", "0.2", "--no-progress", "--no-html",
              "--no-png", "--max-starts", "2"]  # fmt: skip
    assert main([*common, "--orientations", "1", "--out", str(tmp_path / "a.npz")]) in (0, 1)
    assert "--position-only maps its positions" in capsys.readouterr().err
    assert main([*common, "--position-only", "--out", str(tmp_path / "b.npz")]) == 0
    assert "positions only" in capsys.readouterr().out
    msg = cli_error(capsys, *common, "--position-only", "--orientations", "3", "--out", "c.npz")
    assert "--position-only tries one target per voxel" in msg


@pytest.mark.parametrize(
    "kwargs",
    [
        {"resolution": 0.5, "seed": -1},
        {"resolution": "0.5"},
        {"resolution": 0.5, "max_targets": None},
        {"resolution": 0.5, "n_orientations": True},
        {"resolution": 0.5, "position_only": "yes"},
    ],
)
def test_reach_map_refuses_bad_arguments_as_its_own(get_robot, kwargs: dict) -> None:
    with pytest.raises(SwarmIKError):
        reach.reach_map(get_robot("ur5"), **kwargs)


def test_reach_map_load_refuses_what_is_no_map(tmp_path: Path) -> None:
    np.savez(tmp_path / "other.npz", q=np.zeros(3))
    (tmp_path / "text.npz").write_text("not numpy")
    whole = (tmp_path / "other.npz").read_bytes()
    (tmp_path / "cut.npz").write_bytes(whole[: len(whole) // 2])
    (tmp_path / "junk.npz").write_bytes(b"PK\x03\x04" + b"junk" * 40)
    for name, message in [("other.npz", "lacks robot"), ("text.npz", "not a readable reach map"),
                          ("none.npz", "no such file"), ("cut.npz", "not a readable reach map"),
                          ("junk.npz", "not a readable reach map")]:  # fmt: skip
        with pytest.raises(InvalidArgumentError, match=message):
            reach.ReachMap.load(tmp_path / name)


def test_a_byte_order_mark_is_read_past(get_robot, tmp_path: Path) -> None:
    robot = get_robot("ur5")
    pose = robot.fk(robot.mid_q())
    row = np.concatenate([pose[:3, 3], swarm_ik.pose.matrix_to_quat(pose[:3, :3])])
    csv = tmp_path / "bom.csv"
    csv.write_bytes(b"\xef\xbb\xbf" + ("x,y,z,qx,qy,qz,qw\n" + ",".join(map(str, row))).encode())
    np.testing.assert_allclose(read_targets(csv)[0], pose, atol=1e-12)
    goals = tmp_path / "goals.json"
    spec = [{"type": "Position", "frame": robot.ee_frame, "point": pose[:3, 3].tolist()}]
    goals.write_bytes(b"\xef\xbb\xbf" + json.dumps(spec).encode())
    assert len(load_goals(goals)) == 1


def test_a_ctrl_c_a_kernel_lost_is_raised_when_it_returns(get_robot, monkeypatch) -> None:
    """The KeyboardInterrupt of a Ctrl-C is at times lost (``python -m swarm_ik.bench.path``
    ran on after 1 of 40 Ctrl-Cs): where swarm_ik's own handler counts the Ctrl-Cs (whose
    interruption ends the process), a count that is not zero raises it again around the next
    compiled call."""
    from swarm_ik.kernels import SIGINTS, search

    robot = get_robot("panda")
    problem = swarm_ik.IKProblem(robot, robot.fk(robot.random_q(np.random.default_rng(1))))
    real = search.swarm_search

    def loses_a_ctrl_c(*args: object) -> object:
        SIGINTS[0] += 1  # (counted by the handler, its KeyboardInterrupt lost)
        return real(*args)

    monkeypatch.setattr(search, "swarm_search", loses_a_ctrl_c)
    counted = SIGINTS[0]
    try:
        with pytest.raises(KeyboardInterrupt):
            swarm_ik.solve(problem, time_limit=0.5)
    finally:
        SIGINTS[0] = counted
    monkeypatch.setattr(search, "swarm_search", real)
    assert swarm_ik.solve(problem, time_limit=0.5).success  # (nothing counted: no raise)
