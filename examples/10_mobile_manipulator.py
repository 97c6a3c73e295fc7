"""A mobile manipulator: TIAGo's tool to a pose 1.9 m away, out of its arm's reach, by driving
its base there.

TIAGo (``tiago_no_hand.urdf`` of example-robot-data, loaded by its name: a wheeled base, a
prismatic torso lift, a 7-joint arm) is loaded twice.  With its base fixed to the world (8
joints: the lift and the arm) the target is out of reach: the solve fails and returns the
closest pose it found.  With ``floating_base=True`` (six more entries at the head of ``q``:
the base position, then its rotation vector) and ``base_footprint`` as a second goal frame,
two goals keep the base on the floor (:class:`swarm_ik.goals.JointValue` holds its height
at 0, :class:`swarm_ik.goals.Axis` its z axis up; x and y stay free within the base box, the
heading free) and the solve succeeds, the base driven towards the target.  The torso lift
is left free (the solver may raise the arm).  The answer is drawn in meshcat with the
fixed-base attempt ghosted (``--html FILE`` writes a self-contained page instead of serving
it; needs ``pip install swarm_ik[viz]``; without the extra the viewer is skipped with a note).

Run: ``python examples/10_mobile_manipulator.py [--html FILE]``.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

import swarm_ik
from swarm_ik.goals import Axis, JointValue, Pose
from swarm_ik.viz import output_file

QUICK = os.environ.get("SWARM_IK_QUICK") == "1"
ROBOT = "tiago_no_hand"  # example-robot-data's tiago_description/robots/tiago_no_hand.urdf
TOOL, BASE = "arm_tool_link", "base_footprint"  # base_footprint: the root link, on the floor
BOX = 3.0
"""Half-width [m] of the square the base may drive in (``base_box``)."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--html", type=output_file(".html"), help="write the scene to FILE")
    args = parser.parse_args()
    # a shelf 1.8 m ahead, 0.6 m to the left, 0.75 m high; the tool's x axis (its approach
    # direction) pointing forward, level
    target = np.eye(4)
    target[:3, 3] = [1.8, 0.6, 0.75]
    budget = 0.05 if QUICK else 0.5

    arm = swarm_ik.load_robot(ROBOT, TOOL)
    print(f"fixed base: {arm.nq} joints {list(arm.joint_names)}")
    fixed = swarm_ik.solve(swarm_ik.IKProblem(arm, target), seed=0, time_limit=budget)
    print(f"  success={fixed.success} ({fixed.reason}) in {1e3 * fixed.time_s:.1f} ms: the "
          f"closest pose found is {fixed.position_error:.2f} m from the target")  # fmt: skip

    robot = swarm_ik.load_robot(ROBOT, [TOOL, BASE], floating_base=True, base_box=BOX)
    print(f"floating base: {robot.nq} entries in q, the base's 6 then the same {arm.nq} joints")
    on_floor = [JointValue("root_joint.z", 0.0), Axis(BASE, [0, 0, 1], [0, 0, 1])]
    problem = swarm_ik.IKProblem(robot, goals=[Pose(TOOL, target), *on_floor])
    result = swarm_ik.solve(problem, seed=0, time_limit=budget)
    print(f"  success={result.success} ({result.reason}) in {1e3 * result.time_s:.2f} ms")
    for e in result.goal_errors:
        print(f"    {e.goal}: {e.position_error:.1e} m, {e.rotation_error:.1e} rad")
    base = robot.fk(result.q, BASE)
    heading = np.degrees(np.arctan2(base[1, 0], base[0, 0]))
    print(f"  base driven to x = {base[0, 3]:.2f} m, y = {base[1, 3]:.2f} m (z = "
          f"{base[2, 3]:.1e} m, tilt {np.degrees(np.arccos(min(1.0, base[2, 2]))):.1e} deg), "
          f"heading {heading:.0f} deg; torso lift {result.q[6]:.3f} m")  # fmt: skip
    # the fixed-base attempt, as the mobile robot standing at the origin
    q_fixed = np.concatenate([np.zeros(6), fixed.q])
    draw(robot, result.q, q_fixed, target, args.html)


def draw(robot: swarm_ik.RobotModel, q: np.ndarray, q_fixed: np.ndarray, target: np.ndarray,
         html: Path | None) -> None:  # fmt: skip
    """The robot at ``q``, the fixed-base attempt ghosted, a triad at the target and one at
    the tool (:func:`swarm_ik.viz.show_pose`): served live, or written to ``html``."""
    from swarm_ik import viz

    if not viz.viewer_for(html):  # (no meshcat: skipped, or exit 2 when a page was asked for)
        return
    scene = viz.Scene()
    lines = ["TIAGo: the base drives, the arm reaches", "ghost: base fixed (out of reach)"]
    viz.show_pose(robot, q, target=target, ghost_q=q_fixed, lines=lines, scene=scene)
    print(scene.publish(html, "tiago.html", quick=QUICK))


if __name__ == "__main__":
    main()
