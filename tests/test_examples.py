"""Every numbered example runs as a script, headless and short (``SWARM_IK_QUICK=1``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("[0-9]*.py"))
TIMEOUT_S = 120


def _run_script(
    script: Path, *args: str, cwd: Path, quick: bool = True
) -> subprocess.CompletedProcess[str]:
    """Run an example headless (no viewer window, no waiting), short unless ``quick=False``."""
    env = dict(os.environ, MPLBACKEND="Agg", SWARM_IK_NO_WAIT="1")
    env.pop("DISPLAY", None)  # no viewer window, whatever the machine has
    if quick:
        env["SWARM_IK_QUICK"] = "1"
    else:
        env.pop("SWARM_IK_QUICK", None)
    return subprocess.run(
        [sys.executable, str(script), *args],
        cwd=cwd,
        env=env,
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
    )


def test_examples_exist() -> None:
    numbers = [p.name[:2] for p in EXAMPLES]
    for n in ("01", "02", "03", "04", "06"):
        assert n in numbers, f"examples/{n}_*.py is missing; found {[p.name for p in EXAMPLES]}"


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_runs(script: Path, tmp_path: Path) -> None:
    proc = _run_script(script, cwd=tmp_path)
    assert proc.returncode == 0, (
        f"{script.name} exited {proc.returncode}\n--- stdout\n{proc.stdout[-3000:]}"
        f"\n--- stderr\n{proc.stderr[-3000:]}"
    )
    assert proc.stdout.strip(), f"{script.name} printed nothing"
    assert "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == [], f"{script.name} wrote into the working directory"


def _run(name: str, *args: str, cwd: Path, quick: bool = True) -> subprocess.CompletedProcess[str]:
    """Run the example whose file name starts with ``name`` (e.g. ``"04"``)."""
    script = next(p for p in EXAMPLES if p.name.startswith(name))
    return _run_script(script, *args, cwd=cwd, quick=quick)


def test_example_04_writes_its_plot_where_asked_and_nowhere_else(tmp_path: Path) -> None:
    out = tmp_path / "plots" / "c.png"
    out.parent.mkdir()
    work = tmp_path / "work"
    work.mkdir()
    proc = _run("04", "--out", str(out), cwd=work)
    assert proc.returncode == 0, proc.stderr
    assert out.stat().st_size > 10_000
    assert list(work.iterdir()) == []


def test_example_05_shows_nearest_and_best_differ(tmp_path: Path) -> None:
    """Seeded with the start, the first answer is the start's branch (no first step); solved
    afresh from the middle of the ranges, it is another branch (a large first step).  (The
    example said the unseeded path jumps along the way: on these short paths it does not;
    its largest step was the first, from the start.)"""
    proc = _run("05", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    first: dict[str, list[float]] = {}
    along: dict[str, list[float]] = {}
    for line in proc.stdout.splitlines():
        for label in ("nearest", "best, seeded", "best, no seed"):
            if f" {label} " in line:
                first.setdefault(label, []).append(float(line.split("first step")[1].split()[0]))
                along.setdefault(label, []).append(float(line.split("along")[1].split()[0]))
    assert len(first["nearest"]) == len(first["best, no seed"]) == 2
    assert all(f < 0.5 for f in first["nearest"])
    assert all(a < 10.0 for a in along["nearest"])  # (seeded, nearest: no jump along the path)
    assert all(f > 10.0 for f in first["best, no seed"])
