"""Look at a solution before sending it to a robot: meshcat scenes, convergence animations and
self-contained HTML exports.

meshcat is an optional extra (``pip install swarm_ik[viz]``) imported only when a scene is
built; ``import swarm_ik`` never imports it.  The robot is drawn from the URDF's visual geometry
through Pinocchio's geometry model (meshes resolved from ``package://`` paths, including those
of ``example-robot-data``), with the joints off the chain held at the robot's ``q_locked``.

>>> import swarm_ik
>>> from swarm_ik import viz
>>> robot = swarm_ik.load_robot("yumi_left")
>>> problem = swarm_ik.IKProblem.from_q(robot, [0.1, -0.5, 0.2, 0.3, -0.2, 0.4, 0.1])
>>> result, trace = viz.solve_traced(problem, "pso", seed=0, max_evals=3000)
>>> scene = viz.show_result(problem, result, trace=trace)      # doctest: +SKIP
>>> scene.save_html("result.html")                             # doctest: +SKIP
"""

from __future__ import annotations

import contextlib
import functools
import io
import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from swarm_ik.errors import InvalidArgumentError, SwarmIKError
from swarm_ik.problem import IKProblem
from swarm_ik.result import Result
from swarm_ik.robot import RobotModel

FloatArray = NDArray[np.float64]

INSTALL_HINT = "pip install swarm_ik[viz]"
ROOT = "swarm_ik"
"""meshcat path (relative to the visualizer's ``/meshcat``) holding a :class:`Scene`'s objects."""
GHOST_COLOR = (1.0, 0.55, 0.1, 0.35)
"""RGBA of a ghosted (comparison) robot."""
AXIS_COLORS = (0xE03030, 0x30B030, 0x3060E0)
"""Colours of the x, y and z axes of a triad."""
LAYOUTS = ("side", "steps")
"""How :func:`show_solutions` arranges several solutions."""


class VizUnavailableError(SwarmIKError, ImportError):
    """The optional viewer dependency (meshcat) is not installed."""


def require_meshcat() -> Any:
    """Import and return the ``meshcat`` module.

    Raises:
        VizUnavailableError: meshcat is not installed; the message names the extra.
    """
    try:
        with warnings.catch_warnings():  # meshcat's server module imports a deprecated zmq API
            warnings.simplefilter("ignore", DeprecationWarning)
            import meshcat
            import meshcat.geometry  # noqa: F401
            import meshcat.visualizer  # noqa: F401
    except ImportError as exc:
        raise VizUnavailableError(
            f"the viewer needs meshcat, which is not installed ({exc}); install the extra with "
            f"`{INSTALL_HINT}`"
        ) from None
    return meshcat


# ------------------------------------------------------------------ convergence trace
@dataclass(frozen=True)
class Trace:
    """The optimiser's best-so-far configuration after each iteration of one solve.

    Attributes:
        q: Best-so-far joint vector per iteration (rad / m), shape ``(iterations, nq)``.
        fitness: Its fitness (the solve's ``Result.history``), shape ``(iterations,)``.
        improvements: Number of times the best point improved during the solve.
    """

    q: FloatArray
    fitness: FloatArray
    improvements: int

    def __len__(self) -> int:
        return int(self.q.shape[0])

    def subsample(self, max_frames: int) -> Trace:
        """At most ``max_frames`` iterations, evenly spaced, the first and last kept."""
        if max_frames < 2:
            raise InvalidArgumentError(f"max_frames must be at least 2, got {max_frames}")
        n = len(self)
        if n <= max_frames:
            return self
        idx = np.unique(np.round(np.linspace(0, n - 1, max_frames)).astype(int))
        return Trace(self.q[idx], self.fitness[idx], self.improvements)


class _RecordingProblem(IKProblem):
    """An :class:`IKProblem` that remembers every point offered as a new best.

    ``solve`` checks its success criterion (``is_success``) on each new best point, so the
    sequence of calls is the sequence of best-so-far points.  Nothing else changes: the hot
    path (``fitness``) is the parent's.
    """

    trail: list[FloatArray]

    @classmethod
    def wrap(cls, problem: IKProblem) -> _RecordingProblem:
        rec = cls.__new__(cls)
        rec.__dict__.update(problem.__dict__)
        rec.trail = []
        return rec

    def is_success(self, q: FloatArray, tol_pos: float, tol_rot: float) -> bool:
        self.trail.append(np.array(q, dtype=float, copy=True))
        return super().is_success(q, tol_pos, tol_rot)


