"""``python -m swarm_ik.bench.path``: jump-free Cartesian paths (:func:`swarm_ik.path.solve_path`).

Paths of ``--waypoints`` poses (default 40) on UR5 and UR10 (closed form with eaik) and on
Panda and xarm7 (7 joints, redundant), ``--n`` of each kind per arm:

* ``line``: a straight line between two random reachable poses (FK of uniform random joint
  vectors), the orientation slerped;
* ``arc``: a half circle between two such poses (the chord its diameter, in a random plane
  through it), the orientation slerped;
* ``joint``: FK of a smooth joint trajectory (a min-jerk blend between two configurations
  plus a half-sine bump, each joint moving at most 0.1 rad between waypoints): a jump-free
  path exists by construction.

Every path is solved with ``max_joint_step`` 0.2 rad by

* ``solve_path`` (ours), its answer checked here independently: each waypoint with
  :meth:`swarm_ik.IKProblem.verify` (Pinocchio's FK, 1e-5 m / 1e-5 rad), each step against
  the bound;
* greedy nearest tracking with swarm_ik: the first waypoint solved from mid-range, each next
  one with ``swarm_ik.solve(..., q0=previous, prefer="nearest")``;
* the same greedy tracking with TRAC-IK and roboticstoolbox ``ik_LM`` seeded with the
  previous answer, when installed (``--no-peers`` skips them);
* on the 6R arms, the exhaustive reference: every branch of every waypoint with every
  in-limit 2π copy (``windings_of(problem, solve_many(...))``, eaik) and a separate dynamic
  programme (numpy) that decides whether a jump-free sequence exists.  Where ``solve_path``
  claims that no jump-free path exists, the claim is checked again with the numerical
  branch sets added (``solve_many(method="numerical")``, independent of eaik).

Writes ``paths.csv`` (one row per path) and ``path.md`` into ``--out``.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from swarm_ik import argtypes
from swarm_ik.argtypes import count
from swarm_ik.bench import common

ARMS = ("ur5", "ur10", "panda", "xarm7")
KINDS = ("line", "arc", "joint")
STEP = 0.2
"""``max_joint_step`` of every path [rad]."""
TOL = 1e-5
PEERS = ("tracik-1e-6", "rtb-lm")
"""Peers tracked greedily (TRAC-IK at eps 1e-6: at 1e-5 its own test passes answers beyond
the 1e-5 tolerance judged here)."""
FIELDS = (
    "arm", "kind", "path", "waypoints", "all_reachable_ref", "ref_exists", "ref_ms",
    "ours_success", "ours_jump_free", "ours_verified", "ours_reconfigurations",
    "ours_exhaustive", "ours_claims_proof", "proof_rechecked", "ours_max_step", "ours_ms",
    "ours_cpu_ms",
    "ours_candidates", "greedy_success", "greedy_jump_free", "greedy_max_step", "greedy_ms",
    "tracik_claimed", "tracik_success", "tracik_jump_free", "tracik_ms", "rtb_claimed",
    "rtb_success", "rtb_jump_free", "rtb_ms", "reason",
)  # fmt: skip


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``python -m swarm_ik.bench.path``."""
    parser.add_argument("--n", type=count(1), default=100, help="paths per arm and kind (100)")
    parser.add_argument("--waypoints", type=count(1), default=40, help="waypoints per path (40)")
    parser.add_argument("--arms", nargs="+", default=list(ARMS), help="robots")
    parser.add_argument("--kinds", nargs="+", default=list(KINDS), choices=KINDS)
    argtypes.add_seed(parser, "seed of the paths")
    for switch, text in [
        ("--quick", "N = 10 paths (a smoke run)"),
        ("--no-peers", "skip TRAC-IK and rtb"),
        ("--from-csv", "write path.md again from --out's paths.csv (no solving)"),
    ]:
        parser.add_argument(switch, action="store_true", help=text)
    common.add_out(parser, "path", type=Path)


