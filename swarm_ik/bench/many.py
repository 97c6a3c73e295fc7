"""``swarm-ik bench many``: every IK branch, numerical and analytic, against eaik's sets.

For each arm (UR5, UR10, z1) ``N`` targets are the FK of uniform random joint vectors.  The
reference set of a target is eaik's solutions (exact ones only) that have an in-limit 2π copy,
verified with Pinocchio (:func:`swarm_ik.solvers.analytic.solve_all`); the generating
configuration must be in it.  Per target and path: recall (reference branches found, modulo
2π within 1e-6 rad), extras (returned solutions in no reference branch), duplicates (pairs
of returned solutions in one branch), wall time of the call, time to the k-th branch and to
the complete set.  For the 7-joint panda: the covering radius of ``solve_many(n=16)`` over a
dense pool of solutions (``n=256``), against 16 solutions taken in the order found.

Writes ``many.csv``, ``spread.csv`` and ``many.md`` into ``--out``.
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path
from typing import Any, cast

import numpy as np

ARMS = ("ur5", "ur10", "z1")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``swarm-ik bench many``."""
    parser.add_argument("--n-targets", type=int, default=50, help="targets per arm (default 50)")
    parser.add_argument("--n", type=int, default=16, help="solve_many's n (default 16)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the targets")
    parser.add_argument("--arms", nargs="+", default=list(ARMS), help="6R arms to measure")
    parser.add_argument("--out", type=Path, default=Path("bench-many"), help="output folder")


def _match(qs: np.ndarray, ref: np.ndarray, periodic: np.ndarray, tol: float = 1e-6) -> Any:
    from swarm_ik.branches import branch_distance

    if qs.shape[0] == 0 or ref.shape[0] == 0:
        return np.zeros((qs.shape[0], ref.shape[0]), dtype=bool)
    return branch_distance(qs[:, None, :], ref[None, :, :], periodic) < tol


