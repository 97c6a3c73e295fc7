"""``swarm-ik path``: a jump-free joint path through Cartesian waypoints
(:func:`swarm_ik.path.solve_path`).

``swarm-ik path --robot ur5 --poses poses.csv --out q.csv`` reads the waypoints (``.npz`` /
``.npy``: an ``(N, 4, 4)`` or ``(N, 7)`` array; ``.csv``: ``x,y,z,qx,qy,qz,qw`` or 16 matrix
columns, as ``swarm-ik batch --targets``), solves them with ``max_joint_step`` (``--max-step``:
one value, or one per joint), prints one line per jump and the reason, and writes the joint
path (``--out``: ``.csv`` with a header of joint names, or ``.npy``); ``--html FILE`` writes a
page stepping through the path (needs ``[viz]``).

Exit codes: 0 every waypoint reached and no jump, 1 not (the path found is still written and
the reason printed), 2 bad input (``--out`` and ``--html`` are checked before any work), 130
interrupted.

:func:`run_cli` is :func:`run` (the name the path issue asked for).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from swarm_ik import argtypes
from swarm_ik.cli._args import (
    EXIT_NOT_REACHED,
    EXIT_OK,
    RobotCommand,
    add_q0,
    add_tolerances,
    check_input_file,
    check_output_file,
    input_file,
    load_robot,
    target_frame_help,
)
from swarm_ik.errors import InvalidArgumentError

HELP = "a jump-free joint path through Cartesian waypoints"
"""One line for ``swarm-ik --help``."""
DESCRIPTION = (
    "Solve a path of end-effector poses so that no joint moves more than "
    "--max-step between consecutive waypoints (every IK branch considered; on 6R arms "
    "with a closed form a path with jumps proves that none without exists).  Exit 0 when "
    "every waypoint is reached without a jump, 1 otherwise (the path found is written and "
    "the reason printed)."
)
"""The top of ``swarm-ik path --help``."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``swarm-ik path`` after the robot's (see :func:`run`)."""
    parser.add_argument(
        "--poses",
        type=Path,
        required=True,
        metavar="FILE",
        help="waypoints: .npz/.npy ((N,4,4) or (N,7) array) or .csv (x,y,z,qx,qy,qz,qw or 16 "
        "matrix columns), N >= 2",
    )
    parser.add_argument(
        "--max-step",
        nargs="+",
        type=float,
        default=[0.2],
        metavar="STEP",
        help="largest joint change between consecutive waypoints [rad, or m for prismatic "
        "joints]: one value, or one per joint (default 0.2)",
    )
    add_q0(parser, "current joint values (one per joint)")
    parser.add_argument(
        "--scene",
        default=None,
        type=input_file,
        metavar="FILE",
        help="obstacles (JSON, cuRobo .yml, MoveIt .scene or URDF; docs/scenes.md): every "
        "waypoint collision-free (self and scene)",
    )
    parser.add_argument(
        "--densify",
        type=int,
        default=0,
        metavar="K",
        help="check each step through K interpolated poses (default 0)",
    )
    argtypes.add_seed(parser, "seed")
    parser.add_argument(
        "--time-limit",
        type=float,
        default=None,
        help="seconds for the whole call (waypoints not solved by then: held, not reached); "
        "the poses are validated and the answers checked in any case, about 45 us a waypoint, "
        "so a limit shorter than that is overrun (100,000 waypoints: about 4.5 s)",
    )
    parser.add_argument(
        "--max-evals",
        type=int,
        default=None,
        help="most FK + Jacobian evaluations for the whole path, over every solve it runs "
        "(the same path for a seed, unlike --time-limit)",
    )
    add_tolerances(parser)
    parser.add_argument(
        "--out",
        type=Path,
        default=None,
        metavar="FILE",
        help="joint path: .csv or .npy (not --poses or --scene)",
    )
    parser.add_argument(
        "--html",
        type=Path,
        default=None,
        metavar="FILE",
        help="write a page stepping through the path (.html; needs [viz])",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")


add_parser = RobotCommand(
    "path", add_arguments, HELP, DESCRIPTION, frame_help=target_frame_help("the waypoints")
)
"""Add ``path`` to the ``swarm-ik`` sub-parsers."""


def run(args: argparse.Namespace) -> int:
    """``swarm-ik path``; returns the exit code."""
    import numpy as np

    import swarm_ik
    from swarm_ik.cli import _viewer
    from swarm_ik.path import solve_path

    if args.out is not None:
        inputs = (("--poses", args.poses), ("--scene", args.scene))
        check_output_file(args.out, "--out", (".csv", ".npy"), inputs)  # before any work
    if args.html is not None:
        _viewer.check_viewer(args, live=False)
    if not check_input_file(args.poses, "--poses", None).exists():
        raise InvalidArgumentError(f"--poses file not found: {str(args.poses)!r}")
    robot = load_robot(args)  # (every --frame; the waypoints: the first's)
    if args.html is not None:
        _viewer.check_meshes(robot, "--html")
    poses = _read_poses(args.poses)
    step = args.max_step[0] if len(args.max_step) == 1 else args.max_step
    scene = None if args.scene is None else swarm_ik.Scene.load(args.scene)
    res = solve_path(
        robot, poses, max_joint_step=step, q0=args.q0, scene=scene, seed=args.seed,
        densify=args.densify, time_limit=args.time_limit, max_evals=args.max_evals,
        tol_pos=args.tol_pos, tol_rot=args.tol_rot,
    )  # fmt: skip
    if args.out is not None:
        _write(args.out, robot, res.q)
    if args.json:
        print(json.dumps(_as_dict(robot, res, args.out)))
    else:
        print(
            f"robot {robot.name} ({robot.nq} joints), {res.q.shape[0]} waypoints from "
            f"{args.poses}: {'reached' if res.success else 'NOT all reached'}, "
            f"{'jump-free' if res.jump_free else 'with jumps'}, largest step "
            f"{res.max_step:.4g}, {res.time_s * 1e3:.1f} ms"
        )
        for i, size in res.reconfigurations:
            print(f"  jump into waypoint {i}: {size:.4g}")
        print(res.reason)
        if args.out is not None:
            print(f"wrote {args.out}")
    if args.html is not None:
        from swarm_ik import viz

        scene_v = viz.show_configurations(
            robot, list(res.q), target=poses[0] if np.ndim(poses) == 3 else None,
            lines=[f"{robot.name}: {res.q.shape[0]} waypoints", res.reason[:80]],
            layout="steps", hold_s=0.1,
        )  # fmt: skip
        _viewer.present(scene_v, args, live=False)
    return EXIT_OK if res.success and res.jump_free else EXIT_NOT_REACHED


run_cli = run
"""The handler (``run``, under the name the path issue asked for)."""


def _read_poses(path: Path) -> Any:
    """The waypoints of ``--poses``, read as ``swarm-ik batch --targets`` reads its file."""
    from swarm_ik.batch import read_targets_file

    return read_targets_file(path)


def _write(path: Path, robot: Any, q: Any) -> None:
    """The joint path as ``.npy`` or ``.csv`` (a header of joint names)."""
    import numpy as np

    from swarm_ik.paths import written_in_place_of

    with written_in_place_of(path) as part:  # (never a partial file)
        if path.suffix.lower() == ".npy":
            with part.open("wb") as f:  # (a file object: numpy adds no suffix to it)
                np.save(f, q)
        else:
            np.savetxt(part, q, delimiter=",", header=",".join(robot.joint_names), comments="")


def _as_dict(robot: Any, res: Any, out: Path | None) -> dict[str, Any]:
    """The JSON report."""
    return {
        "robot": robot.name,
        "joint_names": list(robot.joint_names),
        "success": res.success,
        "jump_free": res.jump_free,
        "reconfigurations": [[i, s] for i, s in res.reconfigurations],
        "max_step": res.max_step,
        "exhaustive": res.exhaustive,
        "status": res.status,
        "reason": res.reason,
        "time_s": res.time_s,
        "n_evals": res.n_evals,
        "position_errors": [float(v) for v in res.position_errors],
        "rotation_errors": [float(v) for v in res.rotation_errors],
        "q": [[float(v) for v in row] for row in res.q],
        "out": None if out is None else str(out),
    }
