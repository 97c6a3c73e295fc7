"""``swarm-ik bench goals``: goal sets that a single-pose IK cannot state.

Experiments (targets are FK of joint vectors drawn uniformly within the limits, so every goal
set is reachable; success = every primary goal within 1e-5 m / 1e-5 rad by our Pinocchio
check and the joints within limits):

* ``two-arm``: Baxter, a Pose goal on each gripper (14 joints), ours (``swarm``) against pink
  (``pin-pink``: one FrameTask per gripper, the QP iterated to convergence from the same
  mid-range seed), both at the same time budget, in a seeded random order per target, each
  call timed whole and judged by the same check, each one's own claim kept beside it;
* ``axis``: Position + Axis (tool z along the sampled tool z, yaw free) on Panda, UR5, xarm7;
* ``look-at``: Position + LookAt (tool z pointing at a point 0.5 m ahead) on the same arms;
* ``posture``: Panda pose targets with and without a secondary Posture goal at
  ``q_ref = q_true + N(0, 0.4 rad)`` (clipped): the median joint distance to ``q_ref`` of the
  answers, and their primary success.

Rows go to ``goals.csv`` (one per solve), the report ``summary.md`` is built from the CSV.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

import swarm_ik
from swarm_ik import argtypes
from swarm_ik import goals as G
from swarm_ik.argtypes import count, positive_number
from swarm_ik.bench import common

HELP = "goal sets: two-arm Baxter (vs pink), axis and look-at goals, the effect of a posture goal"
FIELDS = (
    "experiment", "robot", "solver", "index", "success", "claimed", "position_error",
    "rotation_error", "time_ms", "q_ref_distance",
)  # fmt: skip
ARMS = ("panda", "ur5", "xarm7")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``swarm-ik bench goals``."""
    parser.add_argument("--n", type=count(1), default=500, help="targets per experiment and robot")
    parser.add_argument(
        "--budget-ms", type=positive_number, default=20.0, help="time budget per solve [ms]"
    )
    argtypes.add_seed(parser, "seed of the targets")
    parser.add_argument("--quick", action="store_true", help="N = 30 (a smoke run)")
    parser.add_argument("--no-pink", action="store_true", help="skip the pink peer")
    common.add_out(parser, "goals")


def _row(exp: str, robot: str, solver: str, i: int, ok: bool, dp: float, dr: float, ms: float,
         dist: float = float("nan"), claimed: bool | None = None) -> dict[str, Any]:  # fmt: skip
    return dict(
        experiment=exp, robot=robot, solver=solver, index=i, success=int(ok),
        claimed=int(ok if claimed is None else claimed), position_error=dp,
        rotation_error=dr, time_ms=ms, q_ref_distance=dist,
    )  # fmt: skip


def _ours(problem: swarm_ik.IKProblem, budget: float, seed: int) -> tuple[Any, float]:
    t0 = time.perf_counter()
    res = swarm_ik.solve(problem, seed=seed, time_limit=budget)
    return res, 1e3 * (time.perf_counter() - t0)


def two_arm(n: int, budget: float, seed: int, pink: bool) -> list[dict[str, Any]]:
    """Baxter, both grippers to FK-sampled poses: ours and pink on the same targets, in a
    seeded random order per target, each call timed whole (ours: the two Pose goals and the
    ``IKProblem`` made, then solved; pink: its configuration and frame tasks made, then
    iterated) and each answer judged by the same Pinocchio check (every goal within the
    tolerances, the joints within the limits); each one's own claim is kept beside it."""
    robot = swarm_ik.load_robot("baxter")
    rng = np.random.default_rng(seed)
    qs = robot.random_q(rng, n)
    order_rng = np.random.default_rng([seed, 1])
    peer = None
    if pink:
        from swarm_ik.bench.peers import PinkIK

        peer = PinkIK(robot.model, list(robot.frames), budget, 1e-5,
                      to_pin=robot.to_pinocchio, from_pin=robot.from_pinocchio)  # fmt: skip
    rows = []
    for i, q in enumerate(qs):
        left, right = robot.fk_all(q)
        judge = swarm_ik.IKProblem(
            robot, goals=[G.Pose("left_gripper", left), G.Pose("right_gripper", right)]
        )

        def ours(i: int = i, left: Any = left, right: Any = right) -> tuple[Any, bool]:
            prob = swarm_ik.IKProblem(
                robot, goals=[G.Pose("left_gripper", left), G.Pose("right_gripper", right)]
            )
            res = swarm_ik.solve(prob, seed=i, time_limit=budget)
            return res.q, res.success

        def theirs(left: Any = left, right: Any = right) -> tuple[Any, bool]:
            assert peer is not None
            qp, claim, _own, _steps = peer.solve_frames([left, right], robot.mid_q())
            return qp, bool(claim)

        calls = [("swarm", ours)] + ([("pink", theirs)] if peer is not None else [])
        for k in order_rng.permutation(len(calls)):
            name, call = calls[k]
            t0 = time.perf_counter()
            qa, claim = call()
            ms = 1e3 * (time.perf_counter() - t0)
            errs = judge.verify(qa)
            # (the limits with 1e-9 of slack for both: pink's integration may end 1e-12 out)
            ok = all(e.met for e in errs) and judge.within_bounds(qa, 1e-9)
            rows.append(_row("two-arm", "baxter", name, i, ok,
                             max(e.position_error for e in errs),
                             max(e.rotation_error for e in errs), ms, claimed=claim))  # fmt: skip
    return rows


