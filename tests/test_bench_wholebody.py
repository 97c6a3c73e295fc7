"""``swarm-ik bench wholebody``: a small run writes its CSV, report and plot; swarm_ik's answers
pass the Pinocchio judge; bad options are refused."""

from __future__ import annotations

from pathlib import Path

import pytest

from swarm_ik.bench.common import read_csv as read_rows
from swarm_ik.cli import main


def test_small_run_writes_report_and_our_answers_pass_the_judge(tmp_path: Path) -> None:
    out = tmp_path / "wb"
    rc = main([
        "bench", "wholebody", "--n", "6", "--chunk", "3", "--time-limit-ms", "200",
        "--solvers", "swarm_ik,swarm_ik-tolerance,pink", "--out", str(out),
    ])  # fmt: skip
    assert rc == 0
    rows = read_rows(out / "wholebody.csv")
    assert {r["solver"] for r in rows} == {"swarm_ik", "swarm_ik-tolerance", "pink"}
    ours = [r for r in rows if r["solver"] == "swarm_ik"]
    assert len(ours) == 6
    assert all(r["success"] == "1" and r["claimed"] == "1" for r in ours)
    assert all(float(r["hand_pos"]) <= 1e-5 for r in ours)
    summary = (out / "summary.md").read_text()
    assert "Tolerance goals" in summary and "| pink |" in summary
    assert (out / "times.png").stat().st_size > 0


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["--n", "0"], "--n"),
        (["--time-limit-ms", "-1"], "--time-limit-ms"),
        (["--solvers", "nope"], "--solvers"),
        (["--chunk", "0"], "--chunk"),
    ],
)
def test_bad_options_exit_2(
    argv: list[str], words: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["bench", "wholebody", *argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err
