"""The command line refuses what it cannot use before any work, and leaves nothing behind:
``--report-only`` over no results, bad benchmark names and schedulers, input paths that are
not regular files, and options that modify one not given."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import pytest
from conftest import FROM_Q, cli_error

from swarm_ik.cli import main

Q_PANDA = ["0", "0", "0", "-1.5", "0", "1.5", "0.7"]


# ------------------------------------------------------------------ bench: refused, no files
@pytest.mark.parametrize("command", ["ik", "paper"])
def test_report_only_over_an_empty_folder_names_the_quick_command(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """An existing empty folder is refused like a missing one, and a ``--quick`` report is
    pointed at the ``--quick`` run that makes its results; nothing is written there."""
    out = tmp_path / "empty"
    out.mkdir()
    line = cli_error(capsys, "bench", command, "--quick", "--report-only", "--out", str(out))
    assert "no results to report" in line and str(out) in line
    assert f"swarm-ik bench {command} --quick --out" in line
    assert not any(out.iterdir())


def test_report_only_says_it_wrote_only_the_report(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """``bench ik --report-only`` rebuilds summary.md from peers.csv: it does not claim to
    have written peers.csv."""
    out = tmp_path / "ik"
    argv = ["bench", "ik", "--quick", "--n", "2", "--peers", "swarm", "--out", str(out)]
    assert main(argv) == 0
    capsys.readouterr()
    before = (out / "peers.csv").read_bytes()
    assert main([*argv, "--report-only"]) == 0
    said = [x for x in capsys.readouterr().err.splitlines() if x.startswith("wrote ")]
    assert said == [f"wrote {out / 'summary.md'}"]
    assert (out / "peers.csv").read_bytes() == before


@pytest.mark.parametrize(
    ("argv", "said"),
    [
        (["throughput", "--quick", "--scheduler", "bogus"], "unknown scheduler 'bogus'"),
        (["ik", "--quick", "--robots", "nosuch.urdf"], "nosuch.urdf"),
        (["collision", "--quick", "--robots", "panda,nosuch"], "unknown robot 'nosuch'"),
        (["collision", "--quick", "--robots", ","], "--robots"),
    ],
)
def test_a_refused_benchmark_leaves_nothing_in_its_folder(
    argv: list[str], said: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Refused before the folder is made: no run.json (which refused the next run of the
    other kind there) and no scenes of the robots named before the bad one."""
    out = tmp_path / "out"
    line = cli_error(capsys, "bench", *argv, "--out", str(out))
    assert said in line
    assert not out.exists()


# ------------------------------------------------------- input paths: not "not found"
def _not_a_file(kind: str, tmp_path: Path) -> tuple[Path, str]:
    """A path of ``kind`` that exists and is not a regular file, and what the error calls it."""
    if kind == "fifo":
        if not hasattr(os, "mkfifo"):
            pytest.skip("no FIFOs here")
        path = tmp_path / "pipe"
        os.mkfifo(path)
        return path, "is a named pipe (FIFO)"
    if kind == "device":
        if not Path("/dev/zero").exists():
            pytest.skip("no /dev/zero here")
        return Path("/dev/zero"), "is a device"
    return tmp_path, "is a folder"


@pytest.mark.parametrize("kind", ["fifo", "device", "folder"])
@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["solve", "--robot", "yumi_left", *FROM_Q, "--scene"], "--scene"),
        (["solve", "--robot", "yumi_left", *FROM_Q, "--scene", "s.json", "--srdf"], "--srdf"),
        (["path", "--robot", "panda", "--poses", "p.csv", "--scene"], "--scene"),
    ],
)
def test_an_input_path_that_is_not_a_regular_file_says_what_it_is(
    kind: str, argv: list[str], option: str, tmp_path: Path, refused: Callable[..., str]
) -> None:
    path, what = _not_a_file(kind, tmp_path)
    line = refused(*argv, str(path))
    assert option in line and str(path) in line and what in line
    assert "not found" not in line