# ------------------------------------------------------------------------------ paths
def smooth_joint_path(
    robot: Any, rng: np.random.Generator, n: int, step: float = 0.1, margin: float = 0.05
) -> Any:
    """A smooth joint trajectory ``(n, nq)`` within the limits: a min-jerk blend from one
    random configuration (at least ``margin`` inside the limits) towards another plus a
    half-sine bump, each joint moving at most ``step`` between samples."""
    lo, hi = robot.lower + margin, robot.upper - margin
    a = rng.uniform(lo, hi)
    d = rng.uniform(-1, 1, robot.nq)
    d *= step * (n - 1) / 2.0 / np.abs(d).max()
    b = np.clip(a + d, lo, hi)
    t = np.linspace(0.0, 1.0, n)[:, None]
    bump = 0.25 * step * (n - 1) / np.pi * np.sin(np.pi * t) * rng.uniform(-1, 1, robot.nq)
    return np.clip(a + (3 * t**2 - 2 * t**3) * (b - a) + bump, robot.lower, robot.upper)


def make_path(robot: Any, kind: str, rng: np.random.Generator, n: int) -> Any:
    """Poses ``(n, 4, 4)`` of one path of ``kind``."""
    from swarm_ik.path import interpolate_pose

    if kind == "joint":
        return np.asarray(robot.fk(smooth_joint_path(robot, rng, n)))
    a, b = (np.asarray(robot.fk(q)) for q in robot.random_q(rng, 2))
    s = np.linspace(0.0, 1.0, n)
    poses = np.array([interpolate_pose(a, b, float(x)) for x in s])
    if kind == "arc":
        chord = b[:3, 3] - a[:3, 3]
        u = np.cross(chord, rng.normal(size=3))
        u /= np.linalg.norm(u)
        mid = 0.5 * (a[:3, 3] + b[:3, 3])
        r = 0.5 * float(np.linalg.norm(chord))
        th = np.pi * s
        poses[:, :3, 3] = mid - 0.5 * chord * np.cos(th)[:, None] + r * np.sin(th)[:, None] * u
    return poses


# ------------------------------------------------------------------------------ solvers
def greedy(robot: Any, poses: Any, seed: int) -> tuple[Any, bool, float]:
    """swarm_ik tracking: ``(q (n, nq), every waypoint solved, seconds)``."""
    import swarm_ik

    t0 = time.perf_counter()
    q = robot.mid_q()
    out, ok = [], True
    for i, pose in enumerate(poses):
        res = swarm_ik.solve(
            swarm_ik.IKProblem(robot, pose), q0=q, prefer="nearest", seed=seed + i,
            tol_pos=TOL, tol_rot=TOL, time_limit=0.02,
        )  # fmt: skip
        ok = ok and res.success
        q = np.array(res.q)
        out.append(q)
    return np.array(out), ok, time.perf_counter() - t0


def peer_tracking(peer: Any, robot: Any, poses: Any) -> tuple[Any, bool, float]:
    """A peer seeded with its previous answer: ``(q (n, nq), the peer's own claim of
    success at every waypoint, seconds)`` (a failed answer keeps the previous
    configuration)."""
    t0 = time.perf_counter()
    q = robot.mid_q()
    out, claimed = [], True
    for i, pose in enumerate(poses):
        ans = peer.solve(np.ascontiguousarray(pose), q, i)
        claimed = claimed and bool(ans.claimed)
        if ans.q is not None:
            q = np.asarray(ans.q, dtype=float)
        out.append(q)
    return np.array(out), claimed, time.perf_counter() - t0


def judge(robot: Any, poses: Any, q: Any) -> tuple[bool, bool, float]:
    """Independent check of a joint path: ``(every waypoint within 1e-5 m / 1e-5 rad and the
    limits, every step within the bound, the largest step)``."""
    import swarm_ik

    ok = True
    for pose, qi in zip(poses, q, strict=True):
        (err,) = swarm_ik.IKProblem(robot, pose).verify(qi, TOL, TOL)
        dp, dr = err.position_error, err.rotation_error
        ok = ok and dp <= TOL and dr <= TOL and robot.within_limits(qi)
    d = np.abs(np.diff(robot.wrap(q), axis=0))
    cont = robot.continuous_mask
    d[:, cont] = np.minimum(d[:, cont], 2 * np.pi - d[:, cont])
    biggest = float(d.max())
    return bool(ok), biggest <= STEP * (1 + 1e-9), biggest