def solve_traced(
    problem: IKProblem, solver: str | None = None, **solve_kwargs: Any
) -> tuple[Result, Trace]:
    """:func:`swarm_ik.solve`, also returning the best-so-far configuration per iteration.

    Only for watching a solve: the recording adds a copy of ``q`` per improvement.

    Args:
        problem: The problem.
        solver: Registry name (default: :data:`swarm_ik.api.DEFAULT_SOLVER`).
        **solve_kwargs: Passed to :func:`swarm_ik.solve` (``seed``, ``max_evals``, ``q0``, …).

    Returns:
        The result and its :class:`Trace` (one row per entry of ``result.history``; at least
        one row, the final ``q``, when the solver recorded no iteration).

    Raises:
        InvalidArgumentError: ``stop_on_success=False`` was asked (the recording relies on the
            success check made at each improvement).
    """
    from swarm_ik.api import DEFAULT_SOLVER, solve

    if not solve_kwargs.get("stop_on_success", True):
        raise InvalidArgumentError(
            "solve_traced records the best point at each success check; stop_on_success=False "
            "is not supported"
        )
    rec = _RecordingProblem.wrap(problem)
    result = solve(rec, solver or DEFAULT_SOLVER, **solve_kwargs)
    trail = np.array(rec.trail, dtype=float).reshape(-1, problem.nq)
    history = np.asarray(result.history, dtype=float)
    if trail.shape[0] == 0 or history.size == 0:
        q = result.q[None].copy()
        return result, Trace(q, np.array([result.fitness]), int(trail.shape[0]))
    f_trail = problem.fitness(trail)
    # the best point after iteration i is the first recorded one whose fitness reached
    # history[i] (the solver's own arithmetic may differ from the problem's in the last bits)
    rows = np.empty(history.size, dtype=int)
    for i, h in enumerate(history):
        tol = 1e-9 * (1.0 + abs(h)) if np.isfinite(h) else 0.0
        above = np.count_nonzero(f_trail > h + tol) if np.isfinite(h) else 0
        rows[i] = min(above, trail.shape[0] - 1)
    q_frames = trail[rows]
    if not np.allclose(q_frames[-1], result.q):  # a final step the history did not record
        q_frames = np.vstack([q_frames, result.q])
        history = np.append(history, result.fitness)
    return result, Trace(q_frames, history, int(trail.shape[0]))


