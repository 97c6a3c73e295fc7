"""Every numbered example runs as a script, headless and short (``SWARM_IK_QUICK=1``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("[0-9]*.py"))
TIMEOUT_S = 120


def test_examples_exist() -> None:
    numbers = [p.name[:2] for p in EXAMPLES]
    for n in ("01", "02", "03", "04", "06"):
        assert n in numbers, f"examples/{n}_*.py is missing; found {[p.name for p in EXAMPLES]}"


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_runs(script: Path, tmp_path: Path) -> None:
    env = dict(os.environ, SWARM_IK_QUICK="1", MPLBACKEND="Agg", SWARM_IK_NO_WAIT="1")
    env.pop("DISPLAY", None)  # no viewer window, whatever the machine has
    proc = subprocess.run(
        [sys.executable, str(script)],
        cwd=tmp_path,
        env=env,
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
    )
    assert proc.returncode == 0, (
        f"{script.name} exited {proc.returncode}\n--- stdout\n{proc.stdout[-3000:]}"
        f"\n--- stderr\n{proc.stderr[-3000:]}"
    )
    assert proc.stdout.strip(), f"{script.name} printed nothing"
    assert "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == [], f"{script.name} wrote into the working directory"
