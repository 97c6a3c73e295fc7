"""``swarm-ik bench many``: every IK branch, numerical and analytic, against eaik's sets.

For each arm (UR5, UR10, z1) ``N`` targets are the FK of uniform random joint vectors.  The
reference set of a target is eaik's solutions (exact ones only) that have an in-limit 2π copy,
verified with Pinocchio (:func:`swarm_ik.solvers.analytic.solve_all`); the generating
configuration must be in it.  Per target and path: recall (reference branches found, modulo
2π within 1e-6 rad), extras (returned solutions in no reference branch), duplicates (pairs
of returned solutions in one branch), wall time of the call, time to the k-th branch and to
the complete set.  For the 7-joint panda: the covering radius of ``solve_many(n=16)`` over a
dense pool of solutions (``n=256``), against 16 solutions taken in the order found.

Writes ``many.csv``, ``spread.csv``, ``many.md`` and ``run.json`` into ``--out`` (checked, with
the arms, before anything is written: :func:`check_arms`).
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path
from typing import Any, cast

import numpy as np

from swarm_ik import argtypes
from swarm_ik.argtypes import count
from swarm_ik.bench import common

ARMS = ("ur5", "ur10", "z1")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``swarm-ik bench many``."""
    parser.add_argument(
        "--n-targets", type=count(1), default=50, help="targets per arm (default 50)"
    )
    parser.add_argument("--n", type=count(1), default=16, help="solve_many's n (default 16)")
    argtypes.add_seed(parser, "seed of the targets")
    parser.add_argument(
        "--arms",
        nargs="+",
        default=list(ARMS),
        help=f"6-joint arms that eaik solves, to measure (default {' '.join(ARMS)})",
    )
    parser.add_argument(  # (no --quick here: common.add_out's help would name one)
        "--out",
        type=Path,
        default=None,
        help=f"output folder (default ./{common.default_out('many', False)})",
    )


def _match(qs: np.ndarray, ref: np.ndarray, periodic: np.ndarray, tol: float = 1e-6) -> Any:
    from swarm_ik.branches import branch_distance

    if qs.shape[0] == 0 or ref.shape[0] == 0:
        return np.zeros((qs.shape[0], ref.shape[0]), dtype=bool)
    return branch_distance(qs[:, None, :], ref[None, :, :], periodic) < tol


def _best_of(fn: Any, reps: int) -> tuple[Any, float]:
    """The result of the fastest of ``reps`` calls of ``fn()`` and its wall time [s] (the
    calls do the same work: same seed)."""
    best = float("inf")
    out = None
    for _ in range(reps):
        t0 = time.perf_counter()
        res = fn()
        dt = time.perf_counter() - t0
        if dt < best:
            best, out = dt, res
    return out, best


def _per_call_us(fn: Any, reps: int, blocks: int = 15) -> float:
    """Wall time of ``fn()`` [µs]: the mean over a block of ``reps`` calls, the smallest of
    ``blocks`` such blocks (as ``timeit`` reports the minimum: the machine is shared, and the
    minimum is the time the calls take when they have a core)."""
    fn()
    best = float("inf")
    for _ in range(blocks):
        t0 = time.perf_counter()
        for _ in range(reps):
            fn()
        best = min(best, (time.perf_counter() - t0) / reps)
    return best * 1e6


def machine_speed() -> float:
    """µs per LM evaluation of a fixed workload (UR5, 64 seeded random starts): how loaded
    the machine was, to read the wall times against (≈ 1.4 µs on an idle core)."""
    import swarm_ik
    from swarm_ik.solvers.hybrid import Polisher

    robot = swarm_ik.load_robot("ur5")
    rng = np.random.default_rng(123)
    problem = swarm_ik.IKProblem.from_q(robot, robot.random_q(rng))
    pol = Polisher.from_problem(problem, tol_pos=1e-12, tol_rot=1e-12)
    starts = rng.uniform(problem.lower, problem.upper, size=(64, robot.nq))
    pol.polish(starts[:2], 10**9, False)
    best = float("inf")
    for _ in range(5):
        t0 = time.perf_counter()
        out = pol.polish(starts, 10**9, False)
        best = min(best, (time.perf_counter() - t0) / out.used)
    return best * 1e6


