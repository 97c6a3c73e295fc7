"""Reachability maps: which points of the workspace the end effector reaches, and in how many
orientations.

:func:`reach_map` lays a voxel grid over the workspace, tries the same ``K`` orientations
(uniform random rotations, seeded) at the centre of every voxel with
:func:`swarm_ik.solve_batch`, and stores the *reachability index* of each voxel: the fraction
of the ``K`` orientations solved (Zacharias, Borst & Hirzinger, "Capturing robot workspace
structure: representing robot capabilities", IROS 2007, define the index the same way over a
sphere of directions).  The index is a lower bound: a pose counts as unreachable when
``max_starts`` starts of the compiled Levenberg–Marquardt polish all fail.

Voxels whose centre lies farther from the first joint than the sum of the chain's link
lengths (plus the prismatic strokes) cannot be reached and are not solved (index 0).  The
default bounds are a cube around the first joint, 1.1 × the largest distance of the end
effector from it over random configurations.

Pictures: :func:`plot_slices` (matplotlib heat maps of three orthogonal slices through the
first joint) and :func:`export_html` (a self-contained meshcat page with the reachable voxels
as a coloured point cloud; needs ``meshcat``).  The command line ``swarm-ik reach`` is
:mod:`swarm_ik.cli.reach`.
"""

from __future__ import annotations

import reprlib
import time
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarm_ik import batch
from swarm_ik._validate import (
    SEED_LIMIT,
    count,
    finest_edge,
    flag,
    floats_or,
    positive_float,
    size_text,
)  # fmt: skip
from swarm_ik.batch import solve_batch
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.kernels.fk import PRISMATIC
from swarm_ik.paths import written_in_place_of
from swarm_ik.robot import RobotModel

FloatArray = NDArray[np.float64]

MAX_TARGETS = 5_000_000
"""Default most poses of one map (voxels × K): the targets alone take 128 bytes each
(640 MB), and at some 25,000 poses/s on one core the solve takes minutes."""


