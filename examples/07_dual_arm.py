"""Two arms at once: Baxter's grippers to two poses, one solve over both arms' 14 joints.

``load_robot("baxter")`` keeps both arms (its goal frames are ``left_gripper`` and
``right_gripper``; the model is the union of the two root → gripper paths, a tree); each goal
is a :class:`swarm_ik.goals.Pose`.  The targets are the FK of a random configuration, so an
answer exists; ``Result.goal_errors`` gives each gripper's errors checked with Pinocchio.
The answer is drawn in meshcat with a triad at each target (``--html FILE`` writes a
self-contained page instead of serving it; needs ``pip install swarm_ik[viz]``; without the
extra the viewer is skipped with a note).

Run: ``python examples/07_dual_arm.py [--html FILE]``.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

import swarm_ik
from swarm_ik.goals import Pose
from swarm_ik.viz import output_file

QUICK = os.environ.get("SWARM_IK_QUICK") == "1"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--html", type=output_file(".html"), help="write the scene to FILE")
    args = parser.parse_args()
    robot = swarm_ik.load_robot("baxter")
    print(f"{robot.name}: {robot.nq} joints, goal frames {robot.frames}")
    rng = np.random.default_rng(3)
    for k in range(3):
        left, right = robot.fk_all(robot.random_q(rng))
        problem = swarm_ik.IKProblem(
            robot, goals=[Pose("left_gripper", left), Pose("right_gripper", right)]
        )
        result = swarm_ik.solve(problem, seed=k, time_limit=0.02)
        ms = 1e3 * result.time_s
        print(f"target {k}: success={result.success} ({result.reason}) in {ms:.2f} ms")
        for e in result.goal_errors:
            print(f"  {e.goal}: {e.position_error:.1e} m, {e.rotation_error:.1e} rad")
    draw(robot, result.q, [left, right], args.html)


def draw(robot: swarm_ik.RobotModel, q: np.ndarray, targets: list[np.ndarray],
         html: Path | None) -> None:  # fmt: skip
    """The robot at ``q`` with a triad at each target: served live, or written to ``html``."""
    from swarm_ik import viz

    if not viz.viewer_for(html):  # (no meshcat: skipped, or exit 2 when a page was asked for)
        return
    scene = viz.show_pose(robot, q, target=targets[0], lines=["Baxter: both grippers"])
    scene.add_triad("target_right", targets[1], length=0.15)
    print(scene.publish(html, "baxter.html", quick=QUICK))


if __name__ == "__main__":
    main()
