"""``swarm-ik batch``: many target poses of one robot solved at once (vectorised, optionally
on Dask).

``swarm-ik batch --robot panda --targets poses.npz --out result.npz`` solves every target of
the file (``.npz``/``.npy``/``.csv``, see :func:`swarm_ik.batch.read_targets`) and writes one
row per target (``.npz`` or ``.csv``); ``--random N`` solves N targets sampled by forward
kinematics instead (``--scene FILE``: every answer clear of the scene's obstacles and of
itself, the goal :class:`~swarm_ik.goals.AvoidCollisions` of every target; a random target's
configuration may itself be in contact, so some may be unreachable).  ``--scheduler``:
``none`` (default: this process, no Dask), ``threads`` (this process, a thread per core),
``local`` (an embedded Dask LocalCluster, one worker process per core; extra ``dask``), or a
scheduler address ``tcp://host:port``.

Exit codes: 0 all targets solved, 1 some not solved, 2 bad input (``--out`` is checked,
written to and removed, before any work), 130 interrupted.

Ctrl-C stops after the chunks already finished: their rows (the first ``k`` targets, in
order) are written to ``--out`` and the command exits with 130, printing one line.  It is
:func:`swarm_ik.batch.solve_batch` with ``keep_on_interrupt=True``: the chunks go out in waves
(one chunk at a time in-process, two per thread or Dask worker), each solved with its index in
the whole batch, so the answers are bit-identical to a plain ``solve_batch``'s.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from swarm_ik import argtypes
from swarm_ik.cli._args import (
    EXIT_INTERRUPTED,
    EXIT_NOT_REACHED,
    EXIT_OK,
    RobotCommand,
    add_collision_options,
    add_lm_options,
    add_q0,
    add_scheduler,
    check_collision_options,
    check_input_file,
    check_output_file,
    load_robot,
    target_frame_help,
)

HELP = "solve many targets at once (vectorised, optionally on Dask)"
"""One line for ``swarm-ik --help``."""
DESCRIPTION = (
    "Solve many target poses of one robot with the compiled "
    "Levenberg-Marquardt polish and restarts; writes one row per target.  Exit 0 when "
    "every target is solved, 1 when some are not, 130 on Ctrl-C (the finished rows are "
    "written)."
)
"""The top of ``swarm-ik batch --help``."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``swarm-ik batch`` after the robot's (see :func:`run`)."""
    src = parser.add_mutually_exclusive_group(required=True)
    src.add_argument(
        "--targets",
        type=Path,
        metavar="FILE",
        help="targets: .npz/.npy ((N,4,4) or (N,7) array) or .csv "
        "(x,y,z,qx,qy,qz,qw or 16 matrix columns); with --position-only also points "
        "((N,3), or .csv columns x,y,z)",
    )
    src.add_argument(
        "--random",
        type=int,
        metavar="N",
        help="N targets = FK of configurations drawn uniformly within the limits",
    )
    parser.add_argument(
        "--out",
        type=Path,
        required=True,
        metavar="FILE",
        help="result file: .npz (q, errors, success, ...) or .csv; its folder must exist and "
        "be writable, and it may not be --targets or --scene (checked before solving)",
    )
    add_q0(parser, "first start for every target (one value per joint); default mid-range")
    parser.add_argument(
        "--position-only", action="store_true", help="ignore the target orientation"
    )
    parser.add_argument("--chunk-size", type=int, default=None, help="targets per task")
    argtypes.add_seed(parser, "seed of the restarts (and of sampled targets)")
    add_lm_options(
        parser,
        128,
        "most LM starts per target's search, the seed included (with --scene an answer in "
        "contact is searched for again, in a few times this many more starts: "
        "swarm_ik.solve_batch's max_starts)",
    )
    parser.add_argument(
        "--max-evals",
        type=int,
        default=None,
        help="most FK + Jacobian evaluations per target, over all its starts (default: the "
        "starts alone bound them)",
    )
    parser.add_argument(
        "--time-limit",
        type=argtypes.positive_number,
        default=None,
        metavar="SECONDS",
        help="seconds for the whole batch: targets not reached by then are reported unsolved "
        "(reading or drawing the targets and loading the kernels, a scene and a Dask cluster "
        "are charged to it up to half of it; writing --out follows it: about 3 s per million "
        "targets in .npz)",
    )
    add_collision_options(
        parser,
        "obstacles every answer must be clear of (and of itself)",
        "with --scene: SRDF of disabled self-collision pairs (default: found)",
    )
    add_scheduler(parser)
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


add_parser = RobotCommand(
    "batch", add_arguments, HELP, DESCRIPTION, frame_help=target_frame_help("the targets")
)
"""Add ``batch`` to the ``swarm-ik`` sub-parsers."""


