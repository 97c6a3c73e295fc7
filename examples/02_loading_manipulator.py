"""The mobile loading manipulator of the MGWO paper: 8 joints, three of them prismatic.

Joint values are ``[θ1, θ2, θ3, d4, d5, d6, θ7, θ8]`` (rad, rad, rad, m, m, m, rad, rad); d4,
d5 and d6 telescope along one line, so only their sum matters.  Two targets:

* a reachable one (the FK of a joint vector within the limits): solved exactly by ``swarm``;
  the paper's MGWO, run beside it on the same budget, ends millimetres off (a population
  optimiser reaches the 1e-5 tolerance slowly: README, "The papers' tables");
* the paper's own target, the FK of its ``x* = (45°, 30°, 45°, 0.8, 1.0, 1.0 m, 30°, −45°)``,
  which violates the paper's limits (θ3 ≤ 35.45°, d ≤ 0.5 m): no joint vector within the
  limits reaches it, so the solver reports ``success=False`` with the best pose it found.  The
  long-stroke variant (``loading_manipulator_long``, d up to 1.5 m, the same angle limits)
  reaches it.

Run: ``python examples/02_loading_manipulator.py`` (``SWARM_IK_QUICK=1``: smaller budgets).
"""

from __future__ import annotations

import os

import numpy as np

import swarm_ik

QUICK = os.environ.get("SWARM_IK_QUICK") == "1"
BUDGET = 20_000 if QUICK else 200_000
X_STAR = np.array([np.pi / 4, np.pi / 6, np.pi / 4, 0.8, 1.0, 1.0, np.pi / 6, -np.pi / 4])


def report(label: str, res: swarm_ik.Result) -> None:
    print(
        f"{label}: success={res.success}  position error {res.position_error:.3e} m  "
        f"rotation error {res.rotation_error:.3e} rad  within limits {res.within_limits}"
    )
    print("   q =", np.round(res.q, 4).tolist())


def main() -> None:
    robot = swarm_ik.load_robot("loading_manipulator")
    print(robot)
    for name, kind, lo, hi in zip(
        robot.joint_names, robot.joint_kinds, robot.lower, robot.upper, strict=True
    ):
        unit = "m" if kind == "prismatic" else "rad"
        print(f"  {name:8s} {kind:10s} [{lo: .3f}, {hi: .3f}] {unit}")

    q_ok = np.array([0.5, 0.3, -0.2, 0.1, 0.25, 0.4, 0.6, -1.0])
    reachable = swarm_ik.IKProblem(robot, robot.fk(q_ok))
    report("\nreachable target, swarm", swarm_ik.solve(reachable, seed=0))
    report("reachable target, mgwo ", swarm_ik.solve(reachable, "mgwo", seed=0, max_evals=BUDGET))

    paper_target = robot.fk(X_STAR)  # the FK itself ignores limits
    print("\npaper target position [m]:", np.round(paper_target[:3, 3], 3).tolist())
    res = swarm_ik.solve(swarm_ik.IKProblem(robot, paper_target), seed=0, max_evals=BUDGET)
    report("paper target, loading_manipulator (limits of the paper)", res)
    assert not res.success, "x* lies outside the limits: the target should be unreachable"

    long_robot = swarm_ik.load_robot("loading_manipulator_long")
    res_long = swarm_ik.solve(
        swarm_ik.IKProblem(long_robot, paper_target), seed=0, max_evals=BUDGET
    )
    report("paper target, loading_manipulator_long", res_long)


if __name__ == "__main__":
    main()
