"""Compare the solvers on one Panda pose, with a convergence plot.

Eight solvers (the papers' optimisers ``foa``, ``hlfoa``, ``gwo``, ``mgwo``, ``pso-improved`` and
``cs-newton``, our ``swarm`` and the ``dls`` baseline; the registry's other names are variants
of these) get the same target and the same budget
of fitness evaluations (``stop_on_success=False``, so each runs until the budget or its own
iteration count ends, as in the papers' experiments).  The script prints one line per solver
and draws the best fitness against the evaluations spent (``Result.history`` holds the best
fitness after each iteration; an iteration costs ``n_evals / iterations`` evaluations on
average).

Run: ``python examples/04_compare_solvers.py [--out convergence.png]`` (the plot needs
matplotlib, the ``plot`` extra; without it the table is printed and the plot skipped).
Without ``--out`` the plot goes into a temporary folder (its path is printed); nothing is
written into the current folder.  A few seconds (``SWARM_IK_QUICK=1``: a smaller budget).
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

import numpy as np

import swarm_ik
from swarm_ik.viz import output_file

QUICK = os.environ.get("SWARM_IK_QUICK") == "1"
BUDGET = 1_000 if QUICK else 3_000
SOLVERS = ("swarm", "dls", "hlfoa", "mgwo", "gwo", "pso-improved", "cs-newton", "foa")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=output_file(".png"), default=None, help="PNG file for the plot"
    )
    args = parser.parse_args()
    if args.out is not None:
        run(args.out)
    elif QUICK:  # the test suite: a folder deleted afterwards
        with tempfile.TemporaryDirectory() as tmp:
            run(Path(tmp) / "convergence.png")
    else:  # a folder kept, so that the plot can be opened (made when there is a plot)
        run(None)


def run(out: Path | None) -> None:
    """Solve with every solver, print the table, save the plot to ``out`` (None: into a new
    temporary folder)."""
    robot = swarm_ik.load_robot("panda")
    q_true = np.array([0.3, -0.5, 0.2, -2.0, 0.1, 1.6, 0.7])
    problem = swarm_ik.IKProblem(robot, robot.fk(q_true))
    names = [s for s in SOLVERS if s in swarm_ik.solvers.names()]

    print(
        f"{'solver':14s} {'success':>7s} {'pos. err [m]':>12s} {'rot. err [rad]':>14s} "
        f"{'evals':>6s} {'time [ms]':>9s}"
    )
    curves = {}
    for name in names:
        res = swarm_ik.solve(problem, name, seed=0, max_evals=BUDGET, stop_on_success=False)
        print(
            f"{name:14s} {res.success!s:>7s} {res.position_error:12.2e} "
            f"{res.rotation_error:14.2e} {res.n_evals:6d} {res.time_s * 1e3:9.1f}"
        )
        h = np.asarray(res.history)
        if h.size:
            curves[name] = (np.arange(1, h.size + 1) * res.n_evals / h.size, h)
    try:
        import matplotlib
    except ImportError:
        print("\nplot skipped: matplotlib is not installed (pip install 'swarm_ik[plot]')")
        return
    if QUICK or not os.environ.get("DISPLAY"):
        matplotlib.use("Agg")  # headless: draw into the file only
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for name, (evals, h) in curves.items():
        ax.semilogy(evals, np.maximum(h, 1e-16), label=name)
    ax.set_xscale("log")
    ax.set_xlabel("fitness evaluations")
    ax.set_ylabel("best fitness  |Δp| + θ  (m + rad)")
    ax.set_title(f"Panda, one pose, budget {BUDGET} evaluations, seed 0")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    if out is None:
        out = Path(tempfile.mkdtemp(prefix="swarm_ik_04_")) / "convergence.png"
    fig.savefig(out, dpi=110)
    print(f"\nconvergence plot: {out}")
    if not QUICK and os.environ.get("DISPLAY"):
        plt.show()


if __name__ == "__main__":
    main()