@dataclass(frozen=True)
class ReachMap:
    """A reachability map on a regular voxel grid.

    Attributes:
        robot: Robot name.
        ee_frame: End-effector frame.
        urdf: The robot's URDF file (absolute path; empty in maps written before it was
            kept), from which :func:`export_html` draws the robot: its name alone may name
            another robot (a user's ``panda.urdf`` beside the bundled Panda).
        x: Voxel centres along x [m], shape ``(nx,)``.
        y: Voxel centres along y [m], shape ``(ny,)``.
        z: Voxel centres along z [m], shape ``(nz,)``.
        index: Reachability index per voxel (fraction of orientations solved, 0–1),
            shape ``(nx, ny, nz)``.
        solved: Whether each voxel was solved (False: beyond the chain's reach), same shape.
        hits: Which orientations were reached at each voxel, shape ``(nx, ny, nz, K)``.
        orientations: The rotations tried at every voxel, shape ``(K, 3, 3)``.
        resolution: Voxel edge [m].
        base: Position of the first joint [m], shape ``(3,)``.
        seed: Seed of the orientations and of the solver.
        tol_pos: Position tolerance [m]; ``tol_rot``: rotation tolerance [rad].
        max_starts: Starts per pose before it counts as unreachable.
        time_s: Wall-clock seconds of the computation.
        position_only: The voxels' centres were solved as positions, the frame's orientation
            free (``orientations`` is then the identity alone, K = 1).
    """

    robot: str
    ee_frame: str
    urdf: str
    x: FloatArray
    y: FloatArray
    z: FloatArray
    index: FloatArray
    solved: NDArray[np.bool_]
    hits: NDArray[np.bool_]
    orientations: FloatArray
    resolution: float
    base: FloatArray
    seed: int
    tol_pos: float
    tol_rot: float
    max_starts: int
    time_s: float
    position_only: bool = False

    @property
    def centres(self) -> FloatArray:
        """Voxel centres [m], shape ``(nx, ny, nz, 3)``."""
        gx, gy, gz = np.meshgrid(self.x, self.y, self.z, indexing="ij")
        return np.stack([gx, gy, gz], axis=-1)

    @property
    def n_orientations(self) -> int:
        """Orientations tried per voxel (K)."""
        return int(self.orientations.shape[0])

    _SAVED = (
        "robot", "ee_frame", "x", "y", "z", "index", "solved", "hits", "orientations",
        "resolution", "base", "seed", "tol_pos", "tol_rot", "max_starts", "time_s",
    )  # fmt: skip
    """The arrays :meth:`load` reads (``urdf`` too when present)."""

    def save(self, path: str | Path) -> Path:
        """Write the map to ``.npz`` (arrays ``x, y, z, index, solved, hits, centres,
        orientations, base`` and the scalars); :meth:`load` reads it back."""
        from swarm_ik.viz.export import check_output_path

        p = Path(path)
        if p.suffix.lower() != ".npz":
            raise InvalidArgumentError(
                f"reachability maps are written as .npz; got {str(p)!r} (valid suffix: .npz)"
            )
        check_output_path(p, "reachability map", (".npz",))  # (a folder, a missing folder)
        with written_in_place_of(p) as part, part.open("wb") as fb:  # (never a partial file)
            self._write(fb)
        return p

    def _write(self, fb: Any) -> None:
        """The arrays of :meth:`save` into the open file ``fb``."""
        np.savez_compressed(
            fb,
            robot=self.robot,
            ee_frame=self.ee_frame,
            x=self.x,
            y=self.y,
            z=self.z,
            index=self.index,
            solved=self.solved,
            hits=self.hits,
            centres=self.centres,
            orientations=self.orientations,
            resolution=self.resolution,
            base=self.base,
            seed=self.seed,
            tol_pos=self.tol_pos,
            tol_rot=self.tol_rot,
            max_starts=self.max_starts,
            time_s=self.time_s,
            position_only=self.position_only,
            urdf=self.urdf,
        )

    @classmethod
    def load(cls, path: str | Path) -> ReachMap:
        """Read a map written by :meth:`save`.

        Raises:
            InvalidArgumentError: no such file, not an ``.npz`` archive, or one without a
                map's arrays (the missing ones named).
        """
        p = Path(path)
        try:
            with np.load(p, allow_pickle=False) as d:
                if not hasattr(d, "files"):  # (one array: a .npy)
                    raise InvalidArgumentError(f"{str(p)!r} is not a reach map's .npz archive")
                missing = [k for k in cls._SAVED if k not in d.files]
                if missing:
                    raise InvalidArgumentError(
                        f"{str(p)!r} is no reach map (written by ReachMap.save): it lacks "
                        f"{', '.join(missing)}"
                    )
                return cls(
                    robot=str(d["robot"]),
                    ee_frame=str(d["ee_frame"]),
                    x=d["x"],
                    y=d["y"],
                    z=d["z"],
                    index=d["index"],
                    solved=d["solved"],
                    hits=d["hits"],
                    orientations=d["orientations"],
                    resolution=float(d["resolution"]),
                    base=d["base"],
                    seed=int(d["seed"]),
                    tol_pos=float(d["tol_pos"]),
                    tol_rot=float(d["tol_rot"]),
                    max_starts=int(d["max_starts"]),
                    time_s=float(d["time_s"]),
                    urdf=str(d["urdf"]) if "urdf" in d.files else "",
                    position_only=bool(d["position_only"]) if "position_only" in d.files else False,
                )
        except InvalidArgumentError:
            raise
        except FileNotFoundError:
            raise InvalidArgumentError(f"no reach map at {str(p)!r}: no such file") from None
        except (OSError, ValueError, EOFError, TypeError, zipfile.BadZipFile, zlib.error) as exc:
            # (not numpy's format, a damaged archive, an array of another kind)
            raise InvalidArgumentError(
                f"{str(p)!r} is not a readable reach map's .npz archive ({type(exc).__name__})"
            ) from None

    def __repr__(self) -> str:
        reach = self.index > 0
        return (
            f"ReachMap(robot={self.robot!r}, grid={self.index.shape}, "
            f"resolution={self.resolution} m, K={self.n_orientations}, "
            f"reachable voxels={int(reach.sum())}, mean index of reachable="
            f"{float(self.index[reach].mean()) if reach.any() else 0.0:.3f})"
        )


