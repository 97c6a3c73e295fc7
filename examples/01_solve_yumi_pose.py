"""Solve one pose of the ABB YuMi left arm (7 joints) — start here.

The target is the forward kinematics of a joint vector, so it is reachable; the default solver
(``swarm``: grey-wolf proposals + a compiled Levenberg–Marquardt polish) finds an exact answer
in milliseconds, and ``hlfoa`` (the HLFOA paper's fruit-fly optimiser) is run for comparison.
The errors of every answer are recomputed with Pinocchio's own forward kinematics.

Run: ``python examples/01_solve_yumi_pose.py`` (``SWARM_IK_QUICK=1`` gives HLFOA a smaller
budget).
"""

from __future__ import annotations

import os

import numpy as np

import swarm_ik

QUICK = os.environ.get("SWARM_IK_QUICK") == "1"


def main() -> None:
    robot = swarm_ik.load_robot("yumi_left")
    print(robot)
    print(
        "joints:",
        ", ".join(
            f"{n} [{lo:.2f}, {hi:.2f}] rad"
            for n, lo, hi in zip(robot.joint_names, robot.lower, robot.upper, strict=True)
        ),
    )

    q_true = np.array([0.3, -0.8, 0.4, 0.6, -0.5, 1.2, 0.7])  # rad
    target = robot.fk(q_true)  # 4x4 pose in metres
    print("target position [m]:", np.round(target[:3, 3], 4).tolist())

    problem = swarm_ik.IKProblem(robot, target)  # fitness "se3": |dp| + theta
    for solver, budget in (("swarm", None), ("hlfoa", 5_000 if QUICK else 50_000)):
        res = swarm_ik.solve(problem, solver, seed=0, max_evals=budget)
        print(
            f"\n{solver}: success={res.success}  position error {res.position_error:.2e} m  "
            f"rotation error {res.rotation_error:.2e} rad  {res.n_evals} evaluations  "
            f"{res.time_s * 1e3:.1f} ms"
        )
        print("  q =", np.round(res.q, 4).tolist())
    # a redundant arm has many answers: the one found need not be q_true, only reach the pose
    assert swarm_ik.solve(problem, seed=0).success


if __name__ == "__main__":
    main()
