"""Partial goals: the Panda's tool pointing straight down over a grid of positions, yaw free.

A pick-and-place cell rarely cares about the rotation of a symmetric gripper about its own
axis.  Each grid point is a :class:`swarm_ik.goals.Position` plus an
:class:`swarm_ik.goals.Axis` (tool z along world −z); a secondary
:class:`swarm_ik.goals.Posture` keeps the arm near its "ready" posture: the solver meets the
two primary goals to 1e-5 and then moves in their null space towards the posture, never
trading primary accuracy for it.  The script compares the joint distance to the posture with
and without that goal.

Run: ``python examples/08_tool_axis.py``.
"""

from __future__ import annotations

import numpy as np

import swarm_ik
from swarm_ik.goals import Axis, Position, Posture

READY = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.785])  # rad: tool about 6° off vertical


def main() -> None:
    robot = swarm_ik.load_robot("panda")
    frame = robot.ee_frame
    down = Axis(frame, axis=[0, 0, 1], direction=[0, 0, -1])
    xs, ys = np.linspace(0.35, 0.6, 4), np.linspace(-0.25, 0.25, 4)
    ok = 0
    dist_with, dist_without = [], []
    for x in xs:
        for y in ys:
            at = Position(frame, [x, y, 0.25])
            plain = swarm_ik.solve(swarm_ik.IKProblem(robot, goals=[at, down]), time_limit=0.02)
            kept = swarm_ik.solve(
                swarm_ik.IKProblem(robot, goals=[at, down, Posture(READY)]), time_limit=0.02
            )
            ok += kept.success
            dist_without.append(np.linalg.norm(plain.q - READY))
            dist_with.append(np.linalg.norm(kept.q - READY))
            z_axis = robot.fk_pinocchio(kept.q)[:3, 2]
            assert not kept.success or z_axis[2] < -0.9999
    n = xs.size * ys.size
    print(f"{ok}/{n} grid points reached with the tool pointing down (yaw free)")
    print(
        f"median joint distance to the ready posture: {np.median(dist_with):.3f} rad with the "
        f"Posture goal, {np.median(dist_without):.3f} rad without"
    )


if __name__ == "__main__":
    main()