def branch_layers(robot: Any, poses: Any, numerical: bool = False) -> list[Any]:
    """Every solution of every waypoint with every in-limit 2π copy (``solve_many`` and
    ``windings_of``; ``numerical`` adds the numerical path's branches)."""
    import swarm_ik

    layers = []
    for pose in poses:
        problem = swarm_ik.IKProblem(robot, pose)
        found = swarm_ik.solve_many(problem, n=16, tol_pos=TOL, tol_rot=TOL)
        if numerical:
            found += swarm_ik.solve_many(
                problem, n=16, method="numerical", tol_pos=TOL, tol_rot=TOL
            )
        copies = swarm_ik.windings_of(problem, found, tol_pos=TOL, tol_rot=TOL)
        qs = [r.q for branch in copies for r in branch]
        layers.append(np.array(qs, dtype=float).reshape(-1, robot.nq))
    return layers


def path_exists(layers: list[Any], step: float = STEP) -> bool:
    """Whether a sequence with one row per layer and every step within ``step`` exists
    (reachability layer by layer; independent of :mod:`swarm_ik.path`)."""
    reach = np.ones(layers[0].shape[0], dtype=bool)
    for qa, qb in zip(layers[:-1], layers[1:], strict=True):
        if not reach.any() or qb.shape[0] == 0:
            return False
        close = np.max(np.abs(qb[:, None, :] - qa[None, reach, :]), axis=-1) <= step * (1 + 1e-9)
        reach = close.any(axis=1)
    return bool(reach.any())


# ------------------------------------------------------------------------------ the run
def run_arm(
    name: str, kinds: list[str], n: int, waypoints: int, seed: int, peers: bool
) -> list[dict[str, Any]]:
    """One row per path of ``name``."""
    import swarm_ik
    from swarm_ik.bench import peers as peer_mod
    from swarm_ik.path import solve_path

    robot = common.cached_robot(name)
    six_r = robot.nq == 6
    made = {}
    if peers:
        for label in PEERS:
            if peer_mod.get(label).available():
                try:
                    made[label] = peer_mod.make(label, robot, 0.005, TOL)
                except swarm_ik.SwarmIKError as exc:  # a peer that cannot build the chain
                    print(f"  {label} skipped on {name}: {exc}")
    warm = make_path(robot, "joint", np.random.default_rng(12345), 5)  # loads the kernels
    solve_path(robot, warm)
    greedy(robot, warm, 0)
    rows = []
    for kind in kinds:
        for p in range(n):
            arm_key = ARMS.index(name) if name in ARMS else len(ARMS)
            rng = np.random.default_rng([seed, arm_key, KINDS.index(kind), p])
            poses = make_path(robot, kind, rng, waypoints)
            c0 = time.process_time()
            res = solve_path(robot, poses, max_joint_step=STEP, seed=p, tol_pos=TOL, tol_rot=TOL)
            cpu_ms = 1e3 * (time.process_time() - c0)
            ok, free, _ = judge(robot, poses, res.q)
            row: dict[str, Any] = dict(
                arm=name, kind=kind, path=p, waypoints=waypoints,
                ours_success=int(res.success), ours_jump_free=int(res.jump_free),
                ours_verified=int(ok == res.success and free == res.jump_free),
                ours_reconfigurations=len(res.reconfigurations),
                ours_exhaustive=int(res.exhaustive),
                ours_claims_proof=int("proves" in res.reason),
                ours_max_step=res.max_step, ours_ms=1e3 * res.time_s, ours_cpu_ms=cpu_ms,
                ours_candidates=float(np.mean(res.n_candidates)),
                reason=res.reason[:200],
            )  # fmt: skip
            qg, _, tg = greedy(robot, poses, p)
            g_ok, g_free, g_max = judge(robot, poses, qg)
            row.update(greedy_success=int(g_ok), greedy_jump_free=int(g_ok and g_free),
                       greedy_max_step=g_max, greedy_ms=1e3 * tg)  # fmt: skip
            for label, key in (("tracik-1e-6", "tracik"), ("rtb-lm", "rtb")):
                if label in made:
                    qp, claimed, tp = peer_tracking(made[label], robot, poses)
                    p_ok, p_free, _ = judge(robot, poses, qp)
                    row[f"{key}_claimed"] = int(claimed)
                    row[f"{key}_success"] = int(p_ok)
                    row[f"{key}_jump_free"] = int(p_ok and p_free)
                    row[f"{key}_ms"] = 1e3 * tp
                else:
                    fields = ("claimed", "success", "jump_free", "ms")
                    row.update({f"{key}_{f}": "" for f in fields})
            row.update(all_reachable_ref="", ref_exists="", ref_ms="", proof_rechecked="")
            if six_r:
                t0 = time.perf_counter()
                layers = branch_layers(robot, poses)
                exists = path_exists(layers)
                row["all_reachable_ref"] = int(all(x.shape[0] for x in layers))
                row["ref_exists"] = int(exists)
                row["ref_ms"] = 1e3 * (time.perf_counter() - t0)
                if row["ours_claims_proof"]:
                    more = branch_layers(robot, poses, numerical=True)
                    row["proof_rechecked"] = int(not path_exists(more))
            rows.append(row)
        print(f"  {name} {kind}: {n} paths", flush=True)
    return rows