def _analytic_costs(problem: Any, ref: np.ndarray, n: int) -> dict[str, float]:
    """µs per call of the analytic path's parts and wholes on one target."""
    import swarm_ik
    from swarm_ik.branches import pose_errors
    from swarm_ik.goals import kernels
    from swarm_ik.kernels import lm
    from swarm_ik.solvers import analytic

    chain = analytic.analytic_chain(problem.robot)
    err = np.empty((ref.shape[0], 1, 2))
    c2 = np.empty(ref.shape[0])
    tab = problem.table(None)
    return {
        "eaik_us": _per_call_us(lambda: chain.solver.calculate_IK(problem.target), 20),
        "pinocchio_check_us": _per_call_us(lambda: pose_errors(problem, ref), 20),
        "kernel_check_us": _per_call_us(
            lambda: lm.errors_batch(ref, problem.tree, tab, kernels(), problem.bounds, err, c2), 20
        ),
        "solve_all_us": _per_call_us(lambda: analytic.solve_all(problem), 20),
        "solve_many_analytic_us": _per_call_us(
            lambda: swarm_ik.solve_many(problem, n=n, method="analytic"), 20
        ),
        "solver_analytic_us": _per_call_us(lambda: swarm_ik.solve(problem, "analytic"), 10),
    }