def run_arm(name: str, n_targets: int, n: int, seed: int) -> list[dict[str, Any]]:
    """One row per target and path (``numerical``, ``analytic``)."""
    import swarm_ik
    from swarm_ik.branches import revolute_mask
    from swarm_ik.solvers import analytic

    robot = swarm_ik.load_robot(name)
    rng = np.random.default_rng(seed)
    wrap_all = revolute_mask(robot)
    warm = swarm_ik.IKProblem.from_q(robot, robot.mid_q())
    swarm_ik.solve_many(warm, n=n, method="numerical")  # compile outside the timings
    analytic.solve_all(warm)
    rows = []
    for t, q in enumerate(robot.random_q(rng, n_targets)):
        problem = swarm_ik.IKProblem.from_q(robot, q)
        ref = analytic.solve_all(problem)[0]
        gen_in_ref = bool(_match(q[None], ref, wrap_all).any())
        reps = 200
        t0 = time.perf_counter()
        for _ in range(reps):
            analytic.solve_all(problem)
        us_all = (time.perf_counter() - t0) / reps * 1e6
        for path in ("numerical", "analytic"):
            t0 = time.perf_counter()
            sols = cast(list[Any], swarm_ik.solve_many(problem, n=n, method=path, seed=t))
            wall = time.perf_counter() - t0
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
            rows.append(
                {
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
                    "t_first_ms": times[0] * 1e3 if times else float("nan"),
                    "t_complete_ms": t_complete * 1e3,
                    "n_evals": max((s.n_evals for s in sols), default=0),
                    "solve_all_us": us_all if path == "analytic" else float("nan"),
                    "all_success": all(s.success for s in sols),
                }
            )
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
        t0 = time.perf_counter()
        sols = cast(list[Any], swarm_ik.solve_many(problem, n=n, method="numerical", seed=t))
        wall = time.perf_counter() - t0
        pool = cast(
            list[Any], swarm_ik.solve_many(problem, n=256, method="numerical", seed=10_000 + t)
        )
        pool_q = np.array([s.q for s in pool]).reshape(-1, robot.nq)
        sel = np.array([s.q for s in sols]).reshape(-1, robot.nq)
        in_order = pool_q[np.argsort([s.time_s for s in pool])][: sel.shape[0]]
        d = np.linalg.norm(sel[:, None] - sel[None], axis=-1) + np.eye(sel.shape[0]) * 1e9
        rows.append(
            {
                "target": t,
                "returned": int(sel.shape[0]),
                "pool": int(pool_q.shape[0]),
                "cover_radius": covering_radius(sel, pool_q, periodic),
                "cover_radius_first_found": covering_radius(in_order, pool_q, periodic),
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


def summarize(rows: list[dict[str, Any]], spread: list[dict[str, Any]], n: int) -> str:
    """Markdown tables of the benchmark."""
    lines = [
        f"# bench many: every IK branch (n={n})",
        "",
        "Recall against eaik's in-limit branch sets (modulo 2π, 1e-6 rad); times are wall "
        "clock of one `solve_many` call on this machine.",
        "",
        "| arm | path | targets | mean branches | recall | complete sets | extras | duplicates "
        "| median ms | p90 ms | median ms to complete set | solve_all µs (median) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for arm in dict.fromkeys(r["arm"] for r in rows):
        for path in ("numerical", "analytic"):
            rr = [r for r in rows if r["arm"] == arm and r["path"] == path]
            n_ref = sum(r["n_ref"] for r in rr)
            found = sum(r["found"] for r in rr)
            wall = np.array([r["wall_ms"] for r in rr])
            comp = np.array([r["t_complete_ms"] for r in rr])
            us = np.array([r["solve_all_us"] for r in rr])
            lines.append(
                f"| {arm} | {path} | {len(rr)} | {n_ref / len(rr):.2f} | "
                f"{100 * found / max(n_ref, 1):.1f} % | "
                f"{sum(r['found'] == r['n_ref'] for r in rr)}/{len(rr)} | "
                f"{sum(r['extras'] for r in rr)} | {sum(r['duplicates'] for r in rr)} | "
                f"{np.median(wall):.3f} | {np.percentile(wall, 90):.3f} | "
                f"{np.nanmedian(comp) if np.isfinite(comp).any() else float('nan'):.3f} | "
                + (f"{np.nanmedian(us):.1f} |" if path == "analytic" else "– |")
            )
    gen = sum(r["generator_in_ref"] for r in rows if r["path"] == "analytic")
    lines += [
        "",
        f"Generating configuration in eaik's set: {gen}/"
        f"{sum(r['path'] == 'analytic' for r in rows)}.",
    ]
    if spread:
        cr = np.array([r["cover_radius"] for r in spread])
        cf = np.array([r["cover_radius_first_found"] for r in spread])
        lines += [
            "",
            f"## 7-joint spread (panda, n={n})",
            "",
            "Covering radius (rad) of the returned solutions over a pool from `n=256`: the "
            "largest distance from a pooled solution to its nearest returned one.",
            "",
            "| targets | returned (mean) | cover radius median | first-found median | "
            "min pair distance median | median ms |",
            "|---|---|---|---|---|---|",
            f"| {len(spread)} | {np.mean([r['returned'] for r in spread]):.1f} | "
            f"{np.median(cr):.3f} | {np.median(cf):.3f} | "
            f"{np.nanmedian([r['min_pair_dist'] for r in spread]):.3f} | "
            f"{np.median([r['wall_ms'] for r in spread]):.2f} |",
        ]
    return "\n".join(lines) + "\n"


def run(args: argparse.Namespace) -> int:
    """Run the experiment; returns the exit code."""
    args.out.mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, Any]] = []
    for arm in args.arms:
        rows += run_arm(arm, args.n_targets, args.n, args.seed)
    spread = run_spread(args.n, args.n_targets, args.seed)
    _write_csv(args.out / "many.csv", rows)
    _write_csv(args.out / "spread.csv", spread)
    md = summarize(rows, spread, args.n)
    (args.out / "many.md").write_text(md)
    print(md)
    return 0


def main(argv: list[str] | None = None) -> int:
    """``python -m swarm_ik.bench.many``: the same as ``swarm-ik bench many``."""
    parser = argparse.ArgumentParser(prog="swarm-ik bench many", description=__doc__)
    add_arguments(parser)
    return run(parser.parse_args(argv))


if __name__ == "__main__":
    raise SystemExit(main())
