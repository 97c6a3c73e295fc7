"""Scale-out on Dask: identical results whatever the workers, and a killed worker's chunks
recomputed (scheduler and workers started as separate processes on 127.0.0.1)."""

from __future__ import annotations

import functools
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import timed

from swarm_ik import distributed
from swarm_ik.batch import BatchChain, BatchSettings, _run_chunk, solve_batch
from swarm_ik.errors import InvalidArgumentError

dask_distributed = pytest.importorskip("distributed")


def _targets(robot, n: int, seed: int) -> np.ndarray:
    return robot.fk(robot.random_q(np.random.default_rng(seed), n))


def _square(x: int) -> int:
    return x * x


def test_check_scheduler_lists_choices():
    assert distributed.check_scheduler(None) is None
    assert distributed.check_scheduler("none") is None
    assert distributed.check_scheduler("local") == "local"
    assert distributed.check_scheduler("tcp://127.0.0.1:8786") == "tcp://127.0.0.1:8786"
    with pytest.raises(InvalidArgumentError, match="'local' .* tcp://"):
        distributed.check_scheduler("127.0.0.1:8786")
    with pytest.raises(InvalidArgumentError, match="distributed.Client"):
        distributed.check_scheduler(3)


def test_map_chunks_in_process_keeps_order():
    assert distributed.map_chunks(_square, [3, 1, 2]) == [9, 1, 4]
    with pytest.raises(InvalidArgumentError, match="one entry per item"):
        distributed.map_chunks(_square, [1, 2], sizes=[1])


def test_a_scheduler_refusing_the_connection_is_reported_at_once():
    """Dask's client retries a refused connection until its timeout (30 s by default); the
    refusal is reported at once."""
    import time

    t0 = time.perf_counter()
    with pytest.raises(InvalidArgumentError, match="could not reach the Dask scheduler"):
        with distributed.connect("tcp://127.0.0.1:1"):
            pass
    assert time.perf_counter() - t0 < 10.0


def test_unreachable_scheduler_is_reported():
    with pytest.raises(InvalidArgumentError, match="could not reach the Dask scheduler"):
        with distributed.connect("tcp://127.0.0.1:1", timeout=1):
            pass


def test_local_cluster_of_two_workers_gives_identical_results(get_robot):
    robot = get_robot("panda")
    targets = _targets(robot, 1500, seed=21)
    ref = solve_batch(robot, targets, seed=4)
    assert (ref.n_starts > 1).any()
    with distributed.connect("local", n_workers=2) as client:
        assert distributed.n_workers(client) == 2
        a = solve_batch(robot, targets, seed=4, scheduler=client)
        b = solve_batch(robot, targets, seed=4, scheduler=client, chunk_size=101)
        # the same chunks again, on the same client: computed again, the same answer
        c = solve_batch(robot, targets, seed=4, scheduler=client, chunk_size=101)
        used = client.run(os.getpid)
    assert len(set(used.values())) == 2  # two worker processes
    for res in (a, b, c):
        np.testing.assert_array_equal(res.q, ref.q)
        np.testing.assert_array_equal(res.success, ref.success)
        np.testing.assert_array_equal(res.n_evals, ref.n_evals)


@timed(2)  # (a kernel compiled in a chunk, on a cold numba cache, is inside the limit)
def test_fresh_workers_load_before_the_time_limit_starts(get_robot):
    """Fresh workers load the kernels and the scene (seconds) before a batch's clock: with a
    1 s limit on a new local cluster the workers started no target (2,000 among 200 boxes:
    0 solved in 4.7 s); their loading is charged as this process's, up to half the limit."""
    from swarm_ik.goals import AvoidCollisions
    from swarm_ik.scene import Box, Scene

    robot = get_robot("panda")
    targets = _targets(robot, 300, seed=5)
    scene = Scene([Box([0.05, 0.05, 0.05], [0.6, 0.6, 0.9])])
    goals = [AvoidCollisions(scene)]
    with distributed.connect("local", n_workers=2) as client:
        res = solve_batch(robot, targets, goals=goals, scheduler=client, time_limit=1.0)
    assert int((res.n_starts > 0).sum()) == 300 and res.success.sum() > 250


