"""``swarm-ik reach``: a reachability map of a robot on a voxel grid (:mod:`swarm_ik.reach`),
written as ``.npz``, a PNG of three slices and (with meshcat installed) an HTML point cloud.

Everything that can be refused is refused before the work: non-finite or inverted
``--bounds``, a grid too large, an output asked for by name (``--png FILE``, ``--html FILE``)
whose extra is missing, output files that cannot be written (each folder tried), meshes of
the robot that cannot be found for the HTML page.  A picture or page not asked for by name
whose extra is missing (matplotlib, meshcat) is skipped, with one line on stderr saying so
and what to install, printed when the checks are done.  Exit codes: 0 the files are
written, 2 bad input, 130 interrupted.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

from swarm_ik import argtypes
from swarm_ik.argtypes import count
from swarm_ik.cli import _viewer
from swarm_ik.cli._args import (
    EXIT_OK,
    RobotCommand,
    add_lm_options,
    add_scheduler,
    check_output_file,
    load_robot,
    target_frame_help,
)
from swarm_ik.errors import InvalidArgumentError

HELP = "reachability map on a voxel grid (npz + PNG slices + HTML point cloud)"
"""One line for ``swarm-ik --help``."""
DESCRIPTION = (
    "Reachability index per voxel: the fraction of K orientations solved at "
    "its centre.  Writes the map (.npz), a PNG of three slices (needs [plot]) and an HTML "
    "point cloud (needs [viz]); every output is checked before solving.  --png/--html FILE "
    "without its extra is refused; by default a picture whose extra is missing is skipped "
    "with a note."
)
"""The top of ``swarm-ik reach --help``."""

MAX_TARGETS = 5_000_000
"""Default of ``--max-targets`` (:data:`swarm_ik.reach.MAX_TARGETS`, restated here so that
building the parser imports no numerics; a test keeps the two equal)."""

BATCH_MAX_TARGETS = 10_000_000
"""Largest ``--max-targets``: what one batch takes (:data:`swarm_ik.batch.MAX_TARGETS`,
restated likewise): a larger cap let a grid of 6·10⁷ poses be built (8.5 GB, 23 s) before
the batch refused it."""


EXTRAS = {
    "--png": ("the slices picture", "matplotlib", "plot"),
    "--html": ("the HTML page", "meshcat", "viz"),
}
"""Option of an output -> (what it writes, the module it needs, the extra that installs it)."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of ``swarm-ik reach`` after the robot's (see :func:`run`)."""
    parser.add_argument(
        "--resolution", type=float, default=0.1, help="voxel edge [m] (default 0.1)"
    )
    parser.add_argument(
        "--bounds",
        nargs=6,
        type=float,
        default=None,
        metavar=("XMIN", "YMIN", "ZMIN", "XMAX", "YMAX", "ZMAX"),
        help="workspace box [m], finite, each min below its max (default: cube around the "
        "first joint, 1.1 × the sampled reach)",
    )
    parser.add_argument(
        "--orientations",
        type=count(1),
        default=None,
        metavar="K",
        help="orientations tried per voxel (default 8, seeded random rotations; 1 with "
        "--position-only)",
    )
    parser.add_argument(
        "--position-only",
        action="store_true",
        help="map where the frame's origin can be, its orientation free (for arms of fewer "
        "than 6 joints, which reach a random full orientation almost nowhere)",
    )
    parser.add_argument(
        "--out",
        type=Path,
        metavar="FILE.npz",
        help="map file (default reach_<robot>.npz)",
    )
    for option, (what, module, extra) in EXTRAS.items():  # --png, --html and their --no-…
        parser.add_argument(
            option,
            type=Path,
            metavar=f"FILE.{option[2:]}",
            help=f"{what} (default: next to --out, skipped with a note without {module}; "
            f"needs [{extra}])",
        )
        parser.add_argument(f"--no-{option[2:]}", action="store_true", help=f"do not write {what}")
    argtypes.add_seed(parser, "seed of the orientations and restarts")
    add_lm_options(parser, 16, "most LM starts per pose")
    parser.add_argument(
        "--max-targets",
        type=count(1, BATCH_MAX_TARGETS),
        default=MAX_TARGETS,
        help=f"refuse grids of more poses (voxels × K) than this (default {MAX_TARGETS}, "
        f"at most {BATCH_MAX_TARGETS}: one batch)",
    )
    add_scheduler(parser)
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


add_parser = RobotCommand(
    "reach", add_arguments, HELP, DESCRIPTION, frame_help=target_frame_help("the map's poses")
)
"""Add ``reach`` to the ``swarm-ik`` sub-parsers."""


def has_extra(option: str) -> bool:
    """Whether the modules that write the output of ``option`` (``--png``, ``--html``) import.

    They are imported, as writing the file would import them: a package installed but
    broken, or a submodule that does not import, counts as missing (looking for the package
    alone let the command solve, then fail on writing).
    """
    try:
        if option == "--png":
            import matplotlib.pyplot  # noqa: F401  (what plot_slices draws with)
        else:
            from swarm_ik import viz

            viz.require_meshcat()  # meshcat and the submodules export_html uses
    except ImportError:  # (viz.VizUnavailableError is one)
        return False
    return True


