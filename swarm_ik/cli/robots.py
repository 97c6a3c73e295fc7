"""``swarm-ik robots``: the robots loadable by name, bundled and from example-robot-data."""

from __future__ import annotations

import argparse
from typing import Any


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``robots`` to the ``swarm-ik`` sub-parsers."""
    return subparsers.add_parser(  # type: ignore[no-any-return]
        "robots",
        help="list the robots loadable by name",
        description="List the robots that --robot takes by name: the bundled ones (robots/) "
        "and those of example-robot-data, with their end-effector (goal) frames.  Any other "
        "robot is given as a path to its .urdf file.",
    )


def run(args: argparse.Namespace) -> int:
    """Print the robot names; returns 0."""
    from swarm_ik.paths import BUNDLED, EXAMPLE_ROBOTS, example_robot_files

    print("bundled (robots/):")
    for name, (fname, frame) in sorted(BUNDLED.items()):
        print(f"  {name:28s} {fname}  (end effector: {frame})")
    print("example-robot-data:")
    for name, (rel, frames) in sorted(EXAMPLE_ROBOTS.items()):
        shown = frames if isinstance(frames, str) else ", ".join(frames)
        print(f"  {name:28s} {rel}  (goal frames: {shown})")
    others = {k: v for k, v in example_robot_files().items() if k not in EXAMPLE_ROBOTS}
    if others:
        print("example-robot-data, any other file by name (goal frame: the tip of the deepest")
        print(
            "chain unless --frame; legged robots, humanoids and free-flying robots such as "
            "iris_simple and quadrotor_base: add --floating-base):"
        )
        for name, rel in sorted(others.items()):
            print(f"  {name:28s} {rel}")
    return 0
