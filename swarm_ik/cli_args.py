"""Command-line options shared by several sub-commands (one definition each)."""

from __future__ import annotations

import argparse
from typing import Any

POSE_HELP = "target position [m] and quaternion qx qy qz qw (x y z w order)"
ROBOT_HELP = "bundled or example-robot-data name, or a .urdf path"
FRAME_HELP = "end-effector frame (default: the robot's tool frame)"


def add_pose(group: Any, help_text: str = POSE_HELP) -> None:
    """``--pose X Y Z QX QY QZ QW`` on a parser or a mutually exclusive group."""
    group.add_argument(
        "--pose",
        nargs=7,
        type=float,
        metavar=("X", "Y", "Z", "QX", "QY", "QZ", "QW"),
        help=help_text,
    )


def add_robot(parser: Any, *, frame: bool = True) -> None:
    """``--robot NAME`` (required) and, with ``frame``, ``--frame NAME`` (one end-effector
    frame; ``swarm-ik solve`` defines its own, repeatable)."""
    parser.add_argument("--robot", required=True, help=ROBOT_HELP)
    if frame:
        parser.add_argument("--frame", default=None, help=FRAME_HELP)


def add_tolerances(parser: Any) -> None:
    """``--tol-pos M`` and ``--tol-rot RAD`` (default 1e-5 each)."""
    parser.add_argument("--tol-pos", type=float, default=1e-5, help="position tolerance [m]")
    parser.add_argument("--tol-rot", type=float, default=1e-5, help="rotation tolerance [rad]")


def solve_kwargs(args: argparse.Namespace) -> dict[str, Any]:
    """The options of ``swarm-ik solve`` that :func:`swarm_ik.solve` takes (no solver params)."""
    return {
        "seed": args.seed,
        "max_evals": args.max_evals,
        "time_limit": args.time_limit,
        "q0": args.q0,
        "tol_pos": args.tol_pos,
        "tol_rot": args.tol_rot,
    }
