"""Jump-free Cartesian paths: every IK branch considered, jumps found and proved.

Three paths with :func:`swarm_ik.path.solve_path` (``max_joint_step`` 0.2 rad):

1. a UR5 tool line of 27 cm: every waypoint's closed-form branches (eaik) and their 2π
   copies, then a dynamic programme through them: the joint path with no step beyond the
   bound and the least joint travel;
2. the same line with its second half moved elsewhere: the path must jump, and since every
   waypoint's set of solutions is complete the reason says that this proves no jump-free path
   exists (the jump's waypoint and size are given);
3. a Panda circle: 7 joints, a curve of solutions per pose, covered by samples tracked from
   waypoint to waypoint.

Run: ``python examples/11_jump_free_path.py`` (``SWARM_IK_QUICK=1``: fewer waypoints).
"""

from __future__ import annotations

import os

import numpy as np

import swarm_ik
from swarm_ik.path import solve_path

QUICK = os.environ.get("SWARM_IK_QUICK") == "1"
N = 16 if QUICK else 40


def line(start: np.ndarray, shift: np.ndarray, n: int) -> np.ndarray:
    """Poses ``(n, 4, 4)`` from ``start`` along ``shift`` [m], orientation fixed."""
    poses = np.repeat(start[None], n, axis=0)
    poses[:, :3, 3] += np.linspace(0.0, 1.0, n)[:, None] * shift
    return poses


def circle(start: np.ndarray, radius: float, n: int) -> np.ndarray:
    """Poses ``(n, 4, 4)`` on a horizontal circle through ``start``, orientation fixed."""
    s = np.linspace(0.0, 2.0 * np.pi, n)
    poses = np.repeat(start[None], n, axis=0)
    poses[:, 0, 3] += radius * (np.cos(s) - 1.0)
    poses[:, 1, 3] += radius * np.sin(s)
    return poses


def report(label: str, res: swarm_ik.path.PathResult) -> None:
    print(f"{label}: {res.q.shape[0]} waypoints, {res.time_s * 1e3:.0f} ms")
    print(f"  success={res.success} jump_free={res.jump_free} max step {res.max_step:.3f} rad")
    print(f"  {res.reason}")


def main() -> None:
    ur5 = swarm_ik.load_robot("ur5")
    start = ur5.fk(np.array([0.3, -1.2, 1.4, -1.8, -1.57, 0.0]))
    poses = line(start, np.array([-0.1, 0.25, 0.05]), N)
    report("UR5 line", solve_path(ur5, poses))

    jumpy = poses.copy()
    jumpy[N // 2 :] = line(ur5.fk(np.array([-1.2, -1.9, 1.2, -0.5, 1.0, 0.4])), np.zeros(3), N)[
        N // 2 :
    ]
    res = solve_path(ur5, jumpy)
    report("UR5 line, second half elsewhere", res)
    for index, size in res.reconfigurations:
        print(f"  jump into waypoint {index}: {size:.2f} rad")

    panda = swarm_ik.load_robot("panda")
    ready = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785])
    res = solve_path(panda, circle(panda.fk(ready), 0.1, N), q0=ready)
    report("Panda circle r = 10 cm from the ready posture", res)


if __name__ == "__main__":
    main()