# --------------------------------------------------------------------------- geometry
def package_dirs(robot: RobotModel) -> list[str]:
    """Folders searched for ``package://`` meshes of ``robot``'s URDF.

    The URDF's folder and its two parents (a ``<pkg>/urdf/robot.urdf`` layout), the
    ``example-robot-data`` folders when that package is installed, and ``$ROS_PACKAGE_PATH``.
    """
    dirs: list[Path] = []
    here = Path(robot.urdf_path).resolve().parent
    dirs += [here, here.parent, here.parent.parent]
    try:
        from swarm_ik.robot import example_robot_data_dir

        erd = example_robot_data_dir()
        dirs += [erd, erd.parent, erd.parent.parent]
    except SwarmIKError:
        pass
    dirs += [Path(p) for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    out: list[str] = []
    for d in dirs:
        s = str(d)
        if s not in out and d.is_dir():
            out.append(s)
    return out


def visual_model(robot: RobotModel) -> Any:
    """Pinocchio visual geometry model of the robot's full URDF model.

    Raises:
        RobotModelError: a mesh cannot be found (the message names it).
    """
    from swarm_ik.errors import RobotModelError

    try:
        return pin.buildGeomFromUrdf(
            robot.full_model,
            str(robot.urdf_path),
            pin.GeometryType.VISUAL,
            package_dirs=package_dirs(robot),
        )
    except ValueError as exc:
        raise RobotModelError(
            f"{robot.urdf_path}: cannot load the visual geometry ({exc}); searched "
            f"{package_dirs(robot)} (add the package folder to ROS_PACKAGE_PATH)"
        ) from None


def full_configuration(robot: RobotModel, q: Any) -> FloatArray:
    """Configuration of ``robot.full_model`` with the chain at ``q`` and the other joints at
    ``robot.q_locked``.

    Args:
        q: Chain joint vector (rad / m), shape ``(nq,)``.

    Returns:
        Pinocchio configuration of the full model, shape ``(full_model.nq,)``.
    """
    q_red = robot.to_pinocchio(robot.check_q(q))
    out = np.array(robot.q_locked, dtype=float, copy=True)
    for j in range(1, robot.model.njoints):
        jr = robot.model.joints[j]
        jf = robot.full_model.joints[robot.full_model.getJointId(robot.model.names[j])]
        out[jf.idx_q : jf.idx_q + jf.nq] = q_red[jr.idx_q : jr.idx_q + jr.nq]
    return out


def _reach(robot: RobotModel) -> float:
    """A length scale of the robot [m]: the sum of its joint offsets (at least 0.2)."""
    return max(0.2, robot.reach_radius())


def _translation(p: Any) -> FloatArray:
    t = np.eye(4)
    t[:3, 3] = np.asarray(p, dtype=float)
    return t


def _rgb_int(rgb: Any) -> int:
    r, g, b = (int(round(255 * min(1.0, max(0.0, float(c))))) for c in rgb[:3])
    return r * 65536 + g * 256 + b


class RobotDrawing:
    """One robot drawn in a :class:`Scene` (built by :meth:`Scene.add_robot`).

    Attributes:
        robot: The robot.
        path: meshcat path of the robot's node.
        q: Configuration shown (rad / m), shape ``(nq,)``.
    """

    def __init__(
        self, scene: Scene, robot: RobotModel, path: str, geom: Any, color: Sequence[float] | None
    ) -> None:
        self.robot = robot
        self.path = path
        self._scene = scene
        self._model = robot.full_model
        self._data = self._model.createData()
        self._geom = geom
        self._geom_data = pin.GeometryData(geom)
        loader = _shape_loader()(self._model, None, geom)
        loader.initViewer(viewer=scene.visualizer)
        with _quiet(), warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            loader.loadViewerModel(rootNodeName=path, visual_color=color)
        self._names = [loader.node_of(g) for g in geom.geometryObjects]
        self.q = np.zeros(robot.nq)

    def transforms(self, q: Any) -> list[tuple[str, FloatArray]]:
        """meshcat node paths and 4x4 transforms of every visual at chain configuration ``q``."""
        from pinocchio.visualize.meshcat_visualizer import applyScalingOnHomegeneousTransform

        pin.forwardKinematics(self._model, self._data, full_configuration(self.robot, q))
        pin.updateGeometryPlacements(self._model, self._data, self._geom, self._geom_data)
        out = []
        for k, g in enumerate(self._geom.geometryObjects):
            t = applyScalingOnHomegeneousTransform(self._geom_data.oMg[k].homogeneous, g.meshScale)
            out.append((self._names[k], t))
        return out

    def set_q(self, q: Any, frame: Any = None) -> None:
        """Pose the robot at ``q`` (rad / m), or record that pose in an animation ``frame``."""
        target = self._scene.visualizer if frame is None else frame
        for name, t in self.transforms(q):
            target[name].set_transform(t)
        if frame is None:
            self.q = np.asarray(q, dtype=float).copy()


@functools.lru_cache(maxsize=1)
def _shape_loader() -> type:
    """Pinocchio's meshcat loader, each shape one node below the node that gets placed.

    meshcat's ``set_transform`` replaces the matrix of the object at a path, and Pinocchio
    puts primitive shapes (cylinders along z where three.js has y) there with a built-in
    rotation: placing the parent node instead keeps that rotation.
    """
    from pinocchio.visualize import MeshcatVisualizer

    class ShapeLoader(MeshcatVisualizer):  # type: ignore[misc]
        def node_of(self, geometry_object: Any) -> str:
            return str(super().getViewerNodeName(geometry_object, pin.GeometryType.VISUAL))

        def getViewerNodeName(self, geometry_object: Any, geometry_type: Any) -> str:  # noqa: N802
            return str(super().getViewerNodeName(geometry_object, geometry_type)) + "/shape"

        def updatePlacements(self, geometry_type: Any) -> None:  # noqa: N802
            """Placements are set by :class:`RobotDrawing` (on the parent nodes)."""

        def loadViewerGeometryObject(  # noqa: N802
            self, geometry_object: Any, geometry_type: Any, color: Any = None
        ) -> None:
            """Pinocchio's loader, except that a colour override also recolours mesh files
            (Pinocchio drops the material of a Collada file): the mesh is sent as plain
            geometry with the override's material."""
            import meshcat.geometry as mg

            ext = Path(geometry_object.meshPath).suffix.lower()
            kinds = {
                ".dae": mg.DaeMeshGeometry,
                ".stl": mg.StlMeshGeometry,
                ".obj": mg.ObjMeshGeometry,
            }
            if color is None or ext not in kinds or not Path(geometry_object.meshPath).is_file():
                super().loadViewerGeometryObject(geometry_object, geometry_type, color)
                return
            rgba = np.asarray(color, dtype=float)
            material = mg.MeshPhongMaterial(
                color=_rgb_int(rgba), opacity=float(rgba[3]), transparent=float(rgba[3]) < 1.0
            )
            shape = kinds[ext].from_file(geometry_object.meshPath)
            self.viewer[self.getViewerNodeName(geometry_object, geometry_type)].set_object(
                shape, material
            )

    return ShapeLoader


@contextlib.contextmanager
def _quiet() -> Any:
    """Silence meshcat's and Pinocchio's chatter on stdout."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield


# ------------------------------------------------------------------------------ scene
class Scene:
    """A meshcat scene: robots, pose triads, text labels, an animation; live or exported.

    Creating one starts meshcat's local server (loopback only, stopped by :meth:`close` or at
    exit); :attr:`url` is the address to open in a browser.  :meth:`frame_camera` re-centres
    the content so that meshcat's camera, which orbits the origin, orbits it.

    Every object sits in a ``shape`` child of the node that is placed: meshcat's
    ``set_transform`` replaces the matrix of the object at a path, which would drop the
    object's own built-in transform (and the static export replays commands in no fixed order).

    Attributes:
        visualizer: The ``meshcat.Visualizer``.
        robots: The robots drawn, by node name.

    Raises:
        VizUnavailableError: meshcat is not installed.
    """

    def __init__(self) -> None:
        meshcat = require_meshcat()
        with _quiet():
            self.visualizer = meshcat.Visualizer()
        self.visualizer[ROOT].delete()
        self.visualizer["/Background"].set_property("top_color", [0.97, 0.97, 0.98])
        self.visualizer["/Background"].set_property("bottom_color", [0.72, 0.75, 0.80])
        self._geoms: dict[int, Any] = {}
        self._anim: Any = None
        self._center = np.zeros(3)
        self.robots: dict[str, RobotDrawing] = {}

    @property
    def url(self) -> str:
        """Address of the live viewer (``http://127.0.0.1:PORT/static/``)."""
        return str(self.visualizer.url())

    def node(self, name: str) -> Any:
        """The meshcat node ``ROOT/name``."""
        return self.visualizer[f"{ROOT}/{name}"]

    # ----------------------------------------------------------------- content
    def add_robot(
        self,
        robot: RobotModel,
        q: Any,
        *,
        name: str = "robot",
        color: Sequence[float] | None = None,
        offset: Any = None,
    ) -> RobotDrawing:
        """Draw ``robot`` at chain configuration ``q``.

        Args:
            robot: The robot.
            q: Joint vector (rad / m), shape ``(nq,)``.
            name: Node name inside the scene (``"a/b"`` nests).
            color: RGBA in ``[0, 1]`` overriding the URDF colours (alpha < 1 ghosts it).
            offset: Translation of the robot's base [m], shape ``(3,)``.

        Returns:
            The drawing (pose it again with :meth:`RobotDrawing.set_q`).
        """
        q = robot.check_q(q)
        geom = self._geoms.get(id(robot))
        if geom is None:
            geom = self._geoms[id(robot)] = visual_model(robot)
        path = f"{ROOT}/{name}"
        drawing = RobotDrawing(self, robot, path, geom, color)
        if offset is not None:
            self.visualizer[path].set_transform(_translation(offset))
        drawing.set_q(q)
        self.robots[name] = drawing
        return drawing

    def add_triad(
        self,
        name: str,
        pose: Any,
        *,
        length: float = 0.1,
        radius: float | None = None,
        opacity: float = 1.0,
        sphere: Sequence[float] | None = None,
    ) -> None:
        """Draw a coordinate frame: x, y, z axes as red, green, blue rods.

        Args:
            name: Node name inside the scene.
            pose: 4x4 transform [m].
            length: Axis length [m].
            radius: Rod radius [m] (default ``length / 25``).
            opacity: Opacity of the rods in ``[0, 1]``.
            sphere: Optional RGBA of a sphere at the origin (radius ``length / 5``).
        """
        import meshcat.geometry as mg

        r = length / 25.0 if radius is None else radius
        node = self.node(name)
        node.delete()
        # meshcat cylinders run along their local y axis: rotate y onto x, y, z
        rots = [
            np.array([[0, 1, 0], [-1, 0, 0], [0, 0, 1]], dtype=float),
            np.eye(3),
            np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], dtype=float),
        ]
        for k, (axis, rot, colour) in enumerate(zip("xyz", rots, AXIS_COLORS, strict=True)):
            t = np.eye(4)
            t[:3, :3] = rot
            t[:3, 3] = 0.5 * length * np.eye(3)[k]
            mat = mg.MeshLambertMaterial(color=colour, opacity=opacity, transparent=opacity < 1.0)
            node[axis]["shape"].set_object(mg.Cylinder(length, r), mat)
            node[axis].set_transform(t)
        if sphere is not None:
            mat = mg.MeshLambertMaterial(
                color=_rgb_int(sphere), opacity=float(sphere[3]), transparent=float(sphere[3]) < 1.0
            )
            node["origin"]["shape"].set_object(mg.Sphere(length / 5.0), mat)
        node.set_transform(np.asarray(pose, dtype=float))

    def add_label(
        self,
        name: str,
        lines: Sequence[str],
        *,
        position: Any,
        height: float = 0.1,
        facing: Any = (1.0, 0.0, 0.0),
    ) -> None:
        """A flat sign with text (a texture), standing upright.

        Args:
            name: Node name inside the scene.
            lines: Text lines.
            position: Centre of the sign [m], shape ``(3,)``.
            height: Height of the sign [m]; the width follows the text.
            facing: Direction the text faces (towards the camera), shape ``(3,)``; the text's
                up is the world's z tilted to be square to it.
        """
        import meshcat.geometry as mg

        png, aspect = _text_png(lines)
        tex = mg.ImageTexture(image=mg.PngImage(png))
        mat = mg.MeshBasicMaterial(map=tex)
        node = self.node(name)
        node["shape"].set_object(mg.Box([height * aspect, height, 1e-4]), mat)
        n = np.asarray(facing, dtype=float)
        n = n / np.linalg.norm(n)
        right = np.cross([0.0, 0.0, 1.0], n)
        if np.linalg.norm(right) < 1e-9:  # seen from straight above
            right = np.array([0.0, 1.0, 0.0])
        right /= np.linalg.norm(right)
        t = np.eye(4)
        t[:3, :3] = np.column_stack([right, np.cross(n, right), n])  # box z → n, y → "up"
        t[:3, 3] = np.asarray(position, dtype=float)
        node.set_transform(t)

    def add_floor(self, center_xy: Any, half_size: float) -> None:
        """A grid on the plane z = 0 (the robot's base), replacing meshcat's default grid.

        Args:
            center_xy: Centre of the grid [m], shape ``(2,)``.
            half_size: Half its side [m]; the cell is a round 1, 2 or 5 × 10^k metres.
        """
        import meshcat.geometry as mg

        self.visualizer["/Grid"].set_property("visible", False)
        self.visualizer["/Axes"].set_property("visible", False)
        cell = _nice_step(half_size / 4.0)
        c = np.round(np.asarray(center_xy, dtype=float) / cell) * cell
        n = int(np.ceil(half_size / cell))
        ticks = np.arange(-n, n + 1) * cell
        lo, hi = -n * cell, n * cell
        segs = []
        for t in ticks:
            segs += [[c[0] + t, c[1] + lo, 0.0], [c[0] + t, c[1] + hi, 0.0]]
            segs += [[c[0] + lo, c[1] + t, 0.0], [c[0] + hi, c[1] + t, 0.0]]
        verts = np.asarray(segs, dtype=np.float32).T
        self.node("floor").set_object(
            mg.LineSegments(mg.PointsGeometry(verts), mg.LineBasicMaterial(color=0x9098A0))
        )

    # ------------------------------------------------------------------ camera
    def frame_camera(
        self,
        points: Any,
        *,
        direction: Sequence[float] = (1.0, 0.75, 0.45),
        distance: float | None = None,
    ) -> FloatArray:
        """Centre the scene on ``points`` and place the camera to see them all.

        meshcat's camera orbits the origin, so the scene's root node is shifted by minus the
        centre of the points' bounding box, and a floor grid is drawn under them at z = 0
        (meshcat's own grid and axes are hidden).

        Args:
            points: Points to keep in view [m], shape ``(n, 3)``.
            direction: Direction from the centre to the camera (world axes, z up).
            distance: Camera distance [m]; default 1.45 × the points' radius.

        Returns:
            The unit direction from the centre to the camera, shape ``(3,)``.
        """
        pts = np.atleast_2d(np.asarray(points, dtype=float))
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        center = 0.5 * (lo + hi)
        radius = max(0.25, 0.5 * float(np.linalg.norm(hi - lo)))
        self._center = center
        self.visualizer[ROOT].set_transform(_translation(-center))
        # a floor that stays in front of the camera (lines passing behind it get lost)
        self.add_floor(center[:2], 0.95 * radius)
        d = np.asarray(direction, dtype=float)
        d = d / np.linalg.norm(d)
        pos = d * (1.45 * radius if distance is None else distance)
        # the camera node lives in three.js axes (y up): world (x, y, z) -> (x, z, -y)
        self.visualizer["/Cameras/default/rotated/<object>"].set_property(
            "position", [float(pos[0]), float(pos[2]), float(-pos[1])]
        )
        return d

    # --------------------------------------------------------------- animation
    def animation(self, fps: int = 20) -> Any:
        """The scene's meshcat animation (created on first use); fill it with
        ``anim.at_frame(scene.visualizer, i)`` then call :meth:`play`."""
        if self._anim is None:
            import meshcat.animation

            self._anim = meshcat.animation.Animation(default_framerate=fps)
        return self._anim

    def play(self, repetitions: int = 1) -> None:
        """Send the animation to the viewer (it starts playing)."""
        if self._anim is not None:
            self.visualizer.set_animation(self._anim, play=True, repetitions=repetitions)

    # ------------------------------------------------------------------ output
    def to_html(self) -> str:
        """The whole scene (animation included) as one self-contained HTML page."""
        return str(self.visualizer.static_html())

    def save_html(self, path: str | os.PathLike[str]) -> Path:
        """Write :meth:`to_html` to ``path``; returns the path written."""
        p = Path(path)
        if p.parent and not p.parent.is_dir():
            raise InvalidArgumentError(
                f"cannot write {str(p)!r}: folder {str(p.parent)!r} does not exist"
            )
        p.write_text(self.to_html(), encoding="utf-8")
        return p

    def close(self) -> None:
        """Stop the meshcat server of this scene (it also stops when Python exits)."""
        window = self.visualizer.window
        sock = getattr(window, "zmq_socket", None)
        if sock is not None and not sock.closed:
            sock.close(linger=0)
        proc = getattr(window, "server_proc", None)
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()
        for pipe in (getattr(proc, "stdout", None), getattr(proc, "stderr", None)):
            if pipe is not None and not pipe.closed:
                pipe.close()

    def __enter__(self) -> Scene:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _nice_step(x: float) -> float:
    """The largest of 1, 2, 5 × 10^k not above ``x`` (``x > 0``)."""
    k = np.floor(np.log10(x))
    for m in (5.0, 2.0, 1.0):
        if m * 10**k <= x:
            return float(m * 10**k)
    return float(10**k)


