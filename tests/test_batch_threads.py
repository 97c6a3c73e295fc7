"""``scheduler="threads"``: a batch's chunks on threads of this process (the kernels release
the GIL), with the answers of the in-process batch, errors and Ctrl-C passed to the caller."""

from __future__ import annotations

import signal
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import WARM_CLI, interrupted_when_ready

import swarm_ik
from swarm_ik import distributed
from swarm_ik.cli import main
from swarm_ik.errors import InvalidArgumentError, InvalidTargetError
from swarm_ik.goals import AvoidCollisions, Posture
from swarm_ik.scene import Box, Scene


def _targets(robot, n: int, seed: int) -> np.ndarray:
    return robot.fk(robot.random_q(np.random.default_rng(seed), n))


def test_threads_is_a_scheduler_where_python_peers_are_not_timed() -> None:
    assert distributed.check_scheduler("threads") == "threads"
    with pytest.raises(InvalidArgumentError, match="'threads' .*'local'"):
        distributed.check_scheduler("thread")
    with pytest.raises(InvalidArgumentError, match="'threads' is for batches"):
        distributed.check_scheduler("threads", threads=False)
    with pytest.raises(InvalidArgumentError) as info:
        distributed.check_scheduler("thread", threads=False)
    assert "'threads'" not in str(info.value)
    with distributed.connect("threads", n_workers=3) as pool:
        assert distributed.n_workers(pool) == 3


def test_map_chunks_on_threads_keeps_order_and_runs_each_item_once() -> None:
    seen: list[int] = []
    lock = threading.Lock()

    def square(x: int) -> int:
        with lock:
            seen.append(x)
        return x * x

    out = distributed.map_chunks(square, list(range(40)), scheduler="threads")
    assert out == [x * x for x in range(40)]
    assert sorted(seen) == list(range(40))
    assert distributed.map_chunks(square, [], scheduler="threads") == []


def test_an_error_in_a_chunk_reaches_the_caller_and_stops_the_rest() -> None:
    started: list[int] = []

    def fails_at_three(x: int) -> int:
        started.append(x)
        if x == 3:
            raise ValueError("chunk 3 failed")
        time.sleep(0.01)
        return x

    pool = distributed.Threads(2)
    with pytest.raises(ValueError, match="chunk 3 failed"):
        pool.map(fails_at_three, list(range(200)))
    time.sleep(0.1)  # (a chunk running when it failed ends; none starts after)
    assert len(started) < 20


def test_threads_give_the_answers_of_the_batch_in_this_process(get_robot) -> None:
    robot = get_robot("panda")
    targets = _targets(robot, 300, 4)
    ref = swarm_ik.solve_batch(robot, targets, seed=2, chunk_size=25)
    got = swarm_ik.solve_batch(robot, targets, seed=2, chunk_size=25, scheduler="threads")
    np.testing.assert_array_equal(got.q, ref.q)
    np.testing.assert_array_equal(got.n_evals, ref.n_evals)
    np.testing.assert_array_equal(got.success, ref.success)
    assert got.success.mean() > 0.99


def test_threads_give_the_answers_of_the_batch_with_goals(get_robot) -> None:
    robot = get_robot("panda")
    scene = Scene([Box([0.3, 0.3, 0.3], [0.0, 0.6, 0.3], name="block")])
    q = robot.random_q(np.random.default_rng(9), 60)
    free = q[[not robot.collision_model().collides(x, scene, 0.0, True) for x in q]][:30]
    targets = robot.fk(free)
    goals = [AvoidCollisions(scene), Posture(robot.mid_q(), weight=1e-3)]
    ref = swarm_ik.solve_batch(robot, targets, goals=goals, chunk_size=8)
    got = swarm_ik.solve_batch(robot, targets, goals=goals, chunk_size=8, scheduler="threads")
    np.testing.assert_array_equal(got.q, ref.q)
    np.testing.assert_array_equal(got.success, ref.success)
    assert got.success.all()


