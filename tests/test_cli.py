"""The ``swarm_ik.cli`` package: one module per sub-command, and its edge cases — the help
texts, ``--goals`` files that are not files (or too large, or too deep), ``--show`` with no
terminal, ``--position-only`` with a position alone, ``reach --bounds``, output paths checked
before the work, meshes not found, Ctrl-C and unexpected errors in every sub-command, and
``.xacro`` robots."""

from __future__ import annotations

import argparse
import io
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from conftest import FROM_Q, cli_error, cli_json, never

import swarm_ik
from swarm_ik import cli
from swarm_ik.cli import _args, _viewer
from swarm_ik.cli import bench as bench_cli
from swarm_ik.cli import reach as reach_cli

ARGS = {
    "robots": ["robots"],
    "solve": ["solve", "--robot", "yumi_left", *FROM_Q],
    "show": ["show", "--robot", "yumi_left", "--q", "0", "0", "0", "0", "0", "0", "0"],
    "batch": ["batch", "--robot", "yumi_left", "--random", "2", "--out", "{tmp}/r.npz"],
    "reach": ["reach", "--robot", "yumi_left", "--out", "{tmp}/m.npz"],
    "bench": ["bench", "ik", "--quick", "--out", "{tmp}/b"],
}
"""A valid command line of every sub-command."""


def _run(*argv: str, timeout: float = 300, **kwargs: Any) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k != "SWARM_IK_NO_WAIT"}
    return subprocess.run(
        [sys.executable, "-m", "swarm_ik.cli", *argv],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
        **kwargs,
    )


# ------------------------------------------------------------------------ the package
def test_every_sub_command_is_a_module_with_add_parser_and_run() -> None:
    assert {"robots", "warmup", "solve", "path", "show", "batch", "reach", "bench"} <= set(
        cli.COMMANDS
    )
    for name, module in cli.COMMANDS.items():
        assert module.__name__ == f"swarm_ik.cli.{name}"
        assert callable(module.add_parser) and callable(module.run)
    from swarm_ik.batch import MAX_TARGETS as BATCH_MAX_TARGETS
    from swarm_ik.reach import MAX_TARGETS

    assert reach_cli.MAX_TARGETS == MAX_TARGETS
    assert reach_cli.BATCH_MAX_TARGETS == BATCH_MAX_TARGETS


def test_import_is_light_and_python_m_works() -> None:
    code = "import sys, swarm_ik.cli; print(sorted({'numpy', 'numba'} & set(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.stdout.strip() == "[]", out.stderr
    proc = _run("robots", timeout=120)
    assert proc.returncode == 0 and "panda" in proc.stdout, proc.stderr