def _text_png(lines: Sequence[str], font_px: int = 28) -> tuple[bytes, float]:
    """PNG of the text lines (dark text on a pale card) and its width / height ratio."""
    from PIL import Image, ImageDraw, ImageFont

    try:
        font: Any = ImageFont.load_default(size=font_px)
    except TypeError:  # Pillow < 10.1: fixed-size bitmap font
        font = ImageFont.load_default()
    lines = [str(s) for s in lines] or [""]
    probe = ImageDraw.Draw(Image.new("RGBA", (1, 1)))
    widths = [probe.textlength(s, font=font) for s in lines]
    pad = font_px // 2
    line_h = int(font_px * 1.3)
    w = int(max(widths) + 2 * pad)
    h = int(line_h * len(lines) + 2 * pad)
    img = Image.new("RGB", (w, h), (255, 255, 250))
    draw = ImageDraw.Draw(img)
    for k, s in enumerate(lines):
        draw.text((pad, pad + k * line_h), s, fill=(20, 20, 30), font=font)
    buf = io.BytesIO()
    img.save(buf, format="PNG")
    return buf.getvalue(), w / h


# ------------------------------------------------------------------- composed views
def error_lines(result: Result, label: str | None = None) -> list[str]:
    """Text lines stating a result's solver, status and errors."""
    head = label or (result.solver or "solver") + (
        f" (seed {result.seed})" if result.seed is not None else ""
    )
    status = "reached" if result.success else "NOT reached"
    return [
        f"{head}: {status}",
        f"  position error {result.position_error:.2e} m, "
        f"rotation error {result.rotation_error:.2e} rad",
    ]


