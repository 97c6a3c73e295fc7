"""The viewer's part of the command line, shared by ``swarm-ik show`` and the
``--show/--animate/--html/--compare`` options of ``swarm-ik solve``.

``--show`` (and ``show`` without ``--html``) starts meshcat's local server, prints its URL and
keeps it up while someone can look at it:

* on a terminal (stdin a TTY): until Enter or Ctrl-C, or at most ``--show-wait SECONDS``;
* with no terminal (a script, a pipe, CI): the command returns right after printing the URL
  (the server stops with it) unless ``--show-wait SECONDS`` asks to keep it up that long
  (``--show-wait inf``: until Ctrl-C or SIGTERM); it never blocks on a stdin nobody types in;
* ``SWARM_IK_NO_WAIT=1`` returns at once in every case (for scripts and tests).

``--html FILE`` writes one self-contained page that any browser opens without a server.
``solve --animate`` or ``--compare`` without ``--html`` or ``--show`` draws nothing: it says
so on stderr and returns.  Everything that can be refused is refused before solving: meshcat
missing, an output page that cannot be written, and meshes of the robot that cannot be found
(all of them named in one line).
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

from swarm_ik.cli._args import check_output_file, non_negative_seconds, solve_kwargs
from swarm_ik.errors import RobotModelError

NO_WAIT_ENV = "SWARM_IK_NO_WAIT"
"""Environment variable: when set (to anything but ``0`` or empty), the live viewer is not
kept open (the command returns right after printing the URL)."""

HTML_SUFFIXES = (".html", ".htm")

SHOW_WAIT_HELP = (
    "keep the live viewer up at most SECONDS (inf: until Ctrl-C).  Default: until Enter on a "
    "terminal; with no terminal (stdin not a TTY) the command returns right after printing "
    "the URL, and the viewer closes with it"
)


def add_show_wait(parser: Any) -> None:
    """``--show-wait SECONDS`` (for any command that can keep the live viewer up)."""
    parser.add_argument(
        "--show-wait",
        type=non_negative_seconds,
        default=None,
        metavar="SECONDS",
        help=SHOW_WAIT_HELP,
    )


def _say(args: argparse.Namespace, text: str) -> None:
    """Print a viewer message: on stdout, or stderr when stdout carries JSON."""
    print(text, file=sys.stderr if getattr(args, "json", False) else sys.stdout, flush=True)


# ------------------------------------------------------------------ checks before the work
def check_viewer(args: argparse.Namespace, *, live: bool) -> None:
    """What drawing needs, checked before any solve: meshcat installed (when a page or the
    live viewer is wanted) and ``--html`` writable as an ``.html``/``.htm`` file.

    Raises:
        VizUnavailableError: meshcat is missing (the message names the extra).
        InvalidArgumentError: ``--html`` cannot be written.
    """
    html = getattr(args, "html", None)
    if html is not None:  # (an empty path too: refused there, not taken as no page)
        check_output_file(html, "--html", HTML_SUFFIXES)
    if html or live:
        from swarm_ik import viz

        viz.require_meshcat()


def _mesh_found(filename: str, dirs: list[str]) -> bool | None:
    """Whether Pinocchio's resolver would find a mesh ``filename`` of the URDF: a
    ``package://PKG/REL`` in ``DIR/PKG/REL`` for one of the search folders, a ``file://`` or
    absolute path as it is, a relative one under one of the folders (the URDF's first);
    ``None`` for another kind of address (not judged)."""
    if filename.startswith("package://"):
        rel = filename[len("package://") :]
        return any((Path(d) / rel).is_file() for d in dirs)
    if filename.startswith("file://"):
        return Path(filename[len("file://") :]).is_file()
    if "://" in filename:
        return None
    p = Path(filename)
    if p.is_absolute():
        return p.is_file()
    return any((Path(d) / p).is_file() for d in dirs)


def missing_meshes(urdf_path: str | os.PathLike[str], dirs: list[str]) -> tuple[list[str], int]:
    """The visual meshes of a URDF that cannot be found in ``dirs``, and how many distinct
    meshes it names (read from the XML and looked for, nothing loaded)."""
    try:
        root = ET.parse(urdf_path).getroot()
    except (ET.ParseError, OSError):
        return [], 0
    names = {
        m.get("filename", "")
        for visual in root.iter("visual")
        for m in visual.iter("mesh")
        if m.get("filename")
    }
    return sorted(n for n in names if _mesh_found(n, dirs) is False), len(names)


def check_meshes(robot: Any, what: str) -> None:
    """Refuse, before any work, a robot whose visual meshes cannot all be found, with one
    line naming how many and which (Pinocchio would stop at the first, and only when the
    scene is drawn, after the solve).

    The URDF's mesh addresses are looked for first (fast, nothing loaded); only when some
    seem missing is the visual geometry loaded to confirm it, so a mesh this look-up misses
    but Pinocchio finds is never refused.

    Raises:
        RobotModelError: ``what`` (the options asking for a drawing), the count and names of
            the meshes not found, and where they were searched.
    """
    from swarm_ik import viz

    dirs = viz.package_dirs(robot)
    missing, total = missing_meshes(robot.urdf_path, dirs)
    if not missing:
        return
    try:
        viz.visual_model(robot)
    except RobotModelError:
        pass
    else:
        return  # found after all
    shown = ", ".join(missing[:10])
    if len(missing) > 10:
        shown += f" and {len(missing) - 10} more"
    raise RobotModelError(
        f"{what}: {len(missing)} of the {total} meshes of robot {robot.name!r} cannot be "
        f"found: {shown}; searched {', '.join(dirs)} (add the folder holding their package to "
        "ROS_PACKAGE_PATH)"
    )


# ------------------------------------------------------------------------- keep it open
def wait(args: argparse.Namespace) -> None:
    """Keep the process (and so meshcat's server) alive while someone may look (module
    docstring); never blocks on a stdin that is not a terminal."""
    if os.environ.get(NO_WAIT_ENV, "") not in ("", "0"):
        return
    limit: float | None = getattr(args, "show_wait", None)
    tty = sys.stdin is not None and sys.stdin.isatty()
    if not tty and limit is None:
        _say(
            args,
            "no terminal to wait on (stdin is not a TTY): the viewer closes now; "
            "--show-wait SECONDS keeps it up, --html FILE writes a page that needs no server",
        )
        return
    if limit == 0:
        return

    def stop(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt

    installed = True
    try:  # a SIGTERM ends the wait like Ctrl-C, so that meshcat's server is stopped too
        previous = signal.signal(signal.SIGTERM, stop)
    except ValueError:  # not the main thread
        installed, previous = False, None
    try:
        if tty or limit is None:
            _wait_for_enter(args, limit)
        else:
            until = "until Ctrl-C" if math.isinf(limit) else f"for {limit:g} s (Ctrl-C closes it)"
            _say(args, f"the viewer stays up {until}")
            _sleep(limit)
    except (KeyboardInterrupt, EOFError):  # Ctrl-C (or SIGTERM) is how the viewer closes:
        pass  # the command then exits with its own outcome (0, or 1 for solve's "not reached")
    finally:
        if installed:
            signal.signal(signal.SIGTERM, signal.SIG_DFL if previous is None else previous)


def _sleep(seconds: float) -> None:
    end = time.monotonic() + seconds
    while True:
        left = end - time.monotonic()
        if left <= 0:
            return
        time.sleep(min(left, 3600.0))


def _wait_for_enter(args: argparse.Namespace, limit: float | None) -> None:
    if limit is None or math.isinf(limit):
        input("press Enter to close the viewer ")
        return
    import select

    print(f"press Enter to close the viewer (it closes by itself in {limit:g} s) ", end="")
    sys.stdout.flush()
    try:
        select.select([sys.stdin], [], [], limit)
    except (OSError, ValueError):  # stdin not selectable (Windows): the time limit alone
        _sleep(limit)
    print()


def present(scene: Any, args: argparse.Namespace, *, live: bool) -> None:
    """Write ``--html`` if asked; print the live URL and wait when ``live``; then close."""
    try:
        html = getattr(args, "html", None)
        if html:
            path = scene.save_html(html)
            size = path.stat().st_size / 1e6
            _say(
                args, f"wrote {path} ({size:.1f} MB): a self-contained page, open it in any browser"
            )
        if live:
            _say(args, f"meshcat viewer: {scene.url}")
            if getattr(args, "open", False):
                import webbrowser

                webbrowser.open(scene.url, new=2)
            wait(args)
    finally:
        scene.close()


def result_line(res: Any, position_only: bool = False) -> str:
    """One line describing a result (the rotation error ``n/a`` when it was not asked for)."""
    status = "reached" if res.success else "NOT reached"
    rot = "n/a" if position_only else f"{res.rotation_error:.3e} rad"
    return (
        f"{res.solver}: {status}, position error {res.position_error:.3e} m, rotation error "
        f"{rot}, {res.n_evals} evaluations, {res.time_s * 1e3:.2f} ms"
    )


# ------------------------------------------------------------------------- solve hook
def wants_drawing(args: argparse.Namespace) -> bool:
    """Whether ``swarm-ik solve`` draws anything (``--html`` or ``--show``)."""
    return args.html is not None or bool(args.show)


def after_solve(args: argparse.Namespace, problem: Any, result: Any) -> None:
    """Called by ``swarm-ik solve`` when one of ``--show/--animate/--html/--compare`` is given
    (the viewer and the meshes were checked before solving, :func:`check_viewer`,
    :func:`check_meshes`).

    ``--animate`` solves again with the same options and seed, recording the best-so-far
    configuration of every iteration (:func:`swarm_ik.viz.solve_traced`); ``--compare SOLVER``
    solves the target with SOLVER too and draws its answer ghosted.  Without ``--html`` or
    ``--show`` there is nowhere to draw: a note on stderr, and nothing else is done.
    """
    if not wants_drawing(args):
        print(
            "swarm-ik: note: --animate/--compare draw a scene; add --html FILE to write it or "
            "--show to open the live viewer (nothing drawn)",
            file=sys.stderr,
        )
        return
    import numpy as np

    from swarm_ik import viz

    kwargs = solve_kwargs(args)
    trace = None
    if args.animate:
        traced, trace = viz.solve_traced(problem, args.solver, **kwargs, **dict(args.param))
        if not np.allclose(traced.q, result.q):  # e.g. a time limit cut the runs differently
            _say(
                args,
                "note: the recorded run ended elsewhere than the one printed; showing "
                "the recorded one",
            )
            result = traced
        _say(
            args,
            f"animation: best-so-far configuration over {len(trace.fitness)} iterations "
            f"({trace.improvements} improvements)",
        )
    compare = None
    if args.compare:
        import swarm_ik

        compare = swarm_ik.solve(problem, args.compare, **kwargs)
        _say(args, "compare " + result_line(compare, args.position_only))
    scene = viz.show_result(problem, result, trace=trace, compare=compare)
    col = getattr(problem, "collision_goal", None)
    if col is not None:  # the obstacles, and what is in contact in red
        report = next((e.details for e in result.goal_errors if e.goal == "AvoidCollisions"), None)
        named = set() if report is None else {n for p in report.pairs_in_contact for n in p}
        viz.add_obstacles(scene, col.scene, [n for n in col.scene.names if n in named])
        if named - set(col.scene.names):
            viz.add_contact_bodies(scene, problem.robot, result.q, sorted(named))
    present(scene, args, live=bool(args.show))
