"""``swarm-ik warmup``: compile every kernel ahead (for images and CI), with a line per step."""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``warmup`` to the ``swarm-ik`` sub-parsers."""
    p = subparsers.add_parser(
        "warmup",
        help="compile the kernels now (a container image, a CI cache)",
        description="Compile (or load from numba's cache) the kernels of every solve path — "
        "the compiled search, the solvers' loops with secondary goals, the batch and the "
        "branch search — so that no later command waits for a compile.  The kernels do not "
        "depend on the robot: one warm-up serves every robot.  Prints one line per step.",
    )
    p.add_argument(
        "--robot",
        default="yumi_left",
        help="robot to warm up with (default: the bundled yumi_left; any robot will do)",
    )
    return p  # type: ignore[no-any-return]


def run(args: argparse.Namespace) -> int:
    """Run one small solve of each kind; returns 0."""
    import numpy as np

    import swarm_ik
    from swarm_ik import goals

    robot = swarm_ik.load_robot(args.robot)
    q = robot.mid_q()
    target = robot.fk(q)
    steps = [
        (
            "compiled search (solve, IKSolver)",
            lambda: swarm_ik.solve(swarm_ik.IKProblem(robot, target)),
        ),
        (
            "solver loops with a secondary goal",
            lambda: swarm_ik.solve(
                swarm_ik.IKProblem(
                    robot, goals=[goals.Pose(robot.ee_frame, target), goals.Posture(q)]
                ),
                max_evals=50,
            ),
        ),
        (
            "paper solvers (fitness)",
            lambda: swarm_ik.solve(swarm_ik.IKProblem(robot, target), "gwo", max_evals=40),
        ),
        ("batch", lambda: swarm_ik.solve_batch(robot, np.stack([target, target]))),
        (
            "branch search (solve_many)",
            lambda: swarm_ik.solve_many(
                swarm_ik.IKProblem(robot, target), n=2, method="numerical", max_evals=200
            ),
        ),
    ]
    t_all = time.perf_counter()
    for label, step in steps:
        t0 = time.perf_counter()
        step()
        print(f"{label}: {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
    print(f"kernels ready ({time.perf_counter() - t_all:.1f} s)")
    return 0