def _view_points(robot: RobotModel, q_list: Sequence[Any], target: Any) -> FloatArray:
    """Points a view should keep in sight: base, joint origins, end effector, target."""
    pts = [np.zeros(3)]
    model, data = robot.full_model, robot.full_model.createData()
    for q in q_list:
        pin.forwardKinematics(model, data, full_configuration(robot, q))
        pts += [np.array(m.translation) for m in data.oMi[1:]]
        pts.append(robot.fk(np.asarray(q, dtype=float))[:3, 3])
    if target is not None:
        pts.append(np.asarray(target)[:3, 3])
    return np.array(pts)


def _triad_length(robot: RobotModel) -> float:
    return 0.12 * _reach(robot)


def show_pose(
    robot: RobotModel,
    q: Any,
    *,
    target: Any = None,
    lines: Sequence[str] = (),
    ghost_q: Any = None,
    scene: Scene | None = None,
) -> Scene:
    """Draw ``robot`` at ``q`` with a triad at its end effector and, if given, at ``target``.

    Args:
        robot: The robot.
        q: Joint vector (rad / m), shape ``(nq,)``.
        target: Optional target pose (4x4, metres); drawn as a larger triad with a yellow ball.
        lines: Text shown on a sign beside the robot (e.g. the errors).
        ghost_q: Optional second configuration drawn ghosted (translucent orange), e.g. another
            solver's answer to the same target.
        scene: Scene to draw into (default: a new one).

    Returns:
        The scene (``scene.url`` for the live view, ``scene.save_html(path)`` to export).
    """
    q = robot.check_q(q)
    scene = Scene() if scene is None else scene
    scene.add_robot(robot, q, name="robot")
    length = _triad_length(robot)
    scene.add_triad("reached", robot.fk(q), length=0.8 * length)
    q_list = [q]
    if ghost_q is not None:
        ghost_q = robot.check_q(ghost_q, "ghost_q")
        scene.add_robot(robot, ghost_q, name="ghost", color=GHOST_COLOR)
        scene.add_triad("ghost_reached", robot.fk(ghost_q), length=0.8 * length, opacity=0.5)
        q_list.append(ghost_q)
    if target is not None:
        target = np.asarray(target, dtype=float)
        scene.add_triad(
            "target", target, length=length, radius=length / 18, sphere=(1.0, 0.85, 0.1, 0.45)
        )
    _label_and_frame(scene, _view_points(robot, q_list, target), lines, _reach(robot))
    return scene