def test_cli_batch_on_threads(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "r.npz"
    rc = main(["batch", "--robot", "yumi_left", "--random", "200", "--out", str(out),
               "--scheduler", "threads", "--chunk-size", "32", "--seed", "3",
               "--no-progress"])  # fmt: skip
    assert rc == 0, capsys.readouterr().err
    robot = swarm_ik.load_robot("yumi_left")
    ref = swarm_ik.solve_batch(robot, _targets(robot, 200, 3), seed=3, chunk_size=32)
    np.testing.assert_array_equal(np.load(out)["q"], ref.q)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="POSIX signals")
def test_ctrl_c_stops_a_batch_on_threads_at_once(tmp_path: Path) -> None:
    """The threads are daemons that take no chunk after the Ctrl-C: the command exits 130 with
    one line while a chunk may still run, instead of waiting for the whole batch."""
    warm = tmp_path / "warm.py"
    warm.write_text(WARM_CLI)
    rc, out, took = interrupted_when_ready(
        [sys.executable, str(warm), "batch", "--robot", "panda", "--random", "400000",
         "--max-starts", "64", "--chunk-size", "2000", "--out", str(tmp_path / "b.npz"),
         "--scheduler", "threads", "--no-progress"],
        tmp_path, after=1.0,
    )  # fmt: skip
    assert rc == 130, out
    lines = out.strip().splitlines()[1:]  # (after "ready")
    assert len(lines) == 1 and lines[0].startswith("swarm-ik: interrupted"), out
    assert took < 5.0


@pytest.mark.parametrize("command", ["ik", "paper"])
def test_benchmarks_of_python_peers_refuse_threads(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rc = main(["bench", command, "--scheduler", "threads", "--out", str(tmp_path / "b")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert "'threads' is for batches" in err[0]
    assert not (tmp_path / "b").exists()


def test_a_ctrl_c_as_a_map_starts_leaves_no_runaway_and_no_lost_thread() -> None:
    """A Ctrl-C landing while the runners start (a SIGINT sent by a timer 1-300 µs into the
    call) stopped nothing (the whole map ran on) and lost pool threads (each later map started
    new ones)."""
    if not hasattr(signal, "setitimer"):
        pytest.skip("no interval timer")

    def interrupt(*_: object) -> None:
        signal.raise_signal(signal.SIGINT)  # (taken by whatever handles SIGINT just then)

    done: list[int] = []

    def slow(x: int) -> None:
        time.sleep(0.002)
        done.append(x)

    old = signal.signal(signal.SIGALRM, interrupt)
    sigint = signal.getsignal(signal.SIGINT)
    pool, runaway = distributed.Threads(2), 0
    try:
        for d in range(1, 300, 3):
            del done[:]
            try:
                signal.setitimer(signal.ITIMER_REAL, d * 1e-6)
                pool.map(slow, list(range(60)))
                signal.setitimer(signal.ITIMER_REAL, 0)
            except KeyboardInterrupt:
                n0 = len(done)
                time.sleep(0.05)
                runaway += len(done) - n0 > 4
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    time.sleep(0.2)
    assert signal.getsignal(signal.SIGINT) is sigint  # (never left replaced)
    assert runaway == 0
    names = [t.name for t in threading.enumerate() if t.name.startswith("swarm-ik-")]
    assert len(names) <= 8, names  # (the pool's threads are reused)


def test_a_pool_handle_is_a_scheduler_and_bench_throughput_refuses_threads(
    get_robot, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    robot = get_robot("panda")
    targets = _targets(robot, 20, 1)
    with distributed.connect("threads") as pool:
        got = swarm_ik.solve_batch(robot, targets, scheduler=pool, chunk_size=4)
    np.testing.assert_array_equal(got.q, swarm_ik.solve_batch(robot, targets, chunk_size=4).q)
    rc = main(["bench", "throughput", "--scheduler", "threads", "--out", str(tmp_path / "b")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "'threads' is for batches" in err[0], err
    assert not (tmp_path / "b").exists()


def test_rotation_blocks_too_large_to_square_are_refused(get_robot) -> None:
    robot = get_robot("panda")
    pose = robot.fk(robot.mid_q())[None].copy()
    pose[0, :3, :3] *= 1e200  # (its products overflow: inf - inf is NaN)
    with pytest.raises(InvalidTargetError, match="not orthonormal"):
        swarm_ik.solve_batch(robot, pose)
