"""Follow a straight line and a circle with YuMi's left arm, seeding each IK with the last.

Each waypoint is solved with the default ``swarm`` solver from the previous joint vector with
``prefer="nearest"``, so that the joint path stays smooth (no jumps between IK branches or
along the arm's self-motion).  The script prints, for each path, the success count, the
step from the start configuration to the first waypoint's answer, the largest joint step
between consecutive waypoints and the time per waypoint for three ways:

* ``nearest``: seeded with the previous solution, keep the solution nearest to it;
* ``best, seeded``: the same seed with the plain ``prefer="best"``; on a path this fine the
  seed itself converges, so the steps nearly equal ``nearest``'s (they differ when the seed fails
  and restarts find other branches);
* ``best, no seed``: every waypoint solved afresh, each search starting at the middle of the
  joint ranges: it returns whichever of the arm's many solutions it finds first.  On these
  short paths that is the same branch all along (small steps), but not the start's: the
  first step, from the start configuration, is large.  Nothing ties it to one branch: on a
  longer path it may change branch anywhere (``swarm_ik.solve_path`` searches the branches
  for a path with no jump).

Run: ``python examples/05_cartesian_path.py`` (``SWARM_IK_QUICK=1`` uses fewer waypoints).
"""

from __future__ import annotations

import os
import time

import numpy as np

import swarm_ik

QUICK = os.environ.get("SWARM_IK_QUICK") == "1"
N_POINTS = 25 if QUICK else 200


def line_path(start: np.ndarray, direction: np.ndarray, length: float, n: int) -> np.ndarray:
    """Poses ``(n, 4, 4)`` along a straight line from ``start`` (4x4), orientation fixed."""
    d = direction / np.linalg.norm(direction)
    poses = np.repeat(start[None], n, axis=0)
    poses[:, :3, 3] += np.linspace(0.0, length, n)[:, None] * d
    return poses


def circle_path(start: np.ndarray, radius: float, n: int) -> np.ndarray:
    """Poses ``(n, 4, 4)`` on a circle through ``start`` in the world x–y plane, orientation
    fixed; one full turn."""
    s = np.linspace(0.0, 2.0 * np.pi, n)
    poses = np.repeat(start[None], n, axis=0)
    centre = start[:3, 3] - np.array([radius, 0.0, 0.0])
    poses[:, 0, 3] = centre[0] + radius * np.cos(s)
    poses[:, 1, 3] = centre[1] + radius * np.sin(s)
    return poses


def follow(
    robot: swarm_ik.RobotModel, poses: np.ndarray, q_start: np.ndarray, prefer: str, seeded: bool
) -> tuple[np.ndarray, int, float]:
    """Solve every pose, seeded by the previous solution when ``seeded``.

    Returns:
        ``(joint path (n, nq), successes, mean seconds per waypoint)``.
    """
    q = q_start.copy()
    path = []
    ok = 0
    t0 = time.perf_counter()
    for i, pose in enumerate(poses):
        res = swarm_ik.solve(
            swarm_ik.IKProblem(robot, pose),
            q0=q if seeded else None,
            prefer=prefer,
            seed=i,
            time_limit=0.02,
        )
        ok += res.success
        q = res.q
        path.append(q)
    return np.asarray(path), ok, (time.perf_counter() - t0) / len(poses)


def main() -> None:
    robot = swarm_ik.load_robot("yumi_left")
    q_start = np.array([0.1, -0.5, 0.2, 0.3, -0.2, 0.4, 0.1])
    start = robot.fk(q_start)
    paths = {
        "line 0.15 m": line_path(start, np.array([0.0, 1.0, 0.5]), 0.15, N_POINTS),
        "circle r = 0.05 m": circle_path(start, 0.05, N_POINTS),
    }
    # warm-up: loads the compiled kernels (numba cache) before anything is timed
    swarm_ik.solve(swarm_ik.IKProblem(robot, start), q0=q_start, prefer="nearest")
    print(f"YuMi left arm, {N_POINTS} waypoints per path, tolerance 1e-5 m / 1e-5 rad")
    for name, poses in paths.items():
        for label, prefer, seeded in (
            ("nearest", "nearest", True),
            ("best, seeded", "best", True),
            ("best, no seed", "best", False),
        ):
            path, ok, per = follow(robot, poses, q_start, prefer, seeded)
            first = np.abs(path[0] - q_start).max()
            steps = np.abs(np.diff(path, axis=0))
            print(
                f"  {name:18s} {label:14s} solved {ok}/{len(poses)}, "
                f"first step {np.degrees(first):6.2f} deg, "
                f"max step along {np.degrees(steps.max()):6.2f} deg, "
                f"{per * 1e3:.2f} ms per waypoint"
            )


if __name__ == "__main__":
    main()