def _share(rows: list[dict[str, Any]], key: str) -> str:
    vals = [int(r[key]) for r in rows if r.get(key, "") != ""]
    if not vals:
        return "–"
    return f"{100.0 * sum(vals) / len(vals):.0f} % ({sum(vals)}/{len(vals)})"


def _median(rows: list[dict[str, Any]], key: str, scale: float = 1.0) -> str:
    vals = [float(r[key]) * scale for r in rows if r.get(key, "") != ""]
    return f"{np.median(vals):.1f}" if vals else "–"


def _p90(rows: list[dict[str, Any]], key: str) -> str:
    vals = [float(r[key]) for r in rows if r.get(key, "") != ""]
    return f"{np.percentile(vals, 90):.1f}" if vals else "–"


def _cells(
    rows: list[dict[str, Any]], arms: list[str], kinds: list[str]
) -> Iterator[tuple[str, str, list[dict[str, Any]]]]:
    """``(arm, kind, its rows)`` for every arm and kind that has rows, in the report's order
    (arms, then kinds)."""
    for arm in arms:
        for kind in kinds:
            rr = [r for r in rows if r["arm"] == arm and r["kind"] == kind]
            if rr:
                yield arm, kind, rr


def summarize(rows: list[dict[str, Any]], args: argparse.Namespace, load: str) -> str:
    """The Markdown report."""
    w = args.waypoints
    arms = list(dict.fromkeys(r["arm"] for r in rows))
    kinds = list(dict.fromkeys(r["kind"] for r in rows))
    lines = [
        "# bench path: jump-free Cartesian paths (`swarm_ik.path.solve_path`)",
        "",
        f"`python -m swarm_ik.bench.path --n {args.n} --waypoints {w}"
        + (" --quick" if args.quick else "")
        + f"`: {len(rows) // max(len(arms) * len(kinds), 1)} paths per arm and kind, {w} "
        f"waypoints each, `max_joint_step` {STEP} rad, tolerances {TOL:g} m / {TOL:g} rad. "
        "Kinds: `line` and `arc` between two random reachable poses (FK of random joint "
        "vectors; parts of them may be unreachable), `joint` = FK of a smooth joint "
        "trajectory (a jump-free path exists). Every answer is checked here with Pinocchio "
        "(`IKProblem.verify`) and against the bound; a path counts as jump-free only if every "
        f"waypoint is reached and every step is within the bound. Machine: {load}.",
        "",
        "## Share of paths made jump-free",
        "",
        "| arm | kind | paths | reference: a path exists | ours jump-free | agreement with "
        "the reference | ours beyond the reference | proofs claimed (rechecked) | wrong claims "
        "| greedy swarm_ik | TRAC-IK greedy | rtb ik_LM greedy |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for arm, kind, rr in _cells(rows, arms, kinds):
        ok = [dict(r, ours_ok=int(int(r["ours_success"]) and int(r["ours_jump_free"]))) for r in rr]
        agree = beyond = "–"
        if rr[0]["ref_exists"] != "":
            same = sum(int(r["ours_ok"] == int(r["ref_exists"])) for r in ok)
            agree = f"{100.0 * same / len(ok):.0f} % ({same}/{len(ok)})"
            beyond = str(
                sum(
                    int(r["ours_ok"] and not int(r["ref_exists"]) and int(r["ours_verified"]))
                    for r in ok
                )
            )
        claims = sum(int(r["ours_claims_proof"]) for r in rr)
        rechecked = sum(int(r["proof_rechecked"] or 0) for r in rr)
        wrong = sum(1 - int(r["ours_verified"]) for r in rr)
        wrong += sum(  # a proof contradicted by the reference, the recheck or the truth
            1
            for r in ok
            if int(r["ours_claims_proof"])
            and (
                r["kind"] == "joint"  # (FK of a smooth trajectory: a path exists)
                or (r["ref_exists"] != "" and int(r["ref_exists"]))
                or not int(r["proof_rechecked"] or 0)
            )
        )
        lines.append(
            f"| {arm} | {kind} | {len(rr)} | {_share(rr, 'ref_exists')} | "
            f"{_share(ok, 'ours_ok')} | {agree} | {beyond} | {claims} ({rechecked}) | "
            f"{wrong} | "
            f"{_share(rr, 'greedy_jump_free')} | {_share(rr, 'tracik_jump_free')} | "
            f"{_share(rr, 'rtb_jump_free')} |"
        )
    lines += [
        "",
        "The greedy peers judged both ways: every waypoint reached by our check (Pinocchio, "
        f"{TOL:g} m / {TOL:g} rad, in the limits) and by the peer's own success flag at "
        "every waypoint (what its user would be told; it says nothing of jumps).",
        "",
        "| arm | kind | TRAC-IK: our check | TRAC-IK: its claim | rtb ik_LM: our check | "
        "rtb ik_LM: its claim |",
        "|---|---|---|---|---|---|",
    ]
    for arm, kind, rr in _cells(rows, arms, kinds):
        lines.append(
            f"| {arm} | {kind} | {_share(rr, 'tracik_success')} | {_share(rr, 'tracik_claimed')}"
            f" | {_share(rr, 'rtb_success')} | {_share(rr, 'rtb_claimed')} |"
        )
    lines += [
        "",
        "Reference (6R arms): every eaik branch of every waypoint with every in-limit 2π copy "
        "and a separate dynamic programme; agreement = ours finds a jump-free path exactly "
        "when the reference does; beyond the reference = ours found one (checked here) where "
        "the reference, missing the solutions eaik does not return at singular waypoints, "
        "found none. A proof claimed (`reason` says no jump-free path exists) is rechecked "
        "with the numerical branch sets added; wrong claims = answers whose success / "
        "jump-free flags the independent check contradicts, plus proofs contradicted by the "
        "reference, the recheck, or the construction (`joint` paths have a jump-free path: "
        "the trajectory they were made from).",
        "",
        "## Time",
        "",
        f"Wall-clock per path of {w} waypoints [ms] (median, p90), the process's CPU time "
        "(median: what the wall time would be on an idle core; the machine is shared) and "
        "the wall time per waypoint [ms] (median); the greedy trackers for comparison "
        "(median wall time per path).",
        "",
        "| arm | kind | ours median | ours p90 | ours CPU median | ours per waypoint | mean "
        "candidates per waypoint | greedy swarm_ik | TRAC-IK greedy | rtb greedy | "
        "exhaustive reference |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for arm, kind, rr in _cells(rows, arms, kinds):
        lines.append(
            f"| {arm} | {kind} | {_median(rr, 'ours_ms')} | {_p90(rr, 'ours_ms')} | "
            f"{_median(rr, 'ours_cpu_ms')} | {_median(rr, 'ours_ms', 1.0 / w)} | "
            f"{_median(rr, 'ours_candidates')} | "
            f"{_median(rr, 'greedy_ms')} | {_median(rr, 'tracik_ms')} | "
            f"{_median(rr, 'rtb_ms')} | {_median(rr, 'ref_ms')} |"
        )
    lines += ["", *_targets(rows)]
    pooled = []
    for arm in arms:
        rr = [r for r in rows if r["arm"] == arm]
        pooled.append(f"{arm} {_median(rr, 'ours_ms')} ms ({_median(rr, 'ours_cpu_ms')} ms CPU)")
    lines += ["", "Median per path over all kinds: " + ", ".join(pooled) + "."]
    return "\n".join(lines) + "\n"


def _targets(rows: list[dict[str, Any]]) -> list[str]:
    """The issue's targets against the rows: 6R arms (a jump-free path whenever the
    exhaustive reference finds one, no wrong claim, ≤ 200 ms median per 40-waypoint path) and
    redundant arms (every FK-of-trajectory path jump-free, ≤ 1 s per 40 waypoints)."""
    six = [r for r in rows if r["ref_exists"] != ""]
    red = [r for r in rows if r["ref_exists"] == ""]
    out = ["## Against the targets", ""]
    if six:
        exists = [r for r in six if int(r["ref_exists"])]
        found = sum(int(int(r["ours_success"]) and int(r["ours_jump_free"])) for r in exists)
        unverified = sum(1 - int(r["ours_verified"]) for r in six)
        bad_proof = sum(
            1
            for r in six
            if int(r["ours_claims_proof"])
            and (r["kind"] == "joint" or int(r["ref_exists"]) or not int(r["proof_rechecked"] or 0))
        )
        out.append(
            f"* 6R arms ({len(six)} paths): jump-free whenever the reference finds a path: "
            f"{found}/{len(exists)}; wrong claims: {unverified + bad_proof}; median "
            f"{_median(six, 'ours_ms')} ms per path ({_median(six, 'ours_cpu_ms')} ms CPU), "
            f"p90 {_p90(six, 'ours_ms')} ms."
        )
    if red:
        fk = [r for r in red if r["kind"] == "joint"]
        ok = sum(int(int(r["ours_success"]) and int(r["ours_jump_free"])) for r in fk)
        out.append(
            f"* Redundant arms ({len(red)} paths): FK-of-trajectory paths jump-free: "
            f"{ok}/{len(fk)}; median {_median(fk, 'ours_ms')} ms per path on them "
            f"({_median(fk, 'ours_cpu_ms')} ms CPU), {_median(red, 'ours_ms')} ms over all "
            f"kinds (p90 {_p90(red, 'ours_ms')} ms)."
        )
    return out


def run(args: argparse.Namespace) -> int:
    """Run the benchmark; returns the exit code."""
    if args.quick:
        args.n = min(args.n, 10)
    out = common.resolve_out(args.out, "path", args.quick)
    if args.from_csv:
        import json

        info = json.loads((out / common.RUN_INFO).read_text())
        args.n, args.waypoints = info.get("n", args.n), info.get("waypoints", args.waypoints)
        rows_read: list[dict[str, Any]] = list(common.read_csv(out / "paths.csv"))
        kept = (out / "path.md").read_text().split("Machine: ", 1)[-1].split(".\n", 1)[0]
        return common.write_report(out / "path.md", summarize(rows_read, args, kept))
    common.check_robots(args.arms)  # a bad name refused before the folder is made
    out.mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, Any]] = []
    t0 = time.perf_counter()
    for arm in args.arms:
        rows += run_arm(arm, args.kinds, args.n, args.waypoints, args.seed, not args.no_peers)
    common.write_csv(out / "paths.csv", FIELDS, rows)
    load = f"{common.load_line()}, {time.perf_counter() - t0:.0f} s in all"
    common.write_run_info(out, "path", args.quick, n=args.n, waypoints=args.waypoints)
    return common.write_report(out / "path.md", summarize(rows, args, load))


main = common.module_main(add_arguments, run, "path", __doc__)


if __name__ == "__main__":
    raise SystemExit(main())
