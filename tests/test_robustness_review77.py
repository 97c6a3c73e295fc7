"""Held-out robustness review (helper 77): a scheduler address that is no Dask scheduler, many
goals, targets as rows, a Ctrl-C during trimesh's import, a FIFO among the cache files, a
closed standard output, and bounds whose span overflows."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import robot

import swarm_ik
from swarm_ik import distributed, errors, kernels
from swarm_ik.api import conflicting_goals
from swarm_ik.batch import check_targets
from swarm_ik.goals import Position
from swarm_ik.pose import make_pose


def test_a_scheduler_address_needs_a_host_and_a_port() -> None:
    for address in ("tcp://", "tcp://127.0.0.1", "tcp://host:port"):
        with pytest.raises(errors.InvalidArgumentError, match="host and a port"):
            distributed.check_scheduler(address)
    assert distributed.check_scheduler("tcp://127.0.0.1:8786") == "tcp://127.0.0.1:8786"
    assert distributed.check_scheduler("tcp://[::1]:8786") == "tcp://[::1]:8786"


def test_a_server_that_accepts_but_says_nothing_is_no_scheduler(monkeypatch) -> None:
    """An HTTP port (a dashboard's, say) accepts the connection and waits for a request: Dask's
    client waited for its greeting forever."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    held: list[socket.socket] = []
    threading.Thread(target=lambda: held.append(server.accept()[0]), daemon=True).start()
    monkeypatch.setattr(distributed, "PROBE_S", 0.3)
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    try:
        with pytest.raises(errors.InvalidArgumentError, match="sent nothing"):
            with distributed.connect(address):
                pass
    finally:
        server.close()
        for conn in held:
            conn.close()


def test_conflicting_goals_among_many_are_found_and_duplicates_are_one() -> None:
    panda = robot("panda")
    f = panda.ee_frame
    same = [Position(f, [0.4, 0.0, 0.3]) for _ in range(3000)]
    problem = swarm_ik.IKProblem(panda, goals=same)
    assert conflicting_goals(problem, 1e-5, 1e-5) is None
    near = [Position(f, [0.4 + 1e-6 * k, 0.0, 0.3]) for k in range(5)]
    assert conflicting_goals(swarm_ik.IKProblem(panda, goals=near), 1e-5, 1e-5) is None
    apart = [*near, Position(f, [0.4, 0.1, 0.3], weight=2.0)]
    found = conflicting_goals(swarm_ik.IKProblem(panda, goals=apart), 1e-5, 1e-5)
    assert found == f"Position({f}) and Position({f})"
    assert swarm_ik.solve(swarm_ik.IKProblem(panda, goals=apart)).reason == "conflicting_goals"


def test_target_rows_give_the_poses_of_make_pose_and_name_a_bad_row() -> None:
    rows = np.random.default_rng(0).normal(size=(500, 7))
    poses = check_targets(rows)
    expected = np.array([make_pose(r[:3], r[3:]) for r in rows])
    np.testing.assert_array_equal(poses, expected)
    rows[321, 3:] = 0.0
    with pytest.raises(errors.InvalidTargetError, match="target 321: quaternion has zero norm"):
        check_targets(rows)


def test_a_ctrl_c_during_trimeshs_import_is_not_swallowed(tmp_path: Path, monkeypatch) -> None:
    """trimesh guards its optional imports with ``except BaseException``; a stand-in that
    does the same with a Ctrl-C arriving meanwhile."""
    from swarm_ik import spheres

    (tmp_path / "trimesh.py").write_text(
        "import os, signal\n"
        "try:\n"
        "    os.kill(os.getpid(), signal.SIGINT)\n"
        "    import time; time.sleep(0.05)\n"
        "except BaseException:\n"
        "    pass\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "trimesh", raising=False)
    try:
        with pytest.raises(KeyboardInterrupt):
            spheres._import_trimesh()
    finally:
        sys.modules.pop("trimesh", None)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_a_fifo_among_the_cache_files_is_removed_not_opened(tmp_path: Path) -> None:
    fifo = tmp_path / "kernel.fifo-1.py311.nbi"
    os.mkfifo(fifo)
    t0 = time.monotonic()
    assert kernels.drop_damaged_cache_files([str(tmp_path)]) == [str(fifo)]
    assert not fifo.exists() and time.monotonic() - t0 < 5.0


def test_a_closed_standard_output_is_no_internal_error() -> None:
    code = "import sys; from swarm_ik.cli import main; sys.exit(main(['robots']))"
    proc = subprocess.run(
        [sys.executable, "-c", code], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
        text=True, timeout=120, preexec_fn=lambda: os.close(1),
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "internal error" not in proc.stderr


def test_refusals_of_the_robot_and_minimize() -> None:
    panda = robot("panda")
    with pytest.raises(errors.InvalidArgumentError, match="text"):
        panda.fk("a")
    with pytest.raises(errors.InvalidArgumentError, match="overflows"):
        swarm_ik.minimize(lambda x: x.sum(1), [-1e308] * 2, [1e308] * 2, max_evals=200)


def test_the_probe_tells_an_unreachable_host_from_a_silent_or_closing_one(monkeypatch) -> None:
    """A server that closes at once is no scheduler; one that never completes the connection
    could not be reached (it was called one that "accepted the connection")."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(1)
    threading.Thread(target=lambda: server.accept()[0].close(), daemon=True).start()
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    try:
        with pytest.raises(errors.InvalidArgumentError, match="closed the connection at once"):
            distributed._probe(address, 1.0)
    finally:
        server.close()

    def never(*args: object, **kwargs: object) -> None:
        raise TimeoutError("timed out")

    monkeypatch.setattr(socket, "create_connection", never)
    with pytest.raises(errors.InvalidArgumentError, match=r"could not reach .* \(timed out\)"):
        distributed._probe("tcp://10.255.255.1:8786", 1.0)
    with pytest.raises(errors.InvalidArgumentError, match="1 to 65535"):
        distributed.check_scheduler("tcp://127.0.0.1:99999")


def test_one_quaternion_and_rows_give_the_same_bits_without_warnings() -> None:
    import warnings

    from swarm_ik.pose import poses_from_rows, quat_to_matrix

    rng = np.random.default_rng(5)
    quats = np.concatenate(
        [
            rng.normal(size=(300, 4)),
            rng.normal(size=(50, 4)) * 1e300,
            [[1.7e308, 1.7e308, 0, 1.7e308]],
        ]
    )
    rows = np.concatenate([np.zeros((len(quats), 3)), quats], axis=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        batch = poses_from_rows(rows)[:, :3, :3]
        one = np.array([quat_to_matrix(q) for q in quats])
    np.testing.assert_array_equal(one, batch)


def test_a_wall_on_a_narrowed_continuous_joint_stops_the_particle() -> None:
    """``Evaluator.wrapped`` is what a step across ±π becomes; a clip beyond it is a wall
    (PSO and MGWO zero the velocity there, and only there)."""
    from swarm_ik.solvers.base import Evaluator

    ev = Evaluator(lambda x: x.sum(1), [-0.5, -np.pi], [0.5, np.pi])
    ev.wrap_mask = np.array([True, True])
    xn = np.array([[0.75, 3.5]])
    x = ev.clip(xn)
    assert (x == ev.wrapped(xn)).tolist() == [[False, True]]
