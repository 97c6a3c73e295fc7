"""Review 46: Ctrl-C around the start-up of `batch --scheduler local` (kept, one line, no
worker traceback), a repeated `--frame` in every command that loads a robot, and the refusal
of a reachability map whose orientations alone exceed the cap."""

from __future__ import annotations

import logging
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from conftest import cli_error

from swarm_ik import reach
from swarm_ik.cli import build_parser, main
from swarm_ik.errors import InvalidArgumentError

SIGINT_BIT = 1 << (signal.SIGINT - 1)
"""SIGINT in the masks of ``/proc/PID/status`` (``SigBlk``, ``SigIgn``)."""

posix_proc = pytest.mark.skipif(
    not sys.platform.startswith("linux"), reason="POSIX signals and /proc"
)


def _status(pid: int) -> dict[str, str]:
    """``/proc/PID/status`` as a dict (empty once the process is gone)."""
    try:
        text = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return {}
    return dict(line.split(":\t", 1) for line in text.splitlines() if ":\t" in line)


def _masks(pid: int) -> tuple[int, int]:
    """The (blocked, ignored) signal masks of ``pid``'s main thread (0, 0 once gone)."""
    st = _status(pid)
    return int(st.get("SigBlk", "0"), 16), int(st.get("SigIgn", "0"), 16)


def _holds_off_sigint(pid: int) -> bool:
    """SIGINT blocked or ignored in ``pid``: a Ctrl-C does not act there (now)."""
    blocked, ignored = _masks(pid)
    return bool((blocked | ignored) & SIGINT_BIT)


def _children(pid: int) -> list[int]:
    """Processes whose parent is ``pid``."""
    kids = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
            kids.append(int(entry.name))
    return kids


def _alive(pid: int) -> bool:
    """Running (not gone, not a zombie waiting for init to reap it)."""
    return _status(pid).get("State", "Z").strip()[:1] not in ("Z", "X", "")