# ------------------------------------------------- options that modify one not given
@pytest.mark.parametrize(
    ("extra", "option", "other"),
    [
        (["--html", "a.html", "--open"], "--open", "--show"),
        (["--q", *Q_PANDA, "--solutions", "3"], "--solutions", "--q"),
        (["--q", *Q_PANDA, "--min-distance", "0.2"], "--min-distance", "--q"),
        (["--q", *Q_PANDA, "--solver", "dls"], "--solver", "--q"),
    ],
)
def test_show_refuses_an_option_that_modifies_nothing(
    extra: list[str],
    option: str,
    other: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    refused: Callable[..., str],
) -> None:
    """``--open`` without the live viewer, or what tunes a solve beside given ``--q`` (then
    nothing is solved), is refused naming both options, before the robot is loaded."""
    monkeypatch.chdir(tmp_path)
    line = refused("show", "--robot", "panda", *extra)
    assert option in line and other in line
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("command", "extra", "expected"),
    [
        ("solve", ["--no-self-collision"], "--no-self-collision applies to --scene, which"),
        ("solve", ["--srdf", "x.srdf"], "--srdf applies to --scene or --goals, which"),
        ("batch", ["--no-self-collision"], "--no-self-collision applies to --scene, which"),
        ("batch", ["--srdf", "x.srdf"], "--srdf applies to --scene, which"),
        ("solve", ["--scene", "s.json", "--srdf", "x.srdf", "--no-self-collision"], "--srdf names"),
        ("batch", ["--scene", "s.json", "--srdf", "x.srdf", "--no-self-collision"], "--srdf names"),
    ],
)
def test_collision_options_that_modify_nothing_are_refused_alike_by_solve_and_batch(
    command: str,
    extra: list[str],
    expected: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    refused: Callable[..., str],
) -> None:
    """``check_collision_options`` (one check for both commands): ``--no-self-collision`` and
    ``--srdf`` without what they modify, or together, refused before the robot is loaded."""
    monkeypatch.chdir(tmp_path)
    rest = FROM_Q if command == "solve" else ["--random", "3", "--out", "r.npz"]
    line = refused(command, "--robot", "yumi_left", *rest, *extra)
    assert expected in line
    assert not any(tmp_path.iterdir())


def test_a_warning_is_one_line_without_the_package_source(capsys) -> None:
    """A q0 outside the limits is clipped with a warning: on the command line one line,
    ``swarm-ik: warning: …`` (it printed the package's file, line and source line)."""
    q0 = ["0", "0", "0", "-2", "0", "2", "9"]  # (panda_joint7 beyond its limit)
    rc = main(["solve", "--robot", "panda", "--from-q", *["0.1"] * 7, "--q0", *q0])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 0
    warn = [line for line in err if "q0 lies outside the joint limits" in line]
    assert warn and warn[0].startswith("swarm-ik: warning: ")
    assert not any(".py:" in line for line in err), err


def test_a_missing_waypoints_file_is_named_by_its_option(refused) -> None:
    line = refused("path", "--robot", "ur5", "--poses", "missing.csv")
    assert line == "swarm-ik: error: --poses file not found: 'missing.csv'"