def chain_reach_bound(robot: RobotModel) -> tuple[FloatArray, float]:
    """A sphere holding every end-effector position: centre (the first joint) and radius.

    The radius is the sum of the joint placement offsets after the first joint, the
    end-effector offset, and the largest travel of every prismatic joint of the tree (a mimic
    follower's too: its driver's travel times its multiplier, plus its offset): a rigorous
    bound, whatever the joint values.

    Returns:
        ``(centre (3,) [m], radius [m])``.
    """
    c = robot.tree
    radius = float(np.linalg.norm(c.pos_p[1:], axis=1).sum() + np.linalg.norm(c.frame_pos[0]))
    for j in range(c.kind.shape[0]):
        if c.kind[j] == PRISMATIC:
            qi = int(c.q_index[j])
            stroke = max(abs(float(robot.lower[qi])), abs(float(robot.upper[qi])))
            travel = abs(float(c.multiplier[j])) * stroke + abs(float(c.offset[j]))
            radius += travel
            if j == 0:  # the first joint's own travel moves the centre as well
                radius += travel
    return np.array(c.pos_p[0], dtype=float), radius


def default_bounds(
    robot: RobotModel, seed: int = 0, n_samples: int = 20000, margin: float = 1.1
) -> tuple[FloatArray, FloatArray]:
    """Default workspace box: a cube around the first joint with half-edge ``margin`` × the
    largest distance of the end effector from it over ``n_samples`` random configurations.

    Returns:
        ``(lower (3,), upper (3,))`` corners [m].
    """
    rng = np.random.default_rng(seed)
    centre, _ = chain_reach_bound(robot)
    pos = robot.fk(robot.random_q(rng, n_samples))[:, :3, 3]
    r = margin * float(np.linalg.norm(pos - centre, axis=1).max())
    return centre - r, centre + r


def random_rotations(rng: np.random.Generator, k: int) -> FloatArray:
    """``k`` rotations drawn uniformly on SO(3) (normalised Gaussian quaternions),
    shape ``(k, 3, 3)``."""
    from scipy.spatial.transform import Rotation

    quat = rng.standard_normal((k, 4))
    quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    return np.asarray(Rotation.from_quat(quat).as_matrix()).reshape(k, 3, 3)