def _label_and_frame(
    scene: Scene,
    pts: FloatArray,
    lines: Sequence[str],
    reach: float,
    direction: Sequence[float] = (1.0, 0.75, 0.45),
) -> None:
    """Put the text sign above ``pts`` facing the camera, then frame the camera on both."""
    d = np.asarray(direction, dtype=float)
    d = d / np.linalg.norm(d)
    if lines:
        _, aspect = _text_png(lines)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        size = max(float(np.linalg.norm(hi - lo)), 0.5 * reach)
        # a few hundredths of the scene per line, and no wider than most of the scene
        height = min(0.07 * size * len(lines), 0.9 * size / aspect)
        centre = np.array(
            [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), hi[2] + 0.12 * reach + 0.5 * height]
        )
        scene.add_label("label", lines, position=centre, height=height, facing=d)
        right = np.cross([0.0, 0.0, 1.0], d)
        right /= np.linalg.norm(right) or 1.0
        up = np.cross(d, right)
        half_w, half_h = 0.5 * height * aspect, 0.5 * height
        corners = [
            centre + sx * half_w * right + sz * half_h * up for sx in (-1, 1) for sz in (-1, 1)
        ]
        pts = np.vstack([pts, corners])
    scene.frame_camera(pts, direction=d)


def animate_trace(
    scene: Scene,
    robot: RobotModel,
    trace: Trace,
    *,
    name: str = "robot",
    fps: int = 20,
    max_frames: int = 200,
    hold_s: float = 1.0,
) -> int:
    """Replay the best-so-far configuration of each iteration as a meshcat animation.

    Args:
        scene: A scene holding ``robot`` under ``name`` (see :func:`show_pose`).
        robot: The robot.
        trace: The trace of :func:`solve_traced`.
        name: The drawing to animate; its ``reached`` triad moves with it.
        fps: Frames (iterations) per second.
        max_frames: Most frames; longer traces are subsampled evenly.
        hold_s: Seconds the final configuration is held at the end.

    Returns:
        The number of frames.
    """
    drawing = scene.robots[name]
    tr = trace.subsample(max_frames)
    anim = scene.animation(fps)
    triad = "reached" if name == "robot" else f"{name}_reached"
    n = len(tr)
    for i in range(n):
        with anim.at_frame(scene.visualizer, i) as frame:
            drawing.set_q(tr.q[i], frame=frame)
            frame[f"{ROOT}/{triad}"].set_transform(robot.fk(tr.q[i]))
    with anim.at_frame(scene.visualizer, n - 1 + int(round(hold_s * fps))) as frame:
        drawing.set_q(tr.q[-1], frame=frame)
        frame[f"{ROOT}/{triad}"].set_transform(robot.fk(tr.q[-1]))
    scene.play()
    return n