def _start_batch(tmp_path: Path) -> subprocess.Popen[str]:
    """``swarm-ik batch --scheduler local`` long enough to be interrupted, in a session of
    its own (a Ctrl-C reaches the whole process group, as from a terminal)."""
    env = dict(os.environ)
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
        env.setdefault(var, "1")
    return subprocess.Popen(
        [sys.executable, "-m", "swarm_ik.cli", "batch", "--robot", "panda", "--random",
         "400000", "--max-starts", "64", "--out", str(tmp_path / "b.npz"), "--scheduler",
         "local", "--no-progress"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path, env=env,
        start_new_session=True,
    )  # fmt: skip


def _wait_for(
    proc: subprocess.Popen[str], ready: Callable[[], bool], what: str, timeout: float = 90.0
) -> None:
    """Poll every 10 ms until ``ready()``; fail (the process killed) if it exits first."""
    end = time.monotonic() + timeout
    while not ready():
        if proc.poll() is not None or time.monotonic() > end:
            os.killpg(proc.pid, signal.SIGKILL)
            out, err = proc.communicate()
            pytest.fail(f"never saw {what} (rc {proc.returncode}):\n{err[-3000:]}")
        time.sleep(0.01)


def _interrupt(proc: subprocess.Popen[str], within: float) -> tuple[float, str]:
    """Ctrl-C to the process group; returns (seconds to exit, stderr) once it exits 130
    within ``within`` s, every process it started gone a few seconds later."""
    family = [proc.pid, *_children(proc.pid)]
    sent = time.perf_counter()
    os.killpg(proc.pid, signal.SIGINT)
    try:
        out, err = proc.communicate(timeout=within)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        pytest.fail(f"still running {within} s after Ctrl-C (the Ctrl-C was lost):\n{out}")
    took = time.perf_counter() - sent
    assert proc.returncode == 130, err
    end = time.monotonic() + 10.0
    while any(_alive(p) for p in family) and time.monotonic() < end:
        time.sleep(0.1)
    assert not [p for p in family if _alive(p)], "processes left behind"
    return took, err


@posix_proc
def test_ctrl_c_during_the_cluster_start_up_is_kept(tmp_path: Path) -> None:
    """The Ctrl-C lands while SIGINT is held off the workers being started (it was ignored:
    lost, and the whole batch ran, 15-20 s, exit 1): exit 130 once the cluster is up, one
    line, nothing written, no process left."""
    pytest.importorskip("distributed")
    proc = _start_batch(tmp_path)
    # the start-up window: SIGINT blocked (or, before the fix, ignored) in the command
    _wait_for(proc, lambda: _holds_off_sigint(proc.pid), "the cluster's start-up")
    took, err = _interrupt(proc, within=12.0)
    assert err.strip().splitlines() == [
        "swarm-ik: interrupted; no chunk had finished; nothing written"
    ]
    assert not (tmp_path / "b.npz").exists()
    assert took < 8.0  # the start-up's end (~2 s) and the cluster's close


@posix_proc
def test_ctrl_c_once_the_cluster_runs_is_one_line_and_workers_ignore_it(tmp_path: Path) -> None:
    """After the start-up the workers hold SIGINT blocked (a Ctrl-C to the group never reaches
    them) and the command does not: exit 130 with one line, no worker's traceback."""
    pytest.importorskip("distributed")
    proc = _start_batch(tmp_path)
    _wait_for(proc, lambda: _holds_off_sigint(proc.pid), "the cluster's start-up")
    _wait_for(proc, lambda: not _holds_off_sigint(proc.pid), "the cluster up")
    time.sleep(0.3)  # the first chunks under way
    workers = [p for p in _children(proc.pid) if "spawn_main" in _cmdline(p)]
    assert workers
    for pid in workers:
        assert _holds_off_sigint(pid), f"worker {pid} would take a Ctrl-C"
    took, err = _interrupt(proc, within=15.0)
    assert len(err.strip().splitlines()) == 1, err
    assert err.startswith("swarm-ik: interrupted") and "Traceback" not in err


def _cmdline(pid: int) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return ""


def _stream_handler_levels() -> list[int]:
    """Levels of the handlers that print the records of Dask's loggers (in a worker)."""
    handlers = logging.getLogger("distributed").handlers
    return [h.level for h in handlers if isinstance(h, logging.StreamHandler)]


def test_embedded_cluster_workers_log_only_critical_records() -> None:
    """A worker's ERROR record (a heartbeat cut by the scheduler closing on Ctrl-C: 30 lines
    of CommClosedError) was printed by the worker process; they now print CRITICAL ones only
    (a task's error still reaches the client as its exception)."""
    pytest.importorskip("distributed")
    from swarm_ik import distributed

    with distributed.connect("local", n_workers=1) as client:
        levels = client.run(_stream_handler_levels)
        assert levels and all(v and set(v) == {logging.CRITICAL} for v in levels.values())

        def fails() -> None:
            raise ValueError("boom")

        with pytest.raises(ValueError, match="boom"):
            client.submit(fails, pure=False).result()


# ------------------------------------------------------------------- --frame, repeated
TALOS_FEET = ["--robot", "talos", "--floating-base", "--frame", "left_sole_link",
              "--frame", "right_sole_link"]  # fmt: skip
"""Two goal frames: the model spans both legs, 6 + 2 × 6 = 18 values."""


@pytest.mark.parametrize("command", ["solve", "show", "batch", "reach", "path"])
def test_frame_is_repeatable_in_every_command(command: str) -> None:
    args = build_parser(command).parse_args(
        [command, *TALOS_FEET, *{
            "solve": ["--pose", "0", "0", "0", "0", "0", "0", "1"],
            "show": [],
            "batch": ["--random", "1", "--out", "x.npz"],
            "reach": [],
            "path": ["--poses", "p.csv"],
        }[command]]
    )  # fmt: skip
    assert args.frame == ["left_sole_link", "right_sole_link"]
    from swarm_ik.cli._args import robot_frames

    assert robot_frames(args) == ["left_sole_link", "right_sole_link"]


@pytest.mark.parametrize("command", ["solve", "show", "batch", "reach", "path"])
def test_help_of_frame_says_what_several_do(command: str) -> None:
    parser = build_parser(command)
    sub = next(a for a in parser._actions if a.dest == "command").choices[command]
    (frame,) = [a for a in sub._actions if a.dest == "frame"]
    assert frame.help is not None and "repeat" in frame.help
    if command in ("batch", "reach", "path"):
        assert "the first's" in frame.help


def test_show_loads_every_frame(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    """`show` with two --frame built the model of the last frame's leg only (12 values)."""
    pytest.importorskip("meshcat")
    line = cli_error(capsys, "show", *TALOS_FEET, "--q", "0", "--html", str(tmp_path / "x.html"))
    assert "--q must hold 18 values" in line and "leg_left_1_joint" in line


def test_show_from_q_with_several_frames_poses_every_frame(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """As `solve`: --from-q with several frames is a pose goal on each (both arms here)."""
    pytest.importorskip("meshcat")
    q = ["0.1", "0.2", "0.3", "0.4", "0.5", "0.6", "0.7"] * 2
    argv = ["--robot", "baxter", "--frame", "left_gripper", "--frame", "right_gripper"]
    rc = main(["show", *argv, "--from-q", *q, "--html", str(tmp_path / "s.html")])
    out = capsys.readouterr().out
    assert rc == 0, out
    # the answer reaches both grippers' poses of the given q
    import swarm_ik

    robot = swarm_ik.load_robot("baxter", ["left_gripper", "right_gripper"])
    qline = next(line for line in out.splitlines() if line.strip().startswith("q ="))
    found = np.array([float(v) for v in qline.split("=")[1].split()])
    want = robot.fk_all(np.array([float(v) for v in q]))
    np.testing.assert_allclose(robot.fk_all(found), want, atol=1e-5)


def test_batch_loads_every_frame_and_solves_the_first(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    out = tmp_path / "b.npz"
    rc = main(["batch", *TALOS_FEET, "--random", "3", "--out", str(out), "--no-progress",
               "--max-starts", "4"])  # fmt: skip
    text = capsys.readouterr().out
    assert rc in (0, 1), text
    assert "(18 joints), frame left_sole_link" in text
    assert np.load(out)["q"].shape == (3, 18)


def test_reach_loads_every_frame_and_maps_the_first(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    rc = main(["reach", "--robot", "baxter", "--frame", "right_gripper", "--frame",
               "left_gripper", "--resolution", "0.6", "--orientations", "1", "--max-starts",
               "2", "--out", str(tmp_path / "m.npz"), "--no-png", "--no-html",
               "--no-progress"])  # fmt: skip
    text = capsys.readouterr().out
    assert rc == 0, text
    assert "frame right_gripper" in text


def test_path_loads_every_frame(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    import swarm_ik

    robot = swarm_ik.load_robot("baxter", ["right_gripper", "left_gripper"])
    q0 = robot.mid_q()
    poses = np.stack([robot.fk(q0), robot.fk(q0)])
    np.save(tmp_path / "p.npy", poses)
    out = tmp_path / "q.npy"
    rc = main(["path", "--robot", "baxter", "--frame", "right_gripper", "--frame",
               "left_gripper", "--poses", str(tmp_path / "p.npy"), "--out", str(out),
               "--q0", *map(str, q0)])  # fmt: skip
    text = capsys.readouterr()
    assert rc == 0, text
    assert np.load(out).shape == (2, 14)  # both arms (the last --frame alone: 7)


def test_a_frame_given_twice_is_refused_in_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    line = cli_error(
        capsys, "batch", "--robot", "panda", "--frame", "panda_hand", "--frame", "panda_hand",
        "--random", "2", "--out", "/tmp/never-written.npz",
    )  # fmt: skip
    assert "given more than once" in line


# ------------------------------------------------------------ reach: orientations alone
def test_orientations_alone_over_the_cap_name_the_options() -> None:
    """No resolution fits when one voxel's orientations exceed the cap: the message said
    "use a coarser resolution (at least 12.2 m)"."""
    with pytest.raises(InvalidArgumentError) as info:
        reach.check_grid_size([-1, -1, -1], [1, 1, 1], 0.1, 10**9, 5_000_000)
    msg = str(info.value)
    assert "--orientations" in msg and "--max-targets" in msg and "coarser" not in msg
    assert "at most 5000000 orientations" in msg


def test_reach_cli_refuses_orientations_over_the_cap(capsys: pytest.CaptureFixture[str]) -> None:
    line = cli_error(capsys, "reach", "--robot", "yumi_left", "--orientations", "1000000000",
                     "--out", "/tmp/never-written.npz", "--no-png", "--no-html")  # fmt: skip
    assert "--orientations" in line and "--max-targets" in line and "at least" not in line


@pytest.mark.parametrize(
    ("lower", "upper", "resolution", "k", "cap"),
    [
        ([0, 0, 0], [1, 1, 1], 0.25, 2, 100),  # (said 0.271 m: 64 voxels, still over)
        ([0, 0, 0], [2, 1, 0.01], 1e-4, 8, 5_000_000),
        ([0, 0, 0], [3, 0.2, 0.05], 1e-3, 8, 5_000_000),
        ([0, 0, 0], [1, 1, 1], 0.1, 3, 5),
    ],
)
def test_the_resolution_named_is_the_finest_that_fits(
    lower: list[float], upper: list[float], resolution: float, k: int, cap: int
) -> None:
    with pytest.raises(InvalidArgumentError, match="coarser resolution") as info:
        reach.check_grid_size(lower, upper, resolution, k, cap)
    fits = float(str(info.value).split("at least ")[1].split(" m")[0])
    assert reach.check_grid_size(lower, upper, fits, k, cap) * k <= cap
    with pytest.raises(InvalidArgumentError):  # 1 % finer no longer fits
        reach.check_grid_size(lower, upper, fits * 0.99, k, cap)


# ------------------------------------------------- the start-up guard, in this process
@posix_proc
def test_start_up_guard_holds_a_ctrl_c_and_raises_it_at_its_end() -> None:
    """Inside the guard SIGINT is blocked (a child started there inherits the mask) and a
    Ctrl-C is held; at its end the mask and handler are as before and the Ctrl-C raises."""
    from swarm_ik.distributed import sigint_blocked_for_workers

    handler = signal.getsignal(signal.SIGINT)
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, set())
    child = "print(open('/proc/self/status').read())"
    reached_end = False
    with pytest.raises(KeyboardInterrupt):
        with sigint_blocked_for_workers():
            assert signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, set())
            status = subprocess.run(
                [sys.executable, "-c", child], capture_output=True, text=True, check=True
            ).stdout
            blocked = int(status.split("SigBlk:")[1].split()[0], 16)
            assert blocked & SIGINT_BIT  # (a worker started here never takes a Ctrl-C)
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
            reached_end = True  # not interrupted inside
    assert reached_end
    assert signal.getsignal(signal.SIGINT) is handler
    assert signal.pthread_sigmask(signal.SIG_BLOCK, set()) == mask
    with sigint_blocked_for_workers():  # no Ctrl-C: nothing raised
        pass