# --------------------------------------------------------------------------- 1: help
def test_help_lists_every_benchmark_and_says_what_each_measures(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("COLUMNS", "80")  # one line per entry on a common terminal
    with pytest.raises(SystemExit) as done:
        cli.main(["--help"])
    assert done.value.code == 0
    top = capsys.readouterr().out
    bench_line = next(ln for ln in top.splitlines() if ln.strip().startswith("bench "))
    assert all(name in bench_line for name in cli.BENCHMARKS)
    with pytest.raises(SystemExit):
        cli.main(["bench", "--help"])
    text = capsys.readouterr().out
    assert set(bench_cli.MEASURES) == set(cli.BENCHMARKS)
    for name, measures in bench_cli.MEASURES.items():
        line = next(ln for ln in text.splitlines() if ln.split()[:1] == [name])
        assert measures in line  # one line each
        assert f"benchmark {name}" not in line and name not in measures.split()


@pytest.mark.parametrize(
    "argv",
    [
        [],
        ["robots"],
        ["solve"],
        ["show"],
        ["batch"],
        ["reach"],
        ["bench"],
    ],
)
def test_every_help_renders(
    argv: list[str], monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("COLUMNS", "100")
    with pytest.raises(SystemExit) as done:
        cli.main([*argv, "--help"])
    assert done.value.code == 0
    text = capsys.readouterr().out
    assert text.startswith("usage: swarm-ik")
    if argv == ["solve"]:
        assert "--pose X Y Z [QX QY QZ QW]" in text and "--show-wait SECONDS" in text
        assert "stdin not a TTY" in " ".join(text.split())
    if argv == ["show"]:
        assert "--pose X Y Z QX QY QZ QW " in text and "--show-wait" in text


# -------------------------------------------------------------------- 2: --goals files
@pytest.mark.parametrize("kind", ["fifo", "device", "folder", "too large"])
def test_goals_that_is_not_a_small_regular_file_exits_2(
    kind: str, tmp_path: Path, refused: Callable[..., str]
) -> None:
    if kind == "fifo":
        if not hasattr(os, "mkfifo"):
            pytest.skip("no FIFOs here")
        path = tmp_path / "goals.json"
        os.mkfifo(path)
        expect = "named pipe (FIFO)"
    elif kind == "device":
        path = Path("/dev/zero")
        if not path.exists():
            pytest.skip("no /dev/zero here")
        expect = "is a device"
    elif kind == "folder":
        path = tmp_path
        expect = "is a folder"
    else:
        path = tmp_path / "goals.json"
        with open(path, "wb") as fh:  # sparse: nothing written
            fh.truncate(_args.MAX_GOALS_BYTES + 1)
        expect = "over the limit of 16 MiB"
    t0 = time.perf_counter()
    line = refused("solve", "--robot", "panda", "--goals", str(path))
    assert time.perf_counter() - t0 < 5.0  # refused, never opened
    assert "--goals" in line and expect in line


def test_goals_nested_too_deep_exits_2_with_one_line(
    tmp_path: Path, refused: Callable[..., str]
) -> None:
    path = tmp_path / "deep.json"
    path.write_text("[" * 100_000 + "]" * 100_000)
    line = refused("solve", "--robot", "panda", "--goals", str(path))
    assert "nested 100000 levels deep, over the limit of 100" in line


def test_json_depth_skips_brackets_inside_strings() -> None:
    assert _args.json_depth(b"") == 0
    assert _args.json_depth(b'[{"a": [1, 2]}]') == 3
    assert _args.json_depth(b'["]]]]]]", [[1]]]') == 3
    assert _args.json_depth(b'["\\"[[[", [1]]') == 2  # an escaped quote does not end it
    assert _args.json_depth(b'["\\\\", [[1]]]') == 3  # an escaped backslash does not escape
    assert _args.json_depth(b'"' + b"[" * 500 + b'"') == 0
    deep = b'["' + b"]" * 1000 + b'", ' + b"[" * 200 + b"]" * 200 + b"]"
    assert _args.json_depth(deep) == 201  # closing brackets in a string hide nothing


def test_goals_file_of_a_normal_size_still_solves(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "goals.json"
    path.write_text(json.dumps([{"type": "Position", "frame": "panda_hand_tcp",
                                 "point": [0.5, 0.0, 0.3]}], indent=2))  # fmt: skip
    assert cli.main(["solve", "--robot", "panda", "--goals", str(path), "--json"]) in (0, 1)
    assert json.loads(capsys.readouterr().out)["goal_errors"][0]["goal"].startswith("Position")


# ------------------------------------------------------------ 3: --show with no terminal
def _wait_args(**kw: Any) -> argparse.Namespace:
    return argparse.Namespace(json=False, **kw)


def test_viewer_wait_returns_at_once_without_a_terminal(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv(_viewer.NO_WAIT_ENV, raising=False)
    monkeypatch.setattr(sys, "stdin", io.StringIO(""))  # not a TTY
    t0 = time.perf_counter()
    _viewer.wait(_wait_args(show_wait=None))
    assert time.perf_counter() - t0 < 1.0
    assert "stdin is not a TTY" in capsys.readouterr().out
    t0 = time.perf_counter()
    _viewer.wait(_wait_args(show_wait=0.3))  # --show-wait: kept up that long, no longer
    assert 0.25 < time.perf_counter() - t0 < 3.0
    assert "stays up for 0.3 s" in capsys.readouterr().out


def test_show_wait_refuses_negative_and_nan(capsys: pytest.CaptureFixture[str]) -> None:
    for bad in ("-1", "nan", "soon"):
        line = cli_error(capsys, "solve", "--robot", "yumi_left", *FROM_Q, "--show-wait", bad)
        assert "--show-wait" in line


def test_solve_show_with_no_terminal_does_not_block(tmp_path: Path) -> None:
    pytest.importorskip("meshcat")
    proc = _run(
        "solve", "--robot", "yumi_left", *FROM_Q, "--show",
        stdin=subprocess.DEVNULL, timeout=240, cwd=tmp_path,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    assert "meshcat viewer: http" in proc.stdout and "stdin is not a TTY" in proc.stdout


# -------------------------------------------------------------------- 4: --position-only
def test_position_only_takes_a_position_and_reports_no_rotation_error(
    capsys: pytest.CaptureFixture[str],
) -> None:
    pose = ["--pose", "0.4", "0.1", "0.4"]
    out = cli_json(capsys, "solve", "--robot", "panda", "--position-only", *pose)
    assert out["success"] and out["rotation_error"] is None
    assert out["goal_errors"][0]["rotation_error"] is None
    assert cli.main(["solve", "--robot", "panda", "--position-only", *pose]) == 0
    text = capsys.readouterr().out
    assert "rotation error n/a" in text and "0.000e+00 rad" not in text
    # a quaternion given anyway is accepted (and ignored)
    assert (
        cli.main(["solve", "--robot", "panda", "--position-only", *pose, "0", "0", "0", "1"]) == 0
    )
    capsys.readouterr()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--pose", "0.4", "0.1", "0.4"], "3 (X Y Z) only with --position-only"),
        (["--pose", "0.4", "0.1", "0.4", "0"], "expected 7 arguments"),
        (["--position-only", "--pose", "0.4", "0.1"], "or 3 (X Y Z) with --position-only"),
    ],
)
def test_pose_of_the_wrong_length_is_one_usage_line(
    argv: list[str], message: str, refused: Callable[..., str]
) -> None:
    line = refused("solve", "--robot", "panda", *argv)
    assert message in line and "swarm-ik solve --help" in line


# ------------------------------------------------------------------ 5: bounds, outputs
@pytest.mark.parametrize(
    ("bounds", "message"),
    [
        (["nan", "0", "0", "1", "1", "1"], "6 finite numbers"),
        (["0", "0", "0", "1", "inf", "1"], "6 finite numbers"),
        (["-inf", "0", "0", "1", "1", "1"], "6 finite numbers"),
        (["1", "0", "0", "0", "1", "1"], "not on x"),
        (["0", "0", "0", "1", "1", "0"], "not on z"),
    ],
)
def test_reach_refuses_non_finite_or_inverted_bounds_before_loading(
    bounds: list[str], message: str, tmp_path: Path, refused: Callable[..., str]
) -> None:
    argv = ["reach", "--robot", "yumi_left", "--out", str(tmp_path / "m.npz"), "--bounds"]
    line = refused(*argv, *bounds)
    assert "--bounds" in line and message in line
    assert list(tmp_path.iterdir()) == []


@pytest.fixture
def read_only_dir(tmp_path: Path) -> Path:
    """A folder where no file can be created: chmod 555, or, where that does not stop this
    user (root), a folder of a read-only file system."""
    from swarm_ik._validate import probe_folder

    d = tmp_path / "ro"
    d.mkdir()
    d.chmod(0o555)
    try:
        if probe_folder(d) is not None:
            yield d
            return
        for alt in (Path("/proc"), Path("/sys")):
            if alt.is_dir() and probe_folder(alt) is not None:
                yield alt
                return
        pytest.skip("no read-only folder available to this user")
    finally:
        d.chmod(0o755)


READ_ONLY = "cannot write in folder"


@pytest.mark.parametrize(
    ("command", "option", "path", "message"),
    [
        ("batch", "--out", "{ro}/r.npz", READ_ONLY),
        ("reach", "--out", "{ro}/m.npz", READ_ONLY),
        ("reach", "--png", "{ro}/m.png", READ_ONLY),
        ("solve", "--html", "{ro}/s.html", READ_ONLY),
        ("show", "--html", "{ro}/s.html", READ_ONLY),
        ("bench", "--out", "{ro}/bench-out", READ_ONLY),
        ("reach", "--out", "missing/m.npz", "does not exist"),
        ("reach", "--out", ".", "is a folder"),
        ("reach", "--png", "missing/m.png", "does not exist"),
        ("reach", "--html", "missing/m.html", "does not exist"),
        ("reach", "--out", "m.txt", "valid: .npz"),
    ],
)
def test_bad_outputs_exit_2_before_any_work(
    command: str,
    option: str,
    path: str,
    message: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    request: pytest.FixtureRequest,
    refused: Callable[..., str],
) -> None:
    """Output paths that cannot be written ({ro}: in a read-only folder) are refused before
    any robot is loaded, and nothing is written."""
    if command in ("solve", "show") or option == "--html":
        pytest.importorskip("meshcat")
    monkeypatch.chdir(tmp_path)
    argv = [a.format(tmp=tmp_path) for a in ARGS[command]]
    if option in argv:
        argv = argv[: argv.index(option)]
    if path.startswith("{ro}"):
        path = path.format(ro=request.getfixturevalue("read_only_dir"))
    if command == "bench":
        import swarm_ik.bench.ik as bench_ik

        monkeypatch.setattr(bench_ik, "run", never)
    line = refused(*argv, option, path)
    assert option in line and message in line
    assert [p.name for p in tmp_path.iterdir()] in ([], ["ro"])  # nothing written


def test_output_probe_leaves_nothing_behind(tmp_path: Path) -> None:
    assert _args.check_output_file(tmp_path / "r.npz", "--out", (".npz",)) == tmp_path / "r.npz"
    assert _args.check_output_folder(tmp_path / "a" / "b") == tmp_path / "a" / "b"
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------- 6: --html, meshes
MESHES_URDF = """<?xml version="1.0"?>
<robot name="arm"><link name="a"/>
<link name="b"><visual><geometry><mesh filename="package://nowhere_pkg/meshes/b.stl"/>
</geometry></visual></link>
<link name="c"><visual><geometry><mesh filename="meshes/c.stl"/></geometry></visual></link>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="k" type="revolute"><parent link="b"/><child link="c"/><origin xyz="0 0 0.3"/>
<axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"""


@pytest.mark.parametrize("command", ["solve", "show"])
def test_meshes_not_found_are_named_in_one_line_before_solving(
    command: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    pytest.importorskip("meshcat")
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(MESHES_URDF)
    monkeypatch.setattr(swarm_ik, "solve", never)
    monkeypatch.setattr(swarm_ik, "solve_many", never)
    argv = [command, "--robot", str(urdf), "--html", str(tmp_path / "a.html")]
    argv += ["--from-q", "0.1", "0.2"] + (["--position-only"] if command == "solve" else [])
    line = cli_error(capsys, *argv)
    assert "2 of the 2 meshes of robot 'arm' cannot be found" in line
    assert "package://nowhere_pkg/meshes/b.stl" in line and "meshes/c.stl" in line
    assert "ROS_PACKAGE_PATH" in line
    assert not (tmp_path / "a.html").exists()


def test_mesh_look_up_follows_pinocchio(tmp_path: Path) -> None:
    (tmp_path / "pkg" / "meshes").mkdir(parents=True)
    (tmp_path / "pkg" / "meshes" / "b.stl").write_text("solid b\nendsolid b\n")
    (tmp_path / "urdf").mkdir()
    urdf = tmp_path / "urdf" / "arm.urdf"
    urdf.write_text(MESHES_URDF.replace("nowhere_pkg", "pkg"))
    missing, total = _viewer.missing_meshes(urdf, [str(tmp_path / "urdf"), str(tmp_path)])
    assert (missing, total) == (["meshes/c.stl"], 2)
    panda = swarm_ik.load_robot("panda")
    from swarm_ik import viz

    assert _viewer.missing_meshes(panda.urdf_path, viz.package_dirs(panda))[0] == []


# ----------------------------------------------------------- 7: Ctrl-C, internal errors
@pytest.mark.parametrize("command", list(ARGS))
def test_ctrl_c_and_unexpected_errors_in_every_sub_command(
    command: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    argv = [a.format(tmp=tmp_path) for a in ARGS[command]]
    module = cli.COMMANDS[command]

    def ctrl_c(args: argparse.Namespace) -> int:
        raise KeyboardInterrupt

    def boom(args: argparse.Namespace) -> int:
        raise RuntimeError("broken\nhere")

    monkeypatch.delenv("SWARM_IK_DEBUG", raising=False)
    monkeypatch.setattr(module, "run", ctrl_c)
    assert cli.main(argv) == 130
    assert capsys.readouterr().err.strip() == "swarm-ik: interrupted"
    monkeypatch.setattr(module, "run", boom)
    assert "internal error (RuntimeError: broken here)" in cli_error(capsys, *argv, code=3)
    monkeypatch.setenv("SWARM_IK_DEBUG", "1")
    with pytest.raises(RuntimeError):
        cli.main(argv)


def test_ctrl_c_while_building_the_parser_exits_130(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def ctrl_c(command: str | None = None) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "build_parser", ctrl_c)
    assert cli.main(["solve", "--json"]) == 130
    assert json.loads(capsys.readouterr().out)["exit_code"] == 130


def test_ctrl_c_during_start_up_of_the_console_script_exits_130() -> None:
    code = (
        "import sys\n"
        "sys.argv = ['swarm-ik', 'robots']\n"
        "from swarm_ik import cli\n"
        "def ctrl_c():\n"
        "    raise KeyboardInterrupt\n"
        "cli._own_process = ctrl_c\n"
        "sys.exit(cli.main())\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 130 and proc.stderr.strip() == "swarm-ik: interrupted"


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_real_sigint_during_a_solve_is_one_line_and_130(tmp_path: Path) -> None:
    proc = subprocess.Popen(
        [sys.executable, "-m", "swarm_ik.cli", "solve", "--robot", "yumi_left", *FROM_Q,
         "--solver", "dls", "--max-evals", "1000000000", "--time-limit", "120",
         "--tol-pos", "1e-300", "--tol-rot", "1e-300"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
    )  # fmt: skip
    time.sleep(6.0)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    # (a line saying the kernels are being prepared may come first, on a slow start)
    assert err.strip().splitlines()[-1] == "swarm-ik: interrupted" and "Traceback" not in err


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_real_sigint_inside_one_large_batch_chunk_stops_within_a_second(tmp_path: Path) -> None:
    """The batch kernel enters Python every INTERRUPT_EVERY targets, so a Ctrl-C inside a
    chunk of 10⁶ targets stops the call at once (it ran on to the chunk's end, 15 s)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "swarm_ik.cli", "batch", "--robot", "panda", "--random",
         "1000000", "--chunk-size", "1000000", "--out", str(tmp_path / "b.npz"),
         "--no-progress"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
    )  # fmt: skip
    time.sleep(6.0)
    sent = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert time.perf_counter() - sent < 2.0
    assert "Traceback" not in err


# ------------------------------------------------------------------------------ 8: xacro
@pytest.mark.parametrize("command", ["solve", "show", "batch", "reach"])
def test_xacro_robot_is_refused_before_loading(
    command: str, tmp_path: Path, refused: Callable[..., str]
) -> None:
    xacro = tmp_path / "arm.urdf.xacro"
    xacro.write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="arm"/>')
    argv = [a.format(tmp=tmp_path) for a in ARGS[command]]
    argv[argv.index("yumi_left")] = str(xacro)
    line = refused(*argv)
    assert "xacro files must be expanded first" in line
    assert "`xacro arm.urdf.xacro > arm.urdf`" in line


def test_output_pipe_closed_by_the_reader_is_141_without_a_traceback() -> None:
    """``swarm-ik robots | head``: the reader goes away while the command still writes."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "swarm_ik.cli", "robots"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # the reader is gone before the first line (head after its lines)
    err = proc.stderr.read()
    assert proc.wait(timeout=120) == 141, err
    assert "Traceback" not in err


# ------------------------------------------------------------- numbers of every sub-command
@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["batch", "--robot", "yumi_left", "--random", "2", "--out", "{tmp}/r.npz", "--seed", "-1"],
         ["--seed", "[0, 2**63)"]),
        (["reach", "--robot", "yumi_left", "--out", "{tmp}/m.npz", "--seed", "-1"], ["--seed"]),
        (["reach", "--robot", "yumi_left", "--out", "{tmp}/m.npz", "--max-targets", "0"],
         ["--max-targets", "from 1"]),
        (["bench", "ik", "--quick", "--out", "{tmp}/b", "--seed", "-1"], ["--seed"]),
        (["bench", "ik", "--quick", "--out", "{tmp}/b", "--budgets-ms", "nan"],
         ["--budgets-ms", "finite number > 0"]),
        (["bench", "ik", "--quick", "--out", "{tmp}/b", "--budgets-ms", "inf"], ["--budgets-ms"]),
        (["bench", "many", "--out", "{tmp}/b", "--n-targets", "0"], ["--n-targets"]),
        (["bench", "goals", "--out", "{tmp}/b", "--n", "-3"], ["--n", "from 1"]),
        (["bench", "throughput", "--quick", "--out", "{tmp}/b", "--boxes", "-1"], ["--boxes"]),
        (["bench", "throughput", "--quick", "--out", "{tmp}/b", "--loop-max", "-1"],
         ["--loop-max", "from 0"]),
        (["bench", "collision", "--quick", "--out", "{tmp}/b", "--seed", "-1"], ["--seed"]),
        (["bench", "wholebody", "--quick", "--out", "{tmp}/b", "--seed", "-1"], ["--seed"]),
        (["solve", "--robot", "yumi_left", *FROM_Q, "--max-evals", "99999999999999999999999"],
         ["max_evals must be at most 2**62"]),
        (["solve", "--robot", "yumi_left", *FROM_Q, "--solver", "gwo", "--param",
          "iterations=1000000000"], ["iterations", "MAX_ITERATIONS"]),
    ],
)  # fmt: skip
def test_numbers_out_of_range_are_refused_with_one_line(
    argv: list[str], words: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    line = cli_error(capsys, *(a.format(tmp=tmp_path) for a in argv))
    assert all(w in line for w in words), line


def test_empty_target_files_and_huge_reach_bounds_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import numpy as np

    (tmp_path / "empty.csv").write_text("x,y,z,qx,qy,qz,qw\n")
    np.save(tmp_path / "empty.npy", np.zeros((0, 4, 4)))
    for name in ("empty.csv", "empty.npy"):
        line = cli_error(capsys, "batch", "--robot", "yumi_left", "--targets",
                         str(tmp_path / name), "--out", str(tmp_path / "b.npz"))  # fmt: skip
        assert "holds no targets" in line
    for big in ("1e300", "1e308"):  # (1e308: an extent beyond a float)
        bounds = [f"-{big}"] * 3 + [big] * 3
        line = cli_error(
            capsys,
            "reach",
            "--robot",
            "yumi_left",
            "--bounds",
            *bounds,
            "--out",
            str(tmp_path / "m.npz"),
        )
        assert "over 1e300 voxels" in line and "smaller bounds" in line


def test_api_budgets_beyond_numbers_are_refused() -> None:
    from swarm_ik.errors import InvalidArgumentError

    robot = swarm_ik.load_robot("yumi_left")
    problem = swarm_ik.IKProblem(robot, robot.fk(robot.mid_q()))
    with pytest.raises(InvalidArgumentError, match="max_evals"):
        swarm_ik.solve(problem, max_evals=10**30)
    with pytest.raises(InvalidArgumentError, match="time_limit"):
        swarm_ik.solve(problem, time_limit=10**400)
    with pytest.raises(InvalidArgumentError, match="ee_frame"):
        swarm_ik.load_robot("yumi_left", 5)  # type: ignore[arg-type]


def test_a_schedule_of_many_evaluations_stays_within_the_iteration_cap() -> None:
    """``SolverSpec.schedule`` of a budget beyond MAX_ITERATIONS iterations (DLS: one
    evaluation each) gives settings that ``solve`` accepts."""
    from swarm_ik.solvers import base

    kw = base.get("dls").schedule(2_000_000)
    assert kw["iterations"] == base.MAX_ITERATIONS and kw["max_evals"] == 2_000_000
    robot = swarm_ik.load_robot("yumi_left")
    problem = swarm_ik.IKProblem(robot, robot.fk(robot.mid_q()))
    assert swarm_ik.solve(problem, "dls", **kw).success


def test_a_ctrl_c_swallowed_in_a_callback_is_raised_again() -> None:
    """Python swallows a KeyboardInterrupt raised in a callback from compiled code (numba's
    and llvmlite's while kernels load: "Exception ignored on calling ctypes callback"); the
    console script's hook raises it again in the main thread, so the command stops (130)."""
    import time
    import types

    from swarm_ik import cli

    cli._unraisable(types.SimpleNamespace(exc_value=KeyboardInterrupt()))
    with pytest.raises(KeyboardInterrupt):
        time.sleep(2.0)


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["solve", "--robot", "yumi_left", *FROM_Q, "--no-self-collision"], "--scene"),
        (["solve", "--robot", "yumi_left", *FROM_Q, "--srdf", "x.srdf"], "--scene or --goals"),
        (["solve", "--robot", "yumi_left", *FROM_Q, "--show-wait", "2"], "--show"),
        (["reach", "--robot", "yumi_left", "--png", "a.png", "--no-png"], "contradict"),
        (["reach", "--robot", "yumi_left", "--html", "a.html", "--no-html"], "contradict"),
        (["show", "--robot", "yumi_left", "--html", "a.html", "--show-wait", "2"], "--show"),
    ],
)
def test_options_that_modify_nothing_or_contradict_are_refused(
    argv: list[str],
    said: str,
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """An option given without the one it modifies, or beside its own negation, is a mistake
    the user wants to hear about (exit 2, one line naming both), not a silent no-op."""
    monkeypatch.chdir(tmp_path)
    line = cli_error(capsys, *argv)
    assert said in line and argv[-1 if argv[-1].startswith("--") else -2] in line
    assert not any(tmp_path.iterdir())


def test_a_ctrl_c_while_the_command_imports_its_modules_is_one_line(tmp_path: Path) -> None:
    """A Ctrl-C 30-70 ms into ``swarm-ik robots``, while the sub-command modules were being
    imported (before ``main`` runs), printed a traceback of the imports.  Here an import hook
    holds the import of ``swarm_ik.cli.batch`` for 2 s, and the Ctrl-C lands inside it."""
    flag = str(tmp_path / "importing")
    (tmp_path / "sitecustomize.py").write_text(
        "import sys, time\n"
        "class _Slow:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name == 'swarm_ik.cli.batch':\n"
        f"            open({flag!r}, 'w').close()\n"
        "            time.sleep(2.0)\n"
        "        return None\n"
        "sys.meta_path.insert(0, _Slow())\n"
    )
    env = {**os.environ, "PYTHONPATH": f"{tmp_path}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "swarm_ik.cli", "robots"], env=env,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    deadline = time.monotonic() + 60
    while not (tmp_path / "importing").exists():
        assert proc.poll() is None and time.monotonic() < deadline
        time.sleep(0.01)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.strip() == "swarm-ik: interrupted", err


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full here")
@pytest.mark.parametrize(
    "argv",
    [["robots"], ["solve", "--robot", "panda", "--pose", "0.4", "0.1", "0.5", "1", "0", "0", "0"]],
)
def test_a_full_output_is_one_line_and_exit_74(argv: list[str]) -> None:
    """``swarm-ik … > /dev/full`` was "internal error (OSError …); please report it", exit 3:
    the environment's failure, one line and exit 74, nothing else on stderr."""
    with open("/dev/full", "w") as full:
        out = subprocess.run(
            [sys.executable, "-m", "swarm_ik.cli", *argv], stdout=full, stderr=subprocess.PIPE,
            text=True, timeout=600,
        )  # fmt: skip
    assert out.returncode == 74, out.stderr
    assert out.stderr.strip() == "swarm-ik: cannot write (No space left on device)"


def test_an_io_error_that_is_not_the_outputs_is_not_reported_as_one(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """An input/output error reading a file (here: loading the robot) was "cannot write the
    output", exit 74, and the host process lost its standard output; a full disk while a
    file of the command is written is 74 and names the file, the JSON object still printed."""
    import errno

    from swarm_ik.cli import solve as solve_cli

    def failing_read(*args: Any, **kwargs: Any) -> None:
        raise OSError(errno.EIO, "Input/output error")

    monkeypatch.setattr(solve_cli, "load_robot", failing_read)
    argv = ["solve", "--robot", "panda", "--pose", "0.4", "0.1", "0.5", "1", "0", "0", "0"]
    assert cli.main([*argv, "--json"]) == 3
    assert json.loads(capsys.readouterr().out)["exit_code"] == 3

    def full_disk(*args: Any, **kwargs: Any) -> None:
        raise OSError(errno.ENOSPC, "No space left on device", "answers.csv")

    monkeypatch.setattr(solve_cli, "load_robot", full_disk)
    assert cli.main([*argv, "--json"]) == 74
    out = json.loads(capsys.readouterr().out)
    assert out["exit_code"] == 74 and "cannot write 'answers.csv'" in out["error"]
    print("still here")
    assert capsys.readouterr().out == "still here\n"


@pytest.mark.parametrize(
    ("argv", "ours"),
    [
        (["python", "/venv/bin/swarm-ik", "solve"], True),
        (["python", "-X", "dev", "/venv/bin/swarm-ik"], True),
        (["python", "-X", "importtime", "-m", "swarm_ik.cli", "robots"], True),
        (["python", "-u", "-B", "C:\\venv\\Scripts\\swarm-ik.exe"], os.sep == "\\"),
        (["python", "x.py", "-m", "swarm_ik.cli"], False),
        (["python", "-c", "import swarm_ik", "-m", "swarm_ik.cli"], False),
        (["python", "-m", "pytest", "-m", "swarm_ik.cli"], False),
        (["python"], False),
    ],
)
def test_only_the_console_script_gets_the_start_up_ctrl_c_handler(
    argv: list[str], ours: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``python x.py -m swarm_ik.cli`` was taken for the console script (its process then
    exited 130 on any Ctrl-C, with no clean-up); ``python -X dev swarm-ik`` was not."""
    from swarm_ik import _startup

    monkeypatch.setattr(sys, "orig_argv", argv)
    assert _startup.console_script() == ours


def test_an_unreachable_target_says_why(capsys: pytest.CaptureFixture[str]) -> None:
    """A solve that ends ``unreachable`` prints which goal and why (the bare word before)."""
    argv = ["solve", "--robot", "panda", "--pose", "3", "0", "0", "0", "0", "0", "1"]
    from swarm_ik.cli import main

    assert main([*argv, "--time-limit", "0.05"]) == 1
    out = capsys.readouterr().out
    assert "why: Pose(panda_hand_tcp) beyond its frame's reach (its point 3 m from" in out
    d = cli_json(capsys, *argv, "--time-limit", "0.05", code=1)
    assert d["reason"] == "unreachable" and "beyond its frame's reach" in d["why"]
