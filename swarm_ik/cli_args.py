"""Command-line options shared by several sub-commands (one definition each)."""

from __future__ import annotations

from typing import Any

POSE_HELP = "target position [m] and quaternion qx qy qz qw (x y z w order)"


def add_pose(group: Any, help_text: str = POSE_HELP) -> None:
    """``--pose X Y Z QX QY QZ QW`` on a parser or a mutually exclusive group."""
    group.add_argument(
        "--pose",
        nargs=7,
        type=float,
        metavar=("X", "Y", "Z", "QX", "QY", "QZ", "QW"),
        help=help_text,
    )