def show_result(
    problem: IKProblem,
    result: Result,
    *,
    trace: Trace | None = None,
    compare: Result | None = None,
    scene: Scene | None = None,
    fps: int = 20,
) -> Scene:
    """Draw a solve: the robot at ``result.q``, the target and reached triads, the errors.

    Args:
        problem: The solved problem.
        result: Its result.
        trace: Optional :class:`Trace` of the solve; its iterations are replayed as an
            animation (then the view ends on ``result.q``).
        compare: Optional result of another solver on the same problem, drawn ghosted.
        scene: Scene to draw into (default: a new one).
        fps: Animation frames per second.

    Returns:
        The scene.
    """
    lines = error_lines(result)
    if compare is not None:
        lines += error_lines(compare, f"{compare.solver} (ghost, orange)")
    if trace is not None:
        lines.append(f"animation: best-so-far over {len(trace.fitness)} iterations")
    scene = show_pose(
        problem.robot,
        result.q,
        target=problem.target,
        lines=lines,
        ghost_q=None if compare is None else compare.q,
        scene=scene,
    )
    if trace is not None:
        animate_trace(scene, problem.robot, trace, fps=fps)
    return scene


def show_configurations(
    robot: RobotModel,
    qs: Sequence[Any],
    *,
    target: Any = None,
    lines: Sequence[str] = (),
    layout: str = "side",
    spacing: float | None = None,
    hold_s: float = 1.5,
    scene: Scene | None = None,
) -> Scene:
    """Several configurations of one robot, side by side or stepped through.

    Args:
        robot: The robot.
        qs: Joint vectors (rad / m), each of shape ``(nq,)``.
        target: Optional target pose (4x4, metres), drawn beside each robot (``"side"``) or
            once (``"steps"``).
        lines: Text of the sign above the scene.
        layout: ``"side"``: one robot per configuration, in a row along y (left to right as
            seen from the camera); ``"steps"``: one robot, an animation holding each
            configuration ``hold_s`` seconds, looping.
        spacing: Distance between the robots in ``"side"`` layout [m] (default: 1.3 × the
            widest configuration across the row).
        hold_s: Seconds per configuration in ``"steps"`` layout.
        scene: Scene to draw into.

    Returns:
        The scene.

    Raises:
        UnknownNameError: unknown layout (the valid ones listed).
        InvalidArgumentError: no configuration given, or one of the wrong length.
    """
    from swarm_ik.errors import unknown

    if layout not in LAYOUTS:
        raise unknown("layout", layout, LAYOUTS)
    if len(qs) == 0:
        raise InvalidArgumentError("show_configurations needs at least one configuration")
    qs = [robot.check_q(q, f"configuration #{k + 1}") for k, q in enumerate(qs)]
    if layout == "steps":
        scene = show_pose(robot, qs[0], target=target, lines=lines, scene=scene)
        fps = 10
        per = max(1, int(round(hold_s * fps)))
        anim = scene.animation(fps)
        drawing = scene.robots["robot"]
        for k, q in enumerate([*qs, qs[-1]]):
            for i in (k * per, k * per + per - 1):
                with anim.at_frame(scene.visualizer, i) as frame:
                    drawing.set_q(q, frame=frame)
                    frame[f"{ROOT}/reached"].set_transform(robot.fk(q))
        scene.play(repetitions=1000)
        return scene
    scene = Scene() if scene is None else scene
    if spacing is None:  # 1.3 × the widest configuration (across the row), target included
        widths = [np.ptp(_view_points(robot, [q], target)[:, 1]) for q in qs]
        step = max(0.3 * _reach(robot), 1.3 * max(widths))
    else:
        step = float(spacing)
    length = _triad_length(robot)
    pts = []
    for k, q in enumerate(qs):
        # the camera looks from +x: +y is on the left, so the first robot gets the largest y
        off = np.array([0.0, (0.5 * (len(qs) - 1) - k) * step, 0.0])
        scene.add_robot(robot, q, name=f"solutions/{k}/robot", offset=off)
        scene.add_triad(
            f"solutions/{k}/reached", _translation(off) @ robot.fk(q), length=0.8 * length
        )
        if target is not None:
            scene.add_triad(
                f"solutions/{k}/target",
                _translation(off) @ np.asarray(target),
                length=length,
                radius=length / 18,
                sphere=(1.0, 0.85, 0.1, 0.45),
            )
        pts.append(_view_points(robot, [q], target) + off)
    _label_and_frame(scene, np.vstack(pts), lines, _reach(robot), direction=(1.0, 0.15, 0.35))
    return scene