@pytest.mark.parametrize(
    ("command", "option", "suffix"),
    [("batch", "--targets", ".csv"), ("path", "--poses", ".csv")],
)
def test_out_naming_the_input_file_is_refused_and_the_input_kept(
    command: str,
    option: str,
    suffix: str,
    tmp_path: Path,
    refused: Callable[..., str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``batch --targets t.csv --out t.csv`` replaced the targets with the answers (exit 0);
    the same file under another spelling too.  Refused before any work, the input intact."""
    given = tmp_path / f"in{suffix}"
    text = "x,y,z,qx,qy,qz,qw\n0.4,0.1,0.5,1,0,0,0\n0.4,0.2,0.5,1,0,0,0\n"
    given.write_text(text)
    monkeypatch.chdir(tmp_path)
    for out in (str(given), f"./{given.name}"):
        line = refused(command, "--robot", "panda", option, str(given), "--out", out)
        assert f"is the file given to {option}" in line
    assert given.read_text() == text


def test_an_unknown_compare_solver_is_refused_before_the_solve(
    refused: Callable[..., str], tmp_path: Path
) -> None:
    """``solve --compare nope`` printed the whole solve, then refused the name."""
    line = refused(
        "solve", "--robot", "panda", "--pose", "0.4", "0.1", "0.5", "1", "0", "0", "0",
        "--compare", "nope", "--html", str(tmp_path / "x.html"),
    )  # fmt: skip
    assert "unknown solver 'nope'" in line


@pytest.mark.parametrize("n", ["0", "65", "1000000"])
def test_show_solutions_beyond_its_cap_is_refused(n: str, refused: Callable[..., str]) -> None:
    """``show --solutions 1000000`` searched for minutes with no output."""
    line = refused(
        "show", "--robot", "panda", "--from-q", "0", "0", "0", "-1", "0", "1", "0",
        "--solutions", n, "--html", "s.html",
    )  # fmt: skip
    assert (
        f"--solutions must be a count from 1 to 64 (swarm_ik.cli.show.MAX_SHOWN), got {n}" in line
    )


def test_an_output_that_fails_midway_leaves_the_old_file(tmp_path: Path) -> None:
    """Outputs are written beside and renamed into place (``paths.written_in_place_of``): a
    full disk left a reachability map's page and a solve's page truncated in place.  A write
    that fails midway keeps the old file and leaves nothing beside it; one that ends replaces
    it whole, with the old file's mode, through a symbolic link (the link kept); two writers
    of one path at once each get a file of their own (they shared one name, and mixed)."""
    from swarm_ik.paths import written_in_place_of

    out = tmp_path / "page.html"
    out.write_text("OLD")
    os.chmod(out, 0o600)
    with pytest.raises(OSError), written_in_place_of(out) as part:
        part.write_text("NEW, half")
        raise OSError(28, "No space left on device")
    assert out.read_text() == "OLD" and sorted(p.name for p in tmp_path.iterdir()) == ["page.html"]
    with written_in_place_of(out) as one, written_in_place_of(out) as two:
        assert one != two
        one.write_text("ONE")
        two.write_text("TWO")
    assert out.read_text() == "ONE" and (out.stat().st_mode & 0o777) == 0o600
    assert sorted(p.name for p in tmp_path.iterdir()) == ["page.html"]
    link = tmp_path / "link.html"
    link.symlink_to(out)
    with written_in_place_of(link) as part:
        part.write_text("NEW")
    assert link.is_symlink() and out.read_text() == "NEW"


def test_a_reach_picture_without_a_suffix_is_a_png(tmp_path: Path) -> None:
    """``plot_slices(rmap, "slices")`` writes ``slices.png`` (the temporary file's ``.part``
    was taken for the format)."""
    pytest.importorskip("matplotlib")
    import swarm_ik
    from swarm_ik.reach import plot_slices, reach_map

    rmap = reach_map(swarm_ik.load_robot("ur5"), resolution=0.4, n_orientations=1)
    written = plot_slices(rmap, tmp_path / "slices")
    assert written == tmp_path / "slices.png" and written.stat().st_size > 1000


@pytest.mark.skipif(not hasattr(os, "fork"), reason="resource limits of a child: POSIX")
def test_a_path_written_past_the_file_size_limit_keeps_the_old_output(tmp_path: Path) -> None:
    """``swarm-ik path --out`` under a file-size limit (a full disk): exit 74, one line, and
    the old output kept whole."""
    import resource
    import subprocess
    import sys

    poses = tmp_path / "line.csv"
    rows = ["x,y,z,qx,qy,qz,qw"] + [f"{0.4 + 0.01 * k},0.1,0.5,1,0,0,0" for k in range(8)]
    poses.write_text("\n".join(rows) + "\n")
    out = tmp_path / "q.csv"
    out.write_text("OLD\n")

    def small_files() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (100, 100))

    argv = [sys.executable, "-m", "swarm_ik.cli", "path", "--robot", "panda", "--poses",
            str(poses), "--out"]  # fmt: skip
    warm = tmp_path / "warm" / "q.csv"  # (numba's cache filled first: its files are large)
    warm.parent.mkdir()
    subprocess.run([*argv, str(warm)], capture_output=True, timeout=600, check=True)
    done = subprocess.run(
        [*argv, str(out)], capture_output=True, text=True, timeout=600, preexec_fn=small_files
    )
    assert done.returncode == 74, done.stderr
    assert done.stderr.strip().startswith("swarm-ik: cannot write"), done.stderr
    assert out.read_text() == "OLD\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["line.csv", "q.csv", "warm"]


def test_compare_analytic_on_a_problem_it_cannot_solve_is_refused_before_the_solve(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """``--compare analytic`` on a 7-joint arm printed the whole solve, then the refusal (two
    JSON objects with ``--json``); refused before solving now, one object."""
    pytest.importorskip("eaik")
    import json

    from conftest import never

    import swarm_ik

    monkeypatch.setattr(swarm_ik, "solve", never)
    argv = ["solve", "--robot", "yumi_left", *FROM_Q, "--compare", "analytic", "--html",
            str(tmp_path / "a.html"), "--json"]  # fmt: skip
    assert main(argv) == 2
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1 and "--compare analytic: no analytic IK" in json.loads(out[0])["error"]