def run(args: argparse.Namespace) -> int:
    """``swarm-ik batch``; returns the exit code."""
    t_call = time.perf_counter()
    import numpy as np

    import swarm_ik
    from swarm_ik.batch import BLOCK, MAX_TARGETS, read_targets_file, solve_batch
    from swarm_ik.errors import InvalidArgumentError

    inputs = (("--targets", args.targets), ("--scene", args.scene))
    check_output_file(args.out, "--out", (".csv", ".npz"), inputs)  # before any work
    check_collision_options(args)
    if args.random is not None and not 1 <= args.random <= MAX_TARGETS:
        raise InvalidArgumentError(
            f"--random must be a count from 1 to {MAX_TARGETS} (swarm_ik.batch.MAX_TARGETS), "
            f"got {args.random}"
        )
    if args.targets is not None:
        check_input_file(args.targets, "--targets", None)
    robot = load_robot(args, srdf=args.srdf)  # (every --frame; the targets: the first's)
    goals = None
    if args.scene is not None:  # (the scene read before the targets are drawn)
        goals = [
            swarm_ik.goals.AvoidCollisions(
                swarm_ik.Scene.load(args.scene), self_collision=not args.no_self_collision
            )
        ]
    if args.targets is not None:
        targets = read_targets_file(args.targets, positions=args.position_only)
        source = str(args.targets)
        if len(targets) == 0:
            raise InvalidArgumentError(f"--targets {args.targets}: the file holds no targets")
    else:
        rng = np.random.default_rng(args.seed)
        # drawn and FK'd a block at a time: a Ctrl-C is answered between blocks, not after
        # millions of targets
        targets = np.empty((args.random, 4, 4))
        for a in range(0, args.random, BLOCK):
            m = min(BLOCK, args.random - a)
            targets[a : a + m] = robot.fk(robot.random_q(rng, m))
        source = f"{args.random} FK-sampled targets (seed {args.seed})"
    time_limit = args.time_limit
    if time_limit is not None:  # (the targets read or drawn: charged up to half of it, as the
        # kernels' loading is inside solve_batch)
        time_limit = max(time_limit - (time.perf_counter() - t_call), 0.5 * time_limit)
    res = solve_batch(
        robot,
        targets,
        goals=goals,
        seed=args.seed,
        q0=args.q0,
        tol_pos=args.tol_pos,
        tol_rot=args.tol_rot,
        position_only=args.position_only,
        max_starts=args.max_starts,
        max_iters=args.max_iters,
        max_evals=args.max_evals,
        time_limit=time_limit,
        scheduler=args.scheduler,
        chunk_size=args.chunk_size,
        progress=not args.no_progress and sys.stderr.isatty(),
        keep_on_interrupt=True,
    )
    if res.interrupted:  # (the line first, then the rows, uncompressed: at once)
        if res.n:
            kept = f"writing the {res.n} finished targets (of {len(targets)}) to {args.out}"
        else:
            kept = "no chunk had finished; nothing written"
        print(f"swarm-ik: interrupted; {kept}", file=sys.stderr, flush=True)
        if res.n:
            try:
                res.save(args.out, targets=targets[: res.n], compress=False)
            except KeyboardInterrupt:  # (a second Ctrl-C: the write given up, the file as it was)
                print(f"swarm-ik: interrupted again; {args.out} not written", file=sys.stderr)
        return EXIT_INTERRUPTED
    res.save(args.out, targets=targets)
    n_ok = int(res.success.sum())
    print(f"robot {robot.name} ({robot.nq} joints), frame {robot.ee_frame}; targets: {source}")
    rot = "" if args.position_only else f" / {args.tol_rot:g} rad"
    if goals is not None:
        rot += f", clear of {args.scene} (coal's check)"
    not_started = int((res.n_starts == 0).sum())
    rate = (  # (a target the time limit left unstarted is no pose solved per second)
        f"{res.poses_per_s:.0f} poses/s"
        if not not_started
        else f"{(res.n - not_started) / res.time_s if res.time_s > 0 else 0.0:.0f} targets "
        "started per s"
    )
    print(
        f"solved {n_ok}/{res.n} ({100 * res.success_rate:.2f} %) within "
        f"{args.tol_pos:g} m{rot} in {res.time_s:.3f} s "
        f"({rate}, scheduler {args.scheduler}"
        + (f", of which {res.setup_s:.2f} s cluster start-up)" if res.setup_s > 0.01 else ")")
    )
    if res.n:
        print(
            f"LM evaluations per target: mean {res.n_evals.mean():.1f}, starts per target: "
            f"mean {res.n_starts.mean():.2f}"
        )
        if not_started:
            print(f"{not_started} targets not started before --time-limit (counted unsolved)")
        out_of_reach = int((res.reason == "unreachable").sum())
        if out_of_reach:
            print(
                f"{out_of_reach} targets out of reach (beyond the frame's reach, inside an "
                "obstacle, or a goal no joint vector meets)"
            )
    print(f"wrote {args.out}")
    return EXIT_OK if n_ok == res.n else EXIT_NOT_REACHED