def show_solutions(
    problem: IKProblem,
    results: Sequence[Result],
    *,
    layout: str = "side",
    hold_s: float = 1.5,
    scene: Scene | None = None,
) -> Scene:
    """Several solutions of one target (e.g. from ``swarm_ik.solve_many``), side by side
    (left to right) or stepped through; see :func:`show_configurations`.

    Raises:
        UnknownNameError: unknown layout (the valid ones listed).
        InvalidArgumentError: no result given.
    """
    if not results:
        raise InvalidArgumentError("show_solutions needs at least one result")
    order = "left to right" if layout == "side" else f"{hold_s:g} s each"
    lines = [f"{len(results)} solutions of one target ({order}):"]
    lines += [f"#{k + 1}: " + error_lines(r)[1].strip() for k, r in enumerate(results)]
    return show_configurations(
        problem.robot,
        [r.q for r in results],
        target=problem.target,
        lines=lines,
        layout=layout,
        hold_s=hold_s,
        scene=scene,
    )


def several_solutions(
    problem: IKProblem,
    n: int,
    *,
    solver: str | None = None,
    min_distance: float = 0.5,
    seed: int = 0,
    **solve_kwargs: Any,
) -> list[Result]:
    """Up to ``n`` distinct solutions of ``problem``.

    Without ``solver``, :func:`swarm_ik.solve_many` (when this version has it); with one (or
    without ``solve_many``), solves from successive seeds keeping the successes at least
    ``min_distance`` apart (Euclidean joint distance, rad / m; at most ``4 n`` solves).

    Args:
        problem: The problem.
        n: Solutions wanted, ``>= 1``.
        solver: Registry name, or ``None``.
        min_distance: Smallest joint-space distance between two kept solutions.
        seed: Seed (the first seed in the fallback).
        **solve_kwargs: Passed on (``max_evals``, ``tol_pos``, ``tol_rot``, ``q0``, …).

    Returns:
        The solutions, best first (the best unsuccessful result alone when none succeeded).
    """
    import swarm_ik

    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise InvalidArgumentError(f"n must be a positive integer, got {n!r}")
    if solver is None and hasattr(swarm_ik, "solve_many"):
        found = list(
            swarm_ik.solve_many(problem, n, min_distance=min_distance, seed=seed, **solve_kwargs)
        )
        if found:
            return found
        return [swarm_ik.solve(problem, seed=seed, **solve_kwargs)]
    kept: list[Result] = []
    best: Result | None = None
    for s in range(seed, seed + 4 * n):
        r = swarm_ik.solve(problem, solver or swarm_ik.api.DEFAULT_SOLVER, seed=s, **solve_kwargs)
        if best is None or r.fitness < best.fitness:
            best = r
        if r.success and all(np.linalg.norm(r.q - k.q) >= min_distance for k in kept):
            kept.append(r)
            if len(kept) == n:
                break
    kept.sort(key=lambda r: r.fitness)
    return kept or ([best] if best is not None else [])