def run_arm(name: str, n_targets: int, n: int, seed: int, reps: int = 5) -> list[dict[str, Any]]:
    """One row per target and path (``numerical``, ``analytic``).

    ``wall_ms`` is the best of ``reps`` identical calls (same seed, same work), which filters
    the load of a shared machine; ``wall_first_ms`` is the first of them.
    """
    import swarm_ik
    from swarm_ik.branches import revolute_mask
    from swarm_ik.solvers import analytic

    robot = swarm_ik.load_robot(name)
    rng = np.random.default_rng(seed)
    wrap_all = revolute_mask(robot)
    warm = swarm_ik.IKProblem.from_q(robot, robot.mid_q())
    swarm_ik.solve_many(warm, n=n, method="numerical")  # compile outside the timings
    swarm_ik.solve_many(warm, n=n, method="analytic")
    swarm_ik.solve(warm, "analytic")
    rows = []
    for t, q in enumerate(robot.random_q(rng, n_targets)):
        problem = swarm_ik.IKProblem.from_q(robot, q)
        ref = analytic.solve_all(problem)[0]
        gen_in_ref = bool(_match(q[None], ref, wrap_all).any())
        us = _analytic_costs(problem, ref, n)
        for path in ("numerical", "analytic"):
            wall_first = float("nan")
            wall = float("inf")
            sols = []
            for _ in range(reps):  # identical calls: keep the fastest one's results and times
                t_call = time.perf_counter()
                out = cast(list[Any], swarm_ik.solve_many(problem, n=n, method=path, seed=t))
                dt = time.perf_counter() - t_call
                wall_first = dt if np.isnan(wall_first) else wall_first
                if dt < wall:
                    wall, sols = dt, out
            qs = np.array([s.q for s in sols]).reshape(-1, robot.nq)
            m = _match(qs, ref, wrap_all)
            found = m.any(axis=0)
            dup = _match(qs, qs, wrap_all)
            n_dup = int((dup.sum() - qs.shape[0]) // 2)
            times = sorted(s.time_s for s in sols)
            t_complete = (
                max(s.time_s for s, row in zip(sols, m, strict=True) if row.any())
                if found.all() and ref.shape[0]
                else float("nan")
            )
            row = {
                "arm": name,
                "target": t,
                "path": path,
                "n_ref": int(ref.shape[0]),
                "generator_in_ref": gen_in_ref,
                "found": int(found.sum()),
                "returned": int(qs.shape[0]),
                "extras": int((~m.any(axis=1)).sum()) if qs.shape[0] else 0,
                "duplicates": n_dup,
                "wall_ms": wall * 1e3,
                "wall_first_ms": wall_first * 1e3,
                "t_complete_ms": t_complete * 1e3,
                "t_kth_ms": " ".join(f"{x * 1e3:.4f}" for x in times),
                "n_evals": max((s.n_evals for s in sols), default=0),
                "all_success": all(s.success for s in sols),
            }
            for key, val in us.items():
                row[key] = val if path == "analytic" else float("nan")
            rows.append(row)
    return rows


def run_spread(n: int, n_targets: int, seed: int) -> list[dict[str, Any]]:
    """Coverage of the 7-joint panda's self-motion by ``solve_many(n)``."""
    import swarm_ik
    from swarm_ik.branches import covering_radius, periodic_mask

    robot = swarm_ik.load_robot("panda")
    periodic = periodic_mask(robot)
    rng = np.random.default_rng(seed + 1)
    swarm_ik.solve_many(swarm_ik.IKProblem.from_q(robot, robot.mid_q()), n=n)
    rows = []
    for t, q in enumerate(robot.random_q(rng, n_targets)):
        problem = swarm_ik.IKProblem.from_q(robot, q)
        sols, wall = _best_of(
            lambda problem=problem, t=t: swarm_ik.solve_many(
                problem, n=n, method="numerical", seed=t
            ),
            5,
        )
        sols = cast(list[Any], sols)
        pool = cast(
            list[Any], swarm_ik.solve_many(problem, n=256, method="numerical", seed=10_000 + t)
        )
        pool_q = np.array([s.q for s in pool]).reshape(-1, robot.nq)
        sel = np.array([s.q for s in sols]).reshape(-1, robot.nq)
        in_order = pool_q[np.argsort([s.time_s for s in pool], kind="stable")][: sel.shape[0]]
        pick = np.random.default_rng(t).choice(pool_q.shape[0], sel.shape[0], replace=False)
        d = np.linalg.norm(sel[:, None] - sel[None], axis=-1) + np.eye(sel.shape[0]) * 1e9
        rows.append(
            {
                "target": t,
                "returned": int(sel.shape[0]),
                "pool": int(pool_q.shape[0]),
                "cover_radius": covering_radius(sel, pool_q, periodic),
                "cover_radius_first_found": covering_radius(in_order, pool_q, periodic),
                "cover_radius_random": covering_radius(pool_q[pick], pool_q, periodic),
                "joint_span": float(np.mean(np.ptp(sel, axis=0) / (robot.upper - robot.lower))),
                "min_pair_dist": float(d.min()) if sel.shape[0] > 1 else float("nan"),
                "wall_ms": wall * 1e3,
            }
        )
    return rows


def _write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def summarize(
    rows: list[dict[str, Any]], spread: list[dict[str, Any]], n: int, speed: float, load: str
) -> str:
    """Markdown tables of the benchmark."""
    from swarm_ik.many import POOL_FACTOR

    lines = [
        f"# bench many: every IK branch (n={n})",
        "",
        "Recall against eaik's in-limit branch sets (modulo 2π, 1e-6 rad). Wall times are the "
        "best of 5 identical calls (same seed) of `solve_many`, to filter the load of the "
        f"shared machine; its speed during the run: {speed:.2f} µs per LM evaluation of a "
        f"fixed UR5 workload (≈ 1.4 µs idle); {load}.",
        "",
        "| arm | path | targets | mean branches | recall | complete sets | extras | duplicates "
        "| median ms | p90 ms | median ms (first call) | median ms to 1st | median ms to "
        "complete set | median evals |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    arms = list(dict.fromkeys(r["arm"] for r in rows))
    for arm in arms:
        for path in ("numerical", "analytic"):
            rr = [r for r in rows if r["arm"] == arm and r["path"] == path]
            n_ref = sum(r["n_ref"] for r in rr)
            found = sum(r["found"] for r in rr)
            wall = np.array([r["wall_ms"] for r in rr])
            first = np.array([r["wall_first_ms"] for r in rr])
            comp = np.array([r["t_complete_ms"] for r in rr])
            t1 = np.array([float(r["t_kth_ms"].split()[0]) for r in rr if r["t_kth_ms"]])
            lines.append(
                f"| {arm} | {path} | {len(rr)} | {n_ref / len(rr):.2f} | "
                f"{100 * found / max(n_ref, 1):.1f} % | "
                f"{sum(r['found'] == r['n_ref'] for r in rr)}/{len(rr)} | "
                f"{sum(r['extras'] for r in rr)} | {sum(r['duplicates'] for r in rr)} | "
                f"{np.median(wall):.3f} | {np.percentile(wall, 90):.3f} | "
                f"{np.median(first):.3f} | {np.median(t1):.3f} | "
                f"{np.nanmedian(comp) if np.isfinite(comp).any() else float('nan'):.3f} | "
                f"{np.median([r['n_evals'] for r in rr]):.0f} |"
            )
    gen = sum(r["generator_in_ref"] for r in rows if r["path"] == "analytic")
    lines += [
        "",
        f"Generating configuration in eaik's set: {gen}/"
        f"{sum(r['path'] == 'analytic' for r in rows)}.",
        "",
        "## Time to the k-th branch (numerical path, median ms over the targets that have k)",
        "",
        "| arm | " + " | ".join(f"k={k}" for k in range(1, 9)) + " |",
        "|---|" + "---|" * 8,
    ]
    for arm in arms:
        rr = [r for r in rows if r["arm"] == arm and r["path"] == "numerical"]
        ks = [[float(x) for x in r["t_kth_ms"].split()] for r in rr]
        cells = []
        for k in range(1, 9):
            vals = [v[k - 1] for v in ks if len(v) >= k]
            cells.append(f"{np.median(vals):.3f} ({len(vals)})" if vals else "–")
        lines.append(f"| {arm} | " + " | ".join(cells) + " |")
    keys = [
        ("eaik_us", "eaik `calculate_IK`"),
        ("pinocchio_check_us", "Pinocchio check of the set (`pose_errors`)"),
        ("kernel_check_us", "compiled-kernel check of the set (`errors_batch`)"),
        ("solve_all_us", "`analytic.solve_all`"),
        ("solve_many_analytic_us", "`solve_many(method='analytic')`"),
        ("solver_analytic_us", "`swarm_ik.solve(problem, 'analytic')`"),
    ]
    lines += [
        "",
        "## Analytic path, µs per pose (median over the targets of the best of 15 blocks of "
        "20 calls, 10 for the last one)",
        "",
        "| arm | " + " | ".join(label for _, label in keys) + " |",
        "|---|" + "---|" * len(keys),
    ]
    for arm in arms:
        rr = [r for r in rows if r["arm"] == arm and r["path"] == "analytic"]
        lines.append(
            f"| {arm} | "
            + " | ".join(f"{np.median([r[k] for r in rr]):.1f}" for k, _ in keys)
            + " |"
        )
    if spread:
        cr = np.array([r["cover_radius"] for r in spread])
        cf = np.array([r["cover_radius_first_found"] for r in spread])
        cx = np.array([r["cover_radius_random"] for r in spread])
        lines += [
            "",
            f"## 7-joint spread (panda, n={n})",
            "",
            "Farthest-point selection (:func:`swarm_ik.branches.spread_select`) of `n` out of "
            f"a pool of {POOL_FACTOR} · n distinct solutions. Coverage: the covering radius "
            "(rad) over a dense pool of solutions from `n=256` (the largest distance from a "
            "pooled solution to its nearest returned one; smaller is better), against the "
            "first `n` solutions found and `n` random pool members; joint span: the mean "
            "range of each joint over the returned solutions, as a fraction of its limits.",
            "",
            "| targets | returned (mean) | pool (mean) | cover radius median | first-found "
            "median | random median | min pair distance median | joint span | median ms |",
            "|---|---|---|---|---|---|---|---|---|",
            f"| {len(spread)} | {np.mean([r['returned'] for r in spread]):.1f} | "
            f"{np.mean([r['pool'] for r in spread]):.0f} | "
            f"{np.median(cr):.3f} | {np.median(cf):.3f} | {np.median(cx):.3f} | "
            f"{np.nanmedian([r['min_pair_dist'] for r in spread]):.3f} | "
            f"{np.median([r['joint_span'] for r in spread]):.2f} | "
            f"{np.median([r['wall_ms'] for r in spread]):.2f} |",
        ]
    return "\n".join(lines) + "\n"


def check_arms(names: list[str]) -> None:
    """Refuse, before anything is written, an arm that is not a 6-joint chain eaik solves (the
    reference sets are eaik's): each is loaded (a bad name refused with the loader's message)
    and its analytic chain built.

    Raises:
        InvalidArgumentError: ``--arms NAME: why`` (its joint count, or the chain eaik has
            no decomposition of).
        AnalyticUnavailableError: eaik is not installed (the message names the extra).
    """
    from swarm_ik.errors import InvalidArgumentError
    from swarm_ik.solvers import analytic

    common.check_robots(names)
    for name in names:
        chain = analytic.analytic_chain(common.cached_robot(name))
        if not chain.supported:
            raise InvalidArgumentError(
                f"--arms {name}: {chain.reason}; bench many measures 6-joint arms that eaik "
                f"solves (default: {' '.join(ARMS)})"
            )


def run(args: argparse.Namespace) -> int:
    """Run the experiment; returns the exit code."""

    out = common.resolve_out(args.out, "many", False)  # checked, not made yet
    check_arms(args.arms)
    out.mkdir(parents=True, exist_ok=True)
    common.write_run_info(out, "many", False, n=args.n, n_targets=args.n_targets, arms=args.arms)
    speed = machine_speed()
    rows: list[dict[str, Any]] = []
    for arm in args.arms:
        rows += run_arm(arm, args.n_targets, args.n, args.seed)
    spread = run_spread(args.n, args.n_targets, args.seed)
    _write_csv(out / "many.csv", rows)
    _write_csv(out / "spread.csv", spread)
    md = summarize(rows, spread, args.n, min(speed, machine_speed()), common.load_line())
    return common.write_report(out / "many.md", md)


main = common.module_main(add_arguments, run, "many", __doc__)


if __name__ == "__main__":
    raise SystemExit(main())
