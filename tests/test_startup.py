"""Start-up: a light `import swarm_ik`, and the first solve of a fresh process meets 5 ms."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("dask", "matplotlib", "meshcat", "yourdfpy", "trimesh", "swarm_ik.bench")
"""Optional dependencies kept off the solve path.  (``coal`` is not listed: Pinocchio itself
imports it.)"""


def _run(code: str) -> str:
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=600, check=True
    )
    return out.stdout.strip().splitlines()[-1]


def test_import_loads_nothing_heavy() -> None:
    got = json.loads(
        _run(
            "import sys, json, swarm_ik; "
            "print(json.dumps(sorted(m for m in sys.modules if m.split('.')[0] in "
            "('numba', 'pinocchio', 'scipy', 'dask', 'matplotlib'))))"
        )
    )
    assert got == []


def test_solve_path_imports_no_optional_heavy_dependency() -> None:
    code = (
        "import sys, json, numpy as np, swarm_ik\n"
        "r = swarm_ik.load_robot('panda')\n"
        "ik = swarm_ik.IKSolver(r, time_limit=0.005)\n"
        "ik.solve(r.fk(r.random_q(np.random.default_rng(0))))\n"
        "swarm_ik.solve(swarm_ik.IKProblem.from_q(r, r.mid_q()))\n"
        f"print(json.dumps([m for m in sys.modules if m.startswith({HEAVY!r})]))\n"
    )
    assert json.loads(_run(code)) == []


@pytest.mark.parametrize(
    ("warm", "call"),
    [
        ("True", "swarm_ik.solve(swarm_ik.IKProblem(r, T), time_limit=0.005)"),
        ("False", "swarm_ik.solve(swarm_ik.IKProblem(r, T), time_limit=0.005)"),
        ("False", "swarm_ik.IKSolver(r, time_limit=0.005).solve(T)"),
        ("False", "swarm_ik.solve(swarm_ik.IKProblem(r, T), time_limit=0.005, seed=rng)"),
        (
            "False",
            "swarm_ik.solve_many(swarm_ik.IKProblem(r, T), n=2, time_limit=0.05, "
            "method='numerical')[0]",
        ),
    ],
)
def test_first_solve_of_a_fresh_process_meets_its_budget(warm: str, call: str) -> None:
    """Kernels are loaded before the clock starts: by load_robot, or (warm_up=False, as the
    CLI does) by the first solve / IKSolver / solve_many itself."""
    code = (
        "import numpy as np, swarm_ik\n"
        f"r = swarm_ik.load_robot('panda', warm_up={warm})\n"
        "rng = np.random.default_rng(1)\n"
        "T = r.fk(np.array([0.1, -0.5, 0.3, -2.0, 0.2, 1.5, 0.4]))\n"
        f"res = {call}\n"
        "print(res.success, res.time_s)\n"
    )
    ok, t = _run(code).split()
    assert ok == "True", t
    assert float(t) < (0.05 if "solve_many" in call else 0.005)


def test_console_script_start_up_keeps_scipy_importable() -> None:
    """The console script hides scipy.linalg from numba's one BLAS probe, then puts it back;
    its solve is the same, and the collector is off only for its own process."""
    code = (
        "import gc, json, sys\n"
        "sys.argv = ['swarm-ik', 'solve', '--robot', 'panda', '--json', '--from-q',"
        " '0.1', '-0.5', '0.3', '-2.0', '0.2', '1.5', '0.4']\n"
        "from swarm_ik import cli\n"
        "import contextlib, io\n"
        "buf = io.StringIO()\n"
        "with contextlib.redirect_stdout(buf):\n"
        "    rc = cli.main()\n"
        "hidden = 'scipy.linalg' in sys.modules\n"
        "import scipy.linalg.cython_blas\n"
        "print(json.dumps([rc, json.loads(buf.getvalue())['success'], hidden, gc.isenabled()]))\n"
    )
    assert json.loads(_run(code)) == [0, True, False, False]


def test_main_with_argv_leaves_the_collector_alone() -> None:
    import gc

    from swarm_ik import cli

    assert gc.isenabled()
    assert cli.main(["robots"]) == 0
    assert gc.isenabled()
