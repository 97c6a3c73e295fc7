"""A humanoid standing on both feet: Talos's hands to two poses, its centre of mass kept over
its feet.

``load_robot(..., floating_base=True)`` roots Talos on a free flyer (six entries at the head of
``q``: the pelvis position, then its rotation vector) and ``locked=`` holds the two torso
joints at 0.  Both soles are held flat at their half-sitting poses on the ground
(:class:`swarm_ik.goals.Pose`), both hands go 30 cm forward and 10 cm down from half-sitting
(a box held in front), and :class:`swarm_ik.goals.CenterOfMass` keeps the centre of mass at
least 3 cm inside the support polygon (the convex hull of the two soles).  Solved once without
the balance goal (the robot would fall: its centre of mass ends far in front of its toes) and
once with it; each answer is checked with Pinocchio alone on the whole URDF
(``robot.full_configuration``).  The balanced answer is drawn in meshcat with the unbalanced
one ghosted, the support polygon and the centres of mass (``--html FILE`` writes a
self-contained page instead of serving it; needs ``pip install swarm_ik[viz]``; without the
extra the viewer is skipped with a note).

Run: ``python examples/09_humanoid.py [--html FILE]``.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
import pinocchio as pin

import swarm_ik
from swarm_ik.bench.wholebody_peers import polygon_margin, reference_configuration, support_polygon
from swarm_ik.goals import CenterOfMass, Pose
from swarm_ik.viz import output_file

QUICK = os.environ.get("SWARM_IK_QUICK") == "1"
FRAMES = ["left_sole_link", "right_sole_link", "gripper_left_base_link", "gripper_right_base_link"]
REACH = np.array([0.30, 0.0, -0.10])
"""Where the hands go from their half-sitting positions [m] (orientations kept)."""
MARGIN = 0.03
"""The centre of mass at least this far inside the support polygon [m]."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--html", type=output_file(".html"), help="write the scene to FILE")
    args = parser.parse_args()
    # the pelvis stands 1.02 m high in half-sitting: a base box taller than the default 1 m
    robot = swarm_ik.load_robot(
        "talos", FRAMES, floating_base=True,
        locked={"torso_1_joint": 0.0, "torso_2_joint": 0.0}, base_box=(1.0, 1.0, 1.5),
    )  # fmt: skip
    held = ", ".join(f"{k} = {v:g}" for k, v in robot.held.items())
    print(f"{robot.name}: q holds {robot.nq} entries, the floating base's 6 (x y z [m], "
          f"rotation vector [rad]) then {robot.nq - 6} joints; locked: {held}")  # fmt: skip
    # half-sitting (example-robot-data's SRDF state), both soles flat on the ground z = 0
    q_ref = robot.from_full_configuration(reference_configuration(robot.full_model))
    poses = robot.fk_all(q_ref)
    polygon = support_polygon(poses[0], poses[1])
    balance = CenterOfMass(support=polygon, margin=MARGIN)
    c_ref = balance.center(robot, q_ref)
    print(f"half-sitting: pelvis at z = {q_ref[2]:.3f} m, centre of mass "
          f"{np.round(c_ref, 3).tolist()}, {polygon_margin(c_ref, polygon):.3f} m inside the "
          f"support polygon ({len(polygon)} vertices)")  # fmt: skip
    hands = poses[2:].copy()
    hands[:, :3, 3] += REACH
    goals = [Pose(f, poses[i]) for i, f in enumerate(FRAMES[:2])]  # the feet stay
    goals += [Pose(f, hands[i]) for i, f in enumerate(FRAMES[2:])]
    budget = 0.2 if QUICK else 1.0
    print(f"hands {100 * REACH[0]:.0f} cm forward, {-100 * REACH[2]:.0f} cm down:")
    answers = []
    for label, extra in [("without CenterOfMass", []), ("with CenterOfMass", [balance])]:
        problem = swarm_ik.IKProblem(robot, goals=[*goals, *extra])
        result = swarm_ik.solve(problem, seed=0, time_limit=budget, q0=q_ref)
        answers.append(result.q)
        margin = polygon_margin(balance.center(robot, result.q), polygon)
        state = "inside" if margin >= 0 else "outside: it would fall"
        print(f"  {label}: success={result.success} ({result.reason}) in "
              f"{1e3 * result.time_s:.2f} ms; centre of mass {margin:+.3f} m from the "
              f"polygon's edge ({state})")  # fmt: skip
        for e in result.goal_errors:
            if np.isfinite(e.rotation_error):
                print(f"    {e.goal}: {e.position_error:.1e} m, {e.rotation_error:.1e} rad")
            else:
                print(f"    {e.goal}: residual {e.position_error:.1e} m")
    q_fall, q = answers
    check_with_pinocchio(robot, q, poses, hands, polygon)
    draw(robot, q, q_fall, hands, polygon, balance, args.html)