def frame_goal_set(kind: str, n: int, budget: float, seed: int) -> list[dict[str, Any]]:
    """Position + Axis, or Position + LookAt, on 6–7 joint arms."""
    rows = []
    for name in ARMS:
        robot = swarm_ik.load_robot(name)
        rng = np.random.default_rng(seed)
        f = robot.ee_frame
        for i, q in enumerate(robot.random_q(rng, n)):
            pose = robot.fk(q)
            if kind == "axis":
                second: G.Goal = G.Axis(f, [0, 0, 1], pose[:3, 2])
            else:
                second = G.LookAt(f, [0, 0, 1], pose[:3, 3] + 0.5 * pose[:3, 2])
            prob = swarm_ik.IKProblem(robot, goals=[G.Position(f, pose[:3, 3]), second])
            res, ms = _ours(prob, budget, i)
            rows.append(_row(kind, name, "swarm", i, res.success, res.position_error,
                             res.rotation_error, ms))  # fmt: skip
    return rows


def posture(n: int, budget: float, seed: int) -> list[dict[str, Any]]:
    """Panda pose targets with and without a secondary Posture goal."""
    robot = swarm_ik.load_robot("panda")
    rng = np.random.default_rng(seed)
    rows = []
    for i in range(n):
        q = robot.random_q(rng)
        q_ref = np.clip(q + rng.normal(0.0, 0.4, robot.nq), robot.lower, robot.upper)
        target = robot.fk(q)
        for label, extra in (("without", []), ("with", [G.Posture(q_ref)])):
            prob = swarm_ik.IKProblem(robot, target, goals=extra)
            res, ms = _ours(prob, budget, i)
            dist = float(np.linalg.norm(res.q - q_ref))
            rows.append(_row("posture", "panda", f"swarm {label} posture", i, res.success,
                             res.position_error, res.rotation_error, ms, dist))  # fmt: skip
    return rows


def report(rows: list[dict[str, str]]) -> str:
    """Markdown summary of ``goals.csv`` rows."""
    lines = [
        "# bench goals",
        "",
        "Success: every primary goal within 1e-5 m / 1e-5 rad (our Pinocchio check, the same "
        "for every solver) and within limits; claimed: the solver's own success flag (ours: "
        "its `Result.success`; pink: its convergence test). Times are the user-facing call of "
        "`swarm_ik.solve`; two-arm: each call timed whole (ours: the goals and the "
        "`IKProblem` made, then solved; pink: its configuration and frame tasks made, then "
        "iterated), the two in a seeded random order per target.",
        "",
        "| experiment | robot | solver | N | success % | claimed % | median ms | p95 ms | "
        "median distance to q_ref |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    groups: dict[tuple[str, str, str], list[dict[str, str]]] = {}
    for r in rows:
        groups.setdefault((r["experiment"], r["robot"], r["solver"]), []).append(r)
    for (exp, robot, solver), rs in groups.items():
        t = np.array([float(r["time_ms"]) for r in rs])
        ok = np.array([int(r["success"]) for r in rs])
        claimed = np.array([int(r.get("claimed") or r["success"]) for r in rs])
        d = np.array([float(r["q_ref_distance"]) for r in rs])
        dist = f"{np.nanmedian(d):.3f}" if np.isfinite(d).any() else ""
        lines.append(
            f"| {exp} | {robot} | {solver} | {len(rs)} | {100 * ok.mean():.1f} | "
            f"{100 * claimed.mean():.1f} | "
            f"{np.median(t):.3f} | {np.percentile(t, 95):.3f} | {dist} |"
        )
    post = groups.get(("posture", "panda", "swarm with posture"))
    base = groups.get(("posture", "panda", "swarm without posture"))
    if post and base:
        dw = np.median([float(r["q_ref_distance"]) for r in post])
        db = np.median([float(r["q_ref_distance"]) for r in base])
        lines += ["", f"Posture goal: median distance to q_ref {dw:.3f} rad against {db:.3f} "
                  f"rad without it ({100 * (1 - dw / db):.0f} % closer)."]  # fmt: skip
    return "\n".join(lines) + "\n"


def run(args: argparse.Namespace) -> int:
    """Run the experiments, write ``goals.csv`` and ``summary.md`` under ``--out``."""
    out = common.resolve_out(args.out, "goals", args.quick)
    n = 30 if args.quick else int(args.n)
    budget = float(args.budget_ms) / 1e3
    common.single_thread()
    rows = two_arm(n, budget, args.seed, pink=not args.no_pink)
    rows += frame_goal_set("axis", n, budget, args.seed)
    rows += frame_goal_set("look-at", n, budget, args.seed)
    rows += posture(n, budget, args.seed)
    common.write_csv(out / "goals.csv", FIELDS, rows)
    common.write_run_info(
        out, "goals", args.quick, n=n, budget_ms=args.budget_ms,
        machine=common.machine_info(("pin-pink",)),
    )  # fmt: skip
    return common.write_report(out / "summary.md", report(common.read_csv(out / "goals.csv")))


main = common.module_main(add_arguments, run, "goals", HELP)


if __name__ == "__main__":
    raise SystemExit(main())