def wanted(option: str, given: Path | None, skipped: list[str]) -> bool:
    """Whether the output of ``option`` can be written: its extra imports (:func:`has_extra`).

    When it does not, an output asked for by name (``given``) is refused; one written by
    default is skipped, the reason appended to ``skipped`` (printed before the work).

    Raises:
        InvalidArgumentError: ``given`` and the extra is missing (one line naming it).
    """
    if has_extra(option):
        return True
    what, module, extra = EXTRAS[option]
    install = f'pip install "swarm_ik[{extra}]"'
    if given is not None:
        raise InvalidArgumentError(
            f"{option} needs {module}, which is not installed: {install} (or leave out {option})"
        )
    skipped.append(
        f"{what} is skipped: it needs {module}, which is not installed ({install}; "
        f"--no-{option[2:]} skips it without this note)"
    )
    return False


def check_bounds(bounds: Any) -> tuple[list[float], list[float]]:
    """``--bounds`` as (lower, upper) corners: six finite numbers, each min below its max.

    Raises:
        InvalidArgumentError: one line naming the bad values.
    """
    values = [float(b) for b in bounds]
    lo, hi = values[:3], values[3:]
    if not all(math.isfinite(v) for v in values):
        raise InvalidArgumentError(
            f"--bounds must be 6 finite numbers (XMIN YMIN ZMIN XMAX YMAX ZMAX), got {values}"
        )
    bad = [axis for axis, a, b in zip("xyz", lo, hi, strict=True) if not a < b]
    if bad:
        raise InvalidArgumentError(
            f"--bounds: each min must be below its max (XMIN YMIN ZMIN XMAX YMAX ZMAX); not on "
            f"{', '.join(bad)}: lower {lo}, upper {hi}"
        )
    return lo, hi


def run(args: argparse.Namespace) -> int:
    """``swarm-ik reach``: everything that can be refused is refused before the work (bounds,
    missing extras, output paths, a grid too large); returns 0 when the files are written."""
    import numpy as np

    from swarm_ik import _validate, reach

    if args.bounds is not None:
        bounds = check_bounds(args.bounds)
    _validate.positive_float(args.resolution, "--resolution")
    out = args.out if args.out is not None else Path(f"reach_{Path(args.robot).stem}.npz")
    out = check_output_file(out, "--out", (".npz",))
    for option, off in ((args.png, args.no_png), (args.html, args.no_html)):
        if option is not None and off:
            name = "--png" if option is args.png else "--html"
            raise InvalidArgumentError(f"{name} FILE and --no-{name[2:]} contradict: give one")
    skipped: list[str] = []  # outputs left out for a missing extra (said before the work)
    png = None
    if not args.no_png and wanted("--png", args.png, skipped):
        png = check_output_file(args.png or out.with_suffix(".png"), "--png", (".png",))
    html = None
    if not args.no_html and wanted("--html", args.html, skipped):
        html = check_output_file(
            args.html or out.with_suffix(".html"), "--html", _viewer.HTML_SUFFIXES
        )
    robot = load_robot(args)  # (every --frame; the map: the first's)
    if html is not None:
        _viewer.check_meshes(robot, "reach --html (--no-html skips the page)")
    # the grid's size is checked before anything is allocated; default_bounds with the same
    # seed is what reach_map would compute itself, so the map is the same
    if args.bounds is not None:
        lo, hi = np.asarray(bounds[0], float), np.asarray(bounds[1], float)
    else:
        lo, hi = reach.default_bounds(robot, seed=args.seed)
    k = reach.orientation_count(args.orientations, args.position_only, "--position-only")
    # (the poses' cap first: its finest resolution fits the voxels' cap too, where the
    # voxels' suggested one was then refused for its poses)
    reach.check_grid_size(lo, hi, args.resolution, k, args.max_targets)
    _validate.check_grid_size(lo, hi, args.resolution)
    if robot.nq < 6 and not args.position_only:
        skipped.append(
            f"note: {robot.name} has {robot.nq} joints, so a random full orientation is out "
            "of its reach almost everywhere; --position-only maps its positions"
        )
    if skipped:  # every check passed: one line, then the work
        print("swarm-ik reach: " + "; ".join(skipped), file=sys.stderr, flush=True)
    rmap = reach.reach_map(
        robot,
        resolution=args.resolution,
        bounds=np.concatenate([lo, hi]),
        seed=args.seed,
        tol_pos=args.tol_pos,
        tol_rot=args.tol_rot,
        max_starts=args.max_starts,
        max_iters=args.max_iters,
        scheduler=None if args.scheduler in (None, "none") else args.scheduler,
        progress=not args.no_progress and sys.stderr.isatty(),
        max_targets=args.max_targets,
        n_orientations=k,
        position_only=args.position_only,
    )
    written = [str(rmap.save(out))]
    if png is not None:
        written.append(str(reach.plot_slices(rmap, png)))
    if html is not None:
        written.append(str(reach.export_html(rmap, html, robot=robot)))
    reachable = rmap.index > 0
    print(
        f"robot {robot.name}, frame {robot.ee_frame}: grid {rmap.index.shape} of "
        f"{rmap.resolution:g} m voxels, "
        + ("positions only" if rmap.position_only else f"K = {rmap.n_orientations} orientations")
    )
    mean = float(rmap.index[reachable].mean()) if reachable.any() else 0.0
    print(
        f"reachable voxels {int(reachable.sum())} of {int(rmap.solved.sum())} within the "
        f"chain's reach; mean index {mean:.3f} ({rmap.time_s:.1f} s)"
    )
    print("wrote " + ", ".join(written))
    return EXIT_OK