def _client_when_up(scheduler_file: str, scheduler: subprocess.Popen, log: Path):
    """A client of the scheduler started with ``--scheduler-file``, once it has written its
    address and answers (a loaded machine takes seconds to start one): tried for 120 s."""
    deadline = time.monotonic() + 120
    while True:
        assert scheduler.poll() is None, f"the scheduler exited: {log.read_text()[-2000:]}"
        if os.path.exists(scheduler_file):
            try:
                return dask_distributed.Client(scheduler_file=scheduler_file, timeout=30)
            except (OSError, ValueError) as exc:  # CommClosedError is an OSError
                if time.monotonic() > deadline:
                    raise AssertionError(f"no scheduler: {exc}; {log.read_text()[-2000:]}") from exc
        assert time.monotonic() < deadline, f"no scheduler file: {log.read_text()[-2000:]}"
        time.sleep(0.2)


def _dask_cli() -> list[str]:
    exe = Path(sys.executable).with_name("dask")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "dask"]


def _stop(procs: list[subprocess.Popen]) -> None:
    """Stop the processes this test started: workers first, then the scheduler (last in
    ``procs`` order reversed), each given 5 s to exit before it is killed."""
    for p in reversed(procs):
        if p.poll() is None:
            p.terminate()
        try:
            p.wait(timeout=5)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait(timeout=5)


def test_killed_worker_chunks_are_recomputed(get_robot, tmp_path):
    robot = get_robot("yumi_left")
    # every 4th target is out of reach, so each chunk costs a few tens of milliseconds
    targets = _targets(robot, 2400, seed=5)
    targets[::4, :3, 3] += 2.0
    settings = BatchSettings(seed=9, max_starts=24)
    bc = BatchChain.from_robot(robot)
    size = 100
    items = [
        (s, targets[s : s + size], np.tile(robot.mid_q(), (len(targets[s : s + size]), 1)))
        for s in range(0, len(targets), size)
    ]
    func = functools.partial(_run_chunk, bc, settings)  # importable on the workers
    ref = [func(it) for it in items]

    # the scheduler picks its own port and writes its address to a file the workers and the
    # client read: no race for a port chosen here, and no connection before it listens
    scheduler_file = str(tmp_path / "scheduler.json")
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    log = (tmp_path / "dask.log").open("w")
    procs: list[subprocess.Popen] = []
    client = None
    try:
        procs.append(
            subprocess.Popen(
                [
                    *_dask_cli(),
                    "scheduler",
                    "--host",
                    "127.0.0.1",
                    "--port",
                    "0",
                    "--no-dashboard",
                    "--scheduler-file",
                    scheduler_file,
                ],
                stdout=log,
                stderr=log,
                env=env,
            )
        )
        for _ in range(2):
            procs.append(
                subprocess.Popen(
                    [
                        *_dask_cli(),
                        "worker",
                        "--scheduler-file",
                        scheduler_file,
                        "--host",
                        "127.0.0.1",
                        "--nthreads",
                        "1",
                        "--nworkers",
                        "1",
                        "--no-nanny",
                        "--no-dashboard",
                        "--local-directory",
                        str(tmp_path / "scratch"),
                    ],
                    stdout=log,
                    stderr=log,
                    env=env,
                )
            )
        client = _client_when_up(scheduler_file, procs[0], tmp_path / "dask.log")
        client.wait_for_workers(2, timeout=120)
        victim = procs[1]
        victim_addr = [w for w, pid in client.run(os.getpid).items() if pid == victim.pid]
        assert len(victim_addr) == 1
        client.run(func, items[0])  # compile / load the kernels on both workers first
        futures = [
            client.submit(func, it, key=f"chunk-{i}", pure=True) for i, it in enumerate(items)
        ]
        deadline = time.monotonic() + 120
        while True:  # kill the victim while it holds unfinished work
            busy = client.processing(workers=victim_addr).get(victim_addr[0], ())
            done = sum(f.done() for f in futures)
            if done >= 1 and busy:
                break
            assert time.monotonic() < deadline, "the workers never started"
            time.sleep(0.005)
        assert done < len(futures) - 2  # most of the work is still ahead
        victim.kill()
        victim.wait(timeout=10)
        results = client.gather(futures)
        assert len(client.scheduler_info()["workers"]) == 1
        # the victim's unfinished chunks went back to the queue and were computed again
        stories = {k: [t[2] for t in client.story(k) if len(t) > 3] for k in busy}
        assert all(st.count("processing") >= 2 for st in stories.values()), stories
    finally:
        if client is not None:
            client.close()
        _stop(procs)
        log.close()
    assert [r.start for r in results] == [it[0] for it in items]  # each chunk once, in order
    for got, want in zip(results, ref, strict=True):
        np.testing.assert_array_equal(got.q, want.q)
        np.testing.assert_array_equal(got.success, want.success)
    assert not all(r.success.all() for r in results)  # the unreachable targets stay failed