def check_with_pinocchio(
    robot: swarm_ik.RobotModel, q: np.ndarray, poses: np.ndarray, hands: np.ndarray,
    polygon: np.ndarray,
) -> None:  # fmt: skip
    """The answer judged with nothing but Pinocchio on the whole URDF (free flyer
    ``[x y z qx qy qz qw, joints…]``, every joint of the file)."""
    model = robot.full_model
    data = model.createData()
    qf = robot.full_configuration(q)
    pin.framesForwardKinematics(model, data, qf)
    worst = 0.0
    for frame, target in zip(FRAMES, [poses[0], poses[1], *hands], strict=True):
        m = data.oMf[model.getFrameId(frame)]
        err = pin.log6(pin.SE3(target).actInv(m)).vector
        worst = max(worst, float(np.abs(err).max()))
    com = np.array(pin.centerOfMass(model, data, qf))
    torso = [float(qf[model.idx_qs[model.getJointId(n)]]) for n in robot.held]
    print(f"checked with Pinocchio alone (whole URDF, nq = {model.nq}): largest frame error "
          f"{worst:.1e}, centre of mass {polygon_margin(com, polygon):.3f} m inside, torso "
          f"{torso}")  # fmt: skip


def draw(
    robot: swarm_ik.RobotModel, q: np.ndarray, q_fall: np.ndarray, hands: np.ndarray,
    polygon: np.ndarray, balance: CenterOfMass, html: Path | None,
) -> None:  # fmt: skip
    """The balanced answer, the unbalanced one ghosted, the hands' targets, the support
    polygon and both centres of mass (a ball, and its shadow on the ground), seen from the
    robot's right: served live, or written to ``html``."""
    from swarm_ik import viz

    if not viz.viewer_for(html):  # (no meshcat: skipped, or exit 2 when a page was asked for)
        return
    scene = viz.Scene()
    scene.add_robot(robot, q, name="robot")
    scene.add_robot(robot, q_fall, name="ghost", color=viz.GHOST_COLOR)
    for k, target in enumerate(hands):
        scene.add_triad(f"target_{k}", target, length=0.12, sphere=(1.0, 0.85, 0.1, 0.45))
    scene.add_polygon("support", polygon, z=0.002)
    for name, qq, rgba in [("com", q, (0.1, 0.6, 0.1, 1.0)), ("com_ghost", q_fall, (1, 0.5, 0, 1))]:
        c = balance.center(robot, qq)
        scene.add_point(name, c, radius=0.03, rgba=rgba)
        scene.add_point(f"{name}_ground", [c[0], c[1], 0.0], radius=0.025, rgba=rgba)
    view = np.array([0.15, -1.0, 0.1])
    lines = [
        "Talos: feet fixed, hands to targets",
        "solid: with CenterOfMass (balanced)",
        "ghost: without; the orange ball is its",
        "centre of mass, outside the feet",
    ]
    scene.add_label("label", lines, position=[0.1, 0.0, 1.95], height=0.3, facing=view)
    scene.frame_camera([[-0.4, -0.5, 0.0], [0.6, 0.5, 2.15]], direction=view, distance=2.6)
    print(scene.publish(html, "talos.html", quick=QUICK))


if __name__ == "__main__":
    main()
