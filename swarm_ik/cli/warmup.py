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
        "the compiled search, the solvers' loops with secondary goals, the batch, collision "
        "goals (solve and batch) and the branch search — so that no later command waits for "
        "a compile.  The kernels do not depend on the robot: one warm-up serves every robot "
        "(the collision step fits and caches the spheres of this robot's links, or of "
        "Panda's when it has no collision geometry).  Prints one line per step.",
    )
    p.add_argument(
        "--robot",
        default="yumi_left",
        help="robot to warm up with (default: the bundled yumi_left; any robot will do)",
    )
    p.add_argument(
        "--fresh",
        action="store_true",
        help="remove swarm_ik's numba cache files first and compile every kernel anew (the "
        "remedy for a cache file damaged so that loading it aborts the process)",
    )
    return p  # type: ignore[no-any-return]


def run(args: argparse.Namespace) -> int:
    """Run one small solve of each kind (after ``--fresh``'s removal of the cache files);
    returns 0."""
    if args.fresh:  # (before any kernel is loaded from the files)
        from swarm_ik import kernels

        removed = kernels.clear_cache()
        print(f"removed {len(removed)} numba cache file(s)", file=sys.stderr, flush=True)
    import numpy as np

    import swarm_ik
    from swarm_ik import goals
    from swarm_ik.errors import RobotModelError
    from swarm_ik.scene import Box, Scene

    robot = swarm_ik.load_robot(args.robot)
    q = robot.mid_q()
    target = robot.fk(q)
    # the collision kernels on a robot with collision geometry (this one's, else Panda's: its
    # link spheres are fitted and cached too), against a box out of its reach
    body = robot
    try:
        body.collision_model()
    except RobotModelError:  # (no <collision> elements, meshes not found)
        body = swarm_ik.load_robot("panda")
    away = ((1.0, 0.0, 0.0, 5.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 0.0, 1.0))
    avoid = goals.AvoidCollisions(Scene([Box((0.1, 0.1, 0.1), away)]))
    body_target = body.fk(body.mid_q())
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
            "collision goal (solve, batch)",
            lambda: (
                swarm_ik.solve(
                    swarm_ik.IKProblem(body, goals=[goals.Pose(body.ee_frame, body_target), avoid])
                ),
                swarm_ik.solve_batch(body, np.stack([body_target] * 2), goals=[avoid]),
            ),
        ),
        ("every built-in goal's kernel", lambda: _goal_kernels(robot, target)),
        ("a goal written in Python", lambda: _python_goal(robot, target)),
        ("floating base and balance", lambda: _whole_body(args.robot)),
        ("jump-free path (solve_path)", lambda: _paths(robot, q, target)),
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


def _goal_kernels(robot: Any, target: Any) -> None:
    """Compile (or load) the kernel of every registered compiled goal type, and of the
    bounded form of a pose (the other kernel a goal of the package names per instance), and
    the judge's compiled rotation angle (an ``Orientation`` goal's errors)."""
    from swarm_ik import goals
    from swarm_ik.kernels import lie

    lie.angle_between(target, target)

    for cls in goals.GOALS.values():
        if cls.kernel is not None:
            goals.kernel_slot(cls.kernel)
    bounded = goals.Pose(robot.ee_frame, target, tolerance=(0.01, 0.01, 0.01, 0.1, 0.1, 0.1))
    goals.kernel_slot(bounded.kernel_of())
    goals.kernels()


def _python_goal(robot: Any, target: Any) -> None:
    """One solve of a pose beside a goal written in Python (docs/goals.md): the numpy
    polish's compiled helpers (the compiled goals' rows and errors at a batch of points).
    The secondary goals' step compiles them too (this step then takes 0.1 s); it is here so
    that a goal written in Python stays covered whatever the other steps run."""
    from dataclasses import dataclass

    import numpy as np

    import swarm_ik
    from swarm_ik import goals

    @dataclass(frozen=True)
    class Height(goals.Goal):
        """The frame origin at a height [m] (the plane goal of docs/goals.md, shorter)."""

        frame: str
        height: float

        def residual(self, state: Any) -> Any:
            return np.array([state.pose(self.frame)[2, 3] - self.height])

        def jacobian(self, state: Any) -> Any:
            return state.jacobian(self.frame)[2:3]

    height = Height(robot.ee_frame, float(target[2, 3]))
    problem = swarm_ik.IKProblem(robot, goals=[goals.Pose(robot.ee_frame, target), height])
    start = np.clip(robot.mid_q() + 0.3, robot.lower, robot.upper)  # (not at the answer)
    swarm_ik.solve(problem, max_evals=50, q0=start)


def _whole_body(name: str) -> None:
    """One solve of the robot on a floating base with a balance goal: the rotation vector's
    helpers and the support polygon's compiled distances (this robot's, else YuMi's arm's
    when its URDF gives no masses: the kernels are the same)."""
    import swarm_ik
    from swarm_ik import goals
    from swarm_ik.errors import RobotModelError

    robot = swarm_ik.load_robot(name, floating_base=True)
    try:
        robot.mass_frames()
    except RobotModelError:  # (a URDF without inertials: `warmup --robot FILE` stopped here)
        robot = swarm_ik.load_robot("yumi_left", floating_base=True)
    q = robot.mid_q()
    square = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
    balance = goals.CenterOfMass(support=square, margin=0.01)
    problem = swarm_ik.IKProblem(robot, goals=[goals.Pose(robot.ee_frame, robot.fk(q)), balance])
    swarm_ik.solve(problem, q0=q, max_evals=50)
    balance.infeasible(robot, 1e-5, 1e-5)  # (the test a large budget runs first)
    robot.jacobian_pinocchio(q)  # (the free flyer's velocity as the rotation vector's rate)


def _paths(robot: Any, q: Any, target: Any) -> None:
    """A two-waypoint path of the robot, and of UR5 when eaik (extra ``analytic``) is installed:
    its candidates are the closed-form branches."""
    import importlib.util

    import swarm_ik

    swarm_ik.solve_path(robot, [target, target], q0=q)
    if importlib.util.find_spec("eaik") is not None:
        ur5 = swarm_ik.load_robot("ur5")
        pose = ur5.fk(ur5.mid_q())
        swarm_ik.solve_path(ur5, [pose, pose])