def test_map_chunks_on_a_scheduler_address(get_robot):
    """``scheduler="tcp://…"``: map_chunks connects, computes in order, and disconnects."""
    with dask_distributed.LocalCluster(
        n_workers=1,
        threads_per_worker=1,
        processes=False,
        protocol="tcp",
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        assert cluster.scheduler_address.startswith("tcp://127.0.0.1:")
        out = distributed.map_chunks(_square, list(range(7)), scheduler=cluster.scheduler_address)
        assert out == [i * i for i in range(7)]


def _square_or_fail(x: int) -> int:
    if x < 0:
        raise ValueError(f"negative chunk {x}")
    return x * x


def test_map_chunks_retried_after_a_failure_on_the_same_client():
    """A call whose chunk fails raises that chunk's error; the same chunks submitted again on
    the same client (the failed call's error, and with it its futures, still held) are
    computed, not answered by the failed call's cancelled tasks."""
    with dask_distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster, dask_distributed.Client(cluster) as client:  # fmt: skip
        items = list(range(6))
        held = []
        for _ in range(3):
            with pytest.raises(ValueError, match="negative chunk -1") as info:
                distributed.map_chunks(_square_or_fail, [-1, *items], client=client)
            held.append(info.value)  # (its traceback holds the failed call's futures)
            again = [-2, *items]  # (the same chunks at the same places after the first)
            with pytest.raises(ValueError, match="negative chunk -2"):
                distributed.map_chunks(_square_or_fail, again, client=client)
            assert distributed.map_chunks(_square_or_fail, [0, *items], client=client) == [
                0,
                *(i * i for i in items),
            ]


def _alive(pid: int) -> bool:
    """Whether process ``pid`` still runs (a zombie counts as gone)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_ctrl_c_kills_the_embedded_workers_instead_of_waiting_for_their_tasks() -> None:
    """A Ctrl-C inside ``connect("local")`` while a worker runs a task that does not return
    (a compiled chunk cannot be interrupted): its workers are killed, so the cluster closes
    at once (a graceful close waited for the task, then killed it after 4 s); no worker is
    left."""
    t_sent = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        with distributed.connect("local", n_workers=1) as client:
            pids = set(client.run(os.getpid).values())
            client.submit(time.sleep, 60, pure=False)
            time.sleep(0.5)  # (the task under way)
            t_sent = time.perf_counter()
            raise KeyboardInterrupt
    took = time.perf_counter() - t_sent
    assert pids and not any(_alive(p) for p in pids)
    assert took < 3.0, f"closing took {took:.1f} s"


def test_a_script_without_a_main_guard_is_told_to_add_one(tmp_path: Path) -> None:
    """scheduler='local' in a script without ``if __name__ == "__main__":``: the worker
    processes import the script again and cannot start; the call ends with a SwarmIKError
    saying so (a 300-line Dask traceback before; a held-out review)."""
    script = tmp_path / "noguard.py"
    script.write_text(
        "import numpy as np, swarm_ik\n"
        "r = swarm_ik.load_robot('panda')\n"
        "t = np.array([r.fk(r.mid_q())] * 4)\n"
        "swarm_ik.solve_batch(r, t, scheduler='local')\n"
    )
    out = subprocess.run(
        [sys.executable, str(script)], capture_output=True, text=True, timeout=180,
        cwd=tmp_path,
    )  # fmt: skip
    assert out.returncode == 1
    last = out.stderr.strip().splitlines()[-1]
    assert last.startswith("swarm_ik.errors.InvalidArgumentError"), last
    assert 'if __name__ == "__main__":' in last, last