def grid_axes(
    lower: Any, upper: Any, resolution: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Voxel centres per axis for the box ``[lower, upper]`` [m] and edge ``resolution``:
    ``ceil(extent / resolution)`` voxels per axis (at least one), centred on the box."""
    lo = np.asarray(lower, dtype=float).reshape(3)
    hi = np.asarray(upper, dtype=float).reshape(3)
    axes = []
    for a in range(3):
        n = max(1, int(np.ceil((hi[a] - lo[a]) / resolution - 1e-9)))
        mid = 0.5 * (lo[a] + hi[a])
        axes.append(mid + (np.arange(n) - 0.5 * (n - 1)) * resolution)
    return axes[0], axes[1], axes[2]


def check_grid_size(
    lower: Any, upper: Any, resolution: float, n_orientations: int, max_targets: int
) -> int:
    """Refuse a grid too large to allocate, before allocating anything.

    Args:
        lower: Lower corner of the box [m], shape ``(3,)``.
        upper: Upper corner [m], shape ``(3,)``.
        resolution: Voxel edge [m], ``> 0``.
        n_orientations: Orientations per voxel (K).
        max_targets: Most poses allowed (voxels × K).

    Returns:
        The number of voxels of the box.

    Raises:
        InvalidArgumentError: the box holds more than ``max_targets`` poses (the message gives
            the count, its memory, and the finest resolution that fits; where even one
            voxel's orientations are too many, fewer orientations or a larger cap).
    """
    with np.errstate(over="ignore", divide="ignore"):  # (an extent beyond a float: inf)
        lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
        ext = hi.reshape(3) - lo.reshape(3)
        per_axis = np.maximum(1.0, np.ceil(ext / float(resolution) - 1e-9))
        n_voxels = float(np.prod(per_axis))
    k = int(n_orientations)
    poses = n_voxels * k
    if np.isfinite(poses) and poses <= max_targets:
        return int(n_voxels)
    if k > max_targets:  # no resolution fits: one voxel is already too many poses
        raise InvalidArgumentError(
            f"{k} orientations per voxel are more than max_targets={max_targets} poses even "
            f"for a single voxel, so no resolution fits: use at most {max_targets} "
            "orientations (--orientations, n_orientations) or raise the cap (--max-targets, "
            "max_targets)"
        )
    fits = finest_edge(lower, upper, max_targets // k)  # (the voxels allowed)
    coarser = "a coarser resolution"
    if fits is not None:
        coarser += f" (at least {fits:.3g} m for this box)"
    fewer = " or fewer orientations" if k > 1 else ""  # (a map of positions has one)
    raise InvalidArgumentError(
        f"resolution {resolution!r} m gives a grid of {size_text(n_voxels)} voxels × "
        f"{n_orientations} orientations = {size_text(poses)} poses (about "
        f"{size_text(poses * 128 / 1e9)} GB of targets), more than max_targets={max_targets}; "
        f"use {coarser}, smaller bounds{fewer}"
    )


DEFAULT_ORIENTATIONS = 8
"""Orientations tried per voxel of a map of poses (:func:`reach_map`, ``swarm-ik reach``)."""


def orientation_count(
    n_orientations: Any, position_only: bool, what: str = "a position-only map"
) -> int:
    """The orientations tried per voxel (K): ``n_orientations`` checked, or its default
    (:data:`DEFAULT_ORIENTATIONS`; 1 for a position-only map, which takes no other).

    Raises:
        InvalidArgumentError: not a positive integer, or other than 1 with ``position_only``
            (the message names ``what`` asked for positions).
    """
    if n_orientations is None:
        return 1 if position_only else DEFAULT_ORIENTATIONS
    k = count(n_orientations, "n_orientations")
    if position_only and k != 1:
        raise InvalidArgumentError(
            f"{what} tries one target per voxel (its orientation is free); got {k} orientations"
        )
    return k


def reach_map(
    robot: RobotModel,
    *,
    resolution: float = 0.1,
    bounds: Any = None,
    n_orientations: int | None = None,
    position_only: bool = False,
    seed: int | None = 0,
    tol_pos: float = 1e-5,
    tol_rot: float = 1e-5,
    max_starts: int = 16,
    max_iters: int = 60,
    scheduler: Any = None,
    progress: bool = False,
    max_targets: int = MAX_TARGETS,
) -> ReachMap:
    """Compute the reachability map of ``robot``.

    Args:
        robot: The robot.
        resolution: Voxel edge [m].
        bounds: ``(lower (3,), upper (3,))`` corners of the box [m], or 6 numbers
            ``xmin ymin zmin xmax ymax zmax``; default :func:`default_bounds`.
        n_orientations: Orientations tried per voxel (K), the same for every voxel
            (default 8; 1 with ``position_only``, which takes no other).
        position_only: Solve each voxel's centre as a position, the frame's orientation free
            (the map of where the frame's origin can be: an arm of fewer than 6 joints
            reaches a random full orientation almost nowhere).
        seed: Seed of the orientations and of the solver's restarts (None: 0, as in
            :func:`swarm_ik.solve`).
        tol_pos: Position tolerance [m]; tol_rot: rotation tolerance [rad].
        max_starts: Starts per pose before it counts as unreachable (the cost of an
            unreachable pose grows with it).
        max_iters: LM evaluations per start.
        scheduler: Where to solve (see :mod:`swarm_ik.distributed`); ``None``: this process.
        progress: Show a progress bar.
        max_targets: Refuse grids needing more poses than this (voxels × K), to catch a
            resolution typed in the wrong unit; the whole box is checked before anything is
            allocated (:func:`check_grid_size`), the voxels within reach after.

    Returns:
        The :class:`ReachMap`.

    Raises:
        InvalidArgumentError: non-positive resolution or K, empty/inverted bounds, or more
            than ``max_targets`` poses.
    """
    t0 = time.perf_counter()
    if not isinstance(robot, RobotModel):
        raise InvalidArgumentError(
            f"robot must be a RobotModel (see swarm_ik.load_robot), got {type(robot).__name__}"
        )
    resolution = positive_float(resolution, "resolution [m]")
    position_only = flag(position_only, "position_only")
    n_orientations = orientation_count(n_orientations, position_only)
    seed = count(0 if seed is None else seed, "seed", 0, SEED_LIMIT - 1)  # (None: 0, as solve)
    max_targets = count(max_targets, "max_targets", 1, batch.MAX_TARGETS)  # (one batch)
    if bounds is None:
        lo, hi = default_bounds(robot, seed=seed)
    else:
        what = "bounds must be 6 finite numbers (xmin ymin zmin xmax ymax zmax) or (lower, upper)"
        b = floats_or(bounds, lambda: f"{what}, got {reprlib.repr(bounds)}").reshape(-1)
        if b.shape != (6,) or not np.all(np.isfinite(b)):
            raise InvalidArgumentError(f"{what}; got {b.tolist()}")
        lo, hi = b[:3], b[3:]
        if np.any(lo >= hi):
            raise InvalidArgumentError(
                f"bounds: lower corner {lo.tolist()} must be below upper corner {hi.tolist()} "
                "on every axis"
            )
    k = int(n_orientations)
    check_grid_size(lo, hi, resolution, k, max_targets)
    x, y, z = grid_axes(lo, hi, resolution)
    shape = (x.size, y.size, z.size)
    gx, gy, gz = np.meshgrid(x, y, z, indexing="ij")
    centres = np.stack([gx, gy, gz], axis=-1).reshape(-1, 3)
    base, radius = chain_reach_bound(robot)
    inside = np.linalg.norm(centres - base, axis=1) <= radius + 1e-12
    n_targets = int(inside.sum()) * k
    if n_targets > max_targets:
        raise InvalidArgumentError(
            f"the grid needs {n_targets} poses ({int(inside.sum())} voxels × {k} orientations), "
            f"more than max_targets={max_targets}; use a coarser resolution (given "
            f"{resolution} m) or smaller bounds"
        )
    rots = np.eye(3)[None] if position_only else random_rotations(np.random.default_rng(seed), k)
    pts = centres[inside]
    targets = np.zeros((pts.shape[0], k, 4, 4))
    targets[:, :, :3, :3] = rots[None]
    targets[:, :, :3, 3] = pts[:, None, :]
    targets[:, :, 3, 3] = 1.0
    res = solve_batch(
        robot, targets.reshape(-1, 4, 4), seed=seed, tol_pos=tol_pos, tol_rot=tol_rot,
        max_starts=max_starts, max_iters=max_iters, scheduler=scheduler, progress=progress,
        position_only=position_only,
    )  # fmt: skip
    hits = np.zeros((centres.shape[0], k), dtype=bool)
    hits[inside] = res.success.reshape(-1, k)
    index = hits.mean(axis=1)
    return ReachMap(
        robot=robot.name,
        ee_frame=robot.ee_frame,
        x=x,
        y=y,
        z=z,
        index=index.reshape(shape),
        solved=inside.reshape(shape),
        hits=hits.reshape(*shape, k),
        orientations=rots,
        resolution=float(resolution),
        base=base,
        seed=int(seed),
        tol_pos=float(tol_pos),
        tol_rot=float(tol_rot),
        max_starts=int(max_starts),
        time_s=time.perf_counter() - t0,
        urdf=str(robot.urdf_path),
        position_only=position_only,
    )


# --------------------------------------------------------------------------- pictures
def plot_slices(rmap: ReachMap, path: str | Path, dpi: int = 120) -> Path:
    """Heat maps of the index on three orthogonal slices through the first joint (XY, XZ,
    YZ), written as a PNG (matplotlib, imported here; another format of matplotlib's by the
    suffix).

    Raises:
        InvalidArgumentError: matplotlib is missing, or ``path`` is a folder, in a missing
            folder, or of a format matplotlib does not write.
    """
    try:
        import matplotlib

        matplotlib.use("Agg", force=False)
        import matplotlib.pyplot as plt
    except ImportError:  # pragma: no cover - depends on the environment
        raise InvalidArgumentError(
            'plotting needs matplotlib: pip install "swarm_ik[plot]"'
        ) from None
    from swarm_ik.viz.export import check_output_path

    p = Path(path)
    if not p.suffix and not p.is_dir():  # (as matplotlib names a file without a suffix)
        p = p.with_suffix(".png")
    from matplotlib.backend_bases import FigureCanvasBase

    formats = tuple(f".{f}" for f in FigureCanvasBase.get_supported_filetypes())
    check_output_path(p, "plot", formats)  # (before drawing: a folder, a missing folder)
    ix = int(np.argmin(np.abs(rmap.x - rmap.base[0])))
    iy = int(np.argmin(np.abs(rmap.y - rmap.base[1])))
    iz = int(np.argmin(np.abs(rmap.z - rmap.base[2])))
    h = 0.5 * rmap.resolution
    panels = [
        (rmap.index[:, :, iz].T, rmap.x, rmap.y, "x", "y", f"XY slice, z = {rmap.z[iz]:.2f} m"),
        (rmap.index[:, iy, :].T, rmap.x, rmap.z, "x", "z", f"XZ slice, y = {rmap.y[iy]:.2f} m"),
        (rmap.index[ix, :, :].T, rmap.y, rmap.z, "y", "z", f"YZ slice, x = {rmap.x[ix]:.2f} m"),
    ]
    fig, axs = plt.subplots(1, 3, figsize=(15, 4.8), constrained_layout=True)
    im: Any = None
    for ax, (img, u, v, lu, lv, title) in zip(axs, panels, strict=True):
        im = ax.imshow(
            img,
            origin="lower",
            vmin=0.0,
            vmax=1.0,
            cmap="viridis",
            extent=(u[0] - h, u[-1] + h, v[0] - h, v[-1] + h),
            interpolation="nearest",
        )
        ax.set_xlabel(f"{lu} [m]")
        ax.set_ylabel(f"{lv} [m]")
        ax.set_title(title)
        ax.set_aspect("equal")
    fig.colorbar(
        im, ax=axs, shrink=0.85, label=f"reachability index (of K = {rmap.n_orientations})"
    )
    fig.suptitle(
        f"{rmap.robot} ({rmap.ee_frame}): reachability, {rmap.resolution:g} m voxels, "
        f"tolerance {rmap.tol_pos:g} m / {rmap.tol_rot:g} rad"
    )
    with written_in_place_of(p) as part:  # (never a partial file)
        fig.savefig(part, dpi=dpi, format=p.suffix[1:].lower())
    plt.close(fig)
    return p


def _viridis(values: FloatArray) -> FloatArray:
    """RGB colours ``(n, 3)`` in [0, 1] of values in [0, 1] (matplotlib's viridis when
    available, else a blue → yellow ramp)."""
    v = np.clip(values, 0.0, 1.0)
    try:
        from matplotlib import colormaps

        return np.asarray(colormaps["viridis"](v))[:, :3]
    except ImportError:  # pragma: no cover - depends on the environment
        return np.stack([v, 0.3 + 0.6 * v, 1.0 - v], axis=1)


def legend_png(n_orientations: int, width: int = 480) -> tuple[bytes, float]:
    """PNG of the colour legend (the viridis bar from 0 to 1 with its caption) and its
    width / height ratio."""
    import io

    from PIL import Image, ImageDraw, ImageFont

    try:
        font: Any = ImageFont.load_default(size=22)
    except TypeError:  # Pillow < 10.1: fixed-size bitmap font
        font = ImageFont.load_default()
    pad, bar_h, height = 16, 36, 140
    img = Image.new("RGB", (width, height), (255, 255, 250))
    draw = ImageDraw.Draw(img)
    draw.text(
        (pad, 8), f"reachability index (of K = {n_orientations})", fill=(20, 20, 30), font=font
    )
    x0, x1, y0 = pad, width - pad, 48
    colours = (255 * _viridis(np.linspace(0.0, 1.0, x1 - x0))).astype(int)
    for k, (r, g, b) in enumerate(colours):
        draw.line([(x0 + k, y0), (x0 + k, y0 + bar_h)], fill=(int(r), int(g), int(b)))
    for v in (0.0, 0.25, 0.5, 0.75, 1.0):
        x = x0 + v * (x1 - x0 - 1)
        draw.line([(x, y0 + bar_h), (x, y0 + bar_h + 8)], fill=(20, 20, 30), width=2)
        label = f"{v:g}"
        w = draw.textlength(label, font=font)
        draw.text((min(max(x - w / 2, 0), width - w), y0 + bar_h + 12), label, fill=(20, 20, 30),
                  font=font)  # fmt: skip
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    return buf.getvalue(), width / height


def export_html(
    rmap: ReachMap,
    path: str | Path,
    point_size: float | None = None,
    robot: RobotModel | None = None,
) -> Path:
    """A self-contained HTML page (meshcat's viewer, no server): the voxels with a non-zero
    index as a point cloud coloured by the index (viridis), the robot at its mid-range
    configuration, and the colour legend.

    Built as a :class:`swarm_ik.viz.Scene` and written with its HTML export.

    Args:
        rmap: The map.
        path: The ``.html`` file to write.
        point_size: Size of a point [m] (default 0.6 × the resolution).
        robot: The robot to draw (default: loaded from the map's URDF file and frame, or by
            its robot name for a map without one; left out when that fails or the file is
            gone).

    Raises:
        InvalidArgumentError: meshcat is not installed, or the path cannot be written.
    """
    from swarm_ik import viz

    try:
        viz.require_meshcat()
    except viz.VizUnavailableError:
        raise InvalidArgumentError(
            'the HTML export needs meshcat: pip install "swarm_ik[viz]"'
        ) from None
    import meshcat.geometry as mg

    out = viz.check_output_path(path, "HTML file", (".html", ".htm"))
    if robot is None:
        import swarm_ik
        from swarm_ik.errors import SwarmIKError

        source = rmap.urdf or rmap.robot
        try:
            robot = swarm_ik.load_robot(source, ee_frame=rmap.ee_frame)
        except SwarmIKError:  # (a URDF that has gone is not stood in for by a namesake)
            robot = None
    reach = rmap.index > 0
    pts = rmap.centres[reach].astype(np.float32)
    colours = _viridis(rmap.index[reach]).astype(np.float32)
    size = float(point_size) if point_size is not None else 0.6 * rmap.resolution
    with viz.Scene() as scene:
        scene.node("reachability/voxels").set_object(
            mg.PointCloud(pts.T.copy(), colours.T.copy(), size=size)
        )
        view = [pts.astype(float).reshape(-1, 3), rmap.base[None]]
        if robot is not None:
            q = robot.mid_q()
            scene.add_robot(robot, q, name="robot")
            scene.add_triad("reached", robot.fk(q), length=0.12 * viz.reach_length(robot))
            view.append(robot.fk(q)[None, :3, 3])
        scene.add_triad("base", viz.scene.translation(rmap.base), length=0.2)
        pts_all = np.vstack(view)
        d = np.array([1.0, 0.75, 0.45]) / np.linalg.norm([1.0, 0.75, 0.45])
        lo, hi = pts_all.min(axis=0), pts_all.max(axis=0)
        extent = max(float(np.linalg.norm(hi - lo)), 0.2)
        png, aspect = legend_png(rmap.n_orientations)
        height = 0.12 * extent
        centre = np.array([0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), hi[2] + 0.6 * height])
        scene.add_image("legend", png, aspect, position=centre, height=height, facing=d)
        right = np.cross([0.0, 0.0, 1.0], d)
        right /= np.linalg.norm(right)
        corners = [centre + sx * 0.5 * height * aspect * right for sx in (-1, 1)]
        scene.frame_camera(
            np.vstack([pts_all, corners, centre + [0, 0, 0.5 * height]]), direction=d
        )
        title = f"{rmap.robot} reachability ({int(reach.sum())} voxels, K = {rmap.n_orientations})"
        return scene.save_html(out, title=title)
