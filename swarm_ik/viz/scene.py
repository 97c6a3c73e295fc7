"""The scene: robots, pose triads, text signs, a floor, the camera and an animation, drawn
with meshcat and kept as a list of commands (live view on demand, HTML export any time).

Every object sits in a ``shape`` child of the node that is placed: meshcat's
``set_transform`` replaces the matrix of the object at a path, which would drop the object's
own built-in transform.
"""

from __future__ import annotations

import contextlib
import io
import os
import sys
import tempfile
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from swarm_ik._types import FloatArray
from swarm_ik._validate import floats_or, positive_float
from swarm_ik.errors import InvalidArgumentError, SwarmIKError
from swarm_ik.goals.base import vec3
from swarm_ik.paths import written_in_place_of
from swarm_ik.robot import RobotModel
from swarm_ik.viz.export import CommandLog, check_output_path, static_html
from swarm_ik.viz.geometry import full_configuration, rgb_int, shape_loader, visual_model

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


def translation(p: Any) -> FloatArray:
    """The 4x4 transform translating by ``p`` [m], shape ``(3,)``."""
    t = np.eye(4)
    t[:3, 3] = np.asarray(p, dtype=float)
    return t


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
        loader = shape_loader()(self._model, None, geom)
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


@contextlib.contextmanager
def _quiet() -> Any:
    """Silence meshcat's and Pinocchio's chatter on stdout."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield


# ------------------------------------------------------------------------------ scene
class Scene:
    """A meshcat scene: robots, pose triads, text labels, an animation; live or exported.

    A scene records its meshcat commands (:class:`~swarm_ik.viz.export.CommandLog`): writing
    it to HTML (:meth:`save_html`) needs no server; asking for :attr:`url` starts meshcat's
    local server (loopback only, stopped by :meth:`close` or at exit) and sends it the scene.
    :meth:`frame_camera` re-centres the content so that meshcat's camera, which orbits the
    origin, orbits it.

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
        self._log = CommandLog()
        self.visualizer = meshcat.Visualizer(window=self._log)
        self.visualizer[ROOT].delete()
        self.visualizer["/Background"].set_property("top_color", [0.97, 0.97, 0.98])
        self.visualizer["/Background"].set_property("bottom_color", [0.72, 0.75, 0.80])
        self._geoms: dict[int, Any] = {}
        self._anim: Any = None
        self._center = np.zeros(3)
        self.robots: dict[str, RobotDrawing] = {}

    @property
    def url(self) -> str:
        """Address of the live viewer (``http://127.0.0.1:PORT/static/``); the first use
        starts meshcat's server."""
        return self._log.web_url

    @property
    def is_live(self) -> bool:
        """Whether the live viewer's server was started."""
        return self._log.is_live

    @property
    def commands(self) -> list[dict[str, Any]]:
        """The scene's meshcat commands (lowered dicts), in order."""
        return self._log.commands

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
        if color is not None:
            color = _rgba(color, "color")
        if offset is not None:
            offset = vec3(offset, "offset [m]")
        geom = self._geoms.get(id(robot))
        if geom is None:
            geom = self._geoms[id(robot)] = visual_model(robot)
        path = f"{ROOT}/{name}"
        drawing = RobotDrawing(self, robot, path, geom, color)
        if offset is not None:
            self.visualizer[path].set_transform(translation(offset))
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

        pose = _finite(pose, (4, 4), "pose")
        length = positive_float(length, "length [m]")
        radius = None if radius is None else positive_float(radius, "radius [m] (or None)")
        opacity = float(_finite(opacity, (), "opacity"))
        if not 0.0 <= opacity <= 1.0:
            raise InvalidArgumentError(f"opacity must lie in [0, 1], got {opacity}")
        if sphere is not None:
            sphere = _rgba(sphere, "sphere")
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
                color=rgb_int(sphere), opacity=float(sphere[3]), transparent=float(sphere[3]) < 1.0
            )
            node["origin"]["shape"].set_object(mg.Sphere(length / 5.0), mat)
        node.set_transform(pose)

    def add_label(self, name: str, lines: Sequence[str], **placement: Any) -> None:
        """A flat sign with text (a texture), standing upright: :meth:`add_image` of the text
        rendered by :func:`text_png` (the width follows the text).

        Args:
            name: Node name inside the scene.
            lines: Text lines.
            **placement: ``position`` (required), ``height``, ``facing`` as :meth:`add_image`.
        """
        png, aspect = text_png(lines)
        self.add_image(name, png, aspect, **placement)

    def add_image(
        self,
        name: str,
        png: bytes,
        aspect: float,
        *,
        position: Any,
        height: float = 0.1,
        facing: Any = (1.0, 0.0, 0.0),
    ) -> None:
        """A flat upright sign showing a PNG image (a texture), e.g. a colour legend.

        Args:
            name: Node name inside the scene.
            png: The image, PNG bytes.
            aspect: Its width / height ratio.
            position: Centre of the sign [m], shape ``(3,)``.
            height: Height of the sign [m]; the width is ``aspect × height``.
            facing: Direction the image faces (towards the camera), shape ``(3,)``; its up
                is the world's z tilted to be square to it.
        """
        import meshcat.geometry as mg

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

    def add_point(
        self,
        name: str,
        position: Any,
        *,
        radius: float = 0.03,
        rgba: Sequence[float] = (1, 0, 0, 1),
    ) -> None:
        """A ball at a point (e.g. a centre of mass).

        Args:
            name: Node name inside the scene.
            position: Its centre [m], shape ``(3,)``.
            radius: Its radius [m].
            rgba: Its colour and opacity in ``[0, 1]``.
        """
        import meshcat.geometry as mg

        mat = mg.MeshLambertMaterial(
            color=rgb_int(rgba), opacity=float(rgba[3]), transparent=float(rgba[3]) < 1.0
        )
        node = self.node(name)
        node["shape"].set_object(mg.Sphere(radius), mat)
        node.set_transform(translation(position))

    def add_polygon(
        self, name: str, vertices: Any, *, z: float = 0.0, color: int = 0x20A020
    ) -> None:
        """A closed polygon outline on the plane at height ``z`` (e.g. a support polygon).

        Args:
            name: Node name inside the scene.
            vertices: Its (x, y) vertices [m], shape ``(k, 2)``.
            z: Height of the plane [m].
            color: Line colour ``0xRRGGBB``.
        """
        import meshcat.geometry as mg

        xy = np.asarray(vertices, dtype=float).reshape(-1, 2)
        segs = []
        for a, b in zip(xy, np.roll(xy, -1, axis=0), strict=True):
            segs += [[a[0], a[1], z], [b[0], b[1], z]]
        verts = np.asarray(segs, dtype=np.float32).T
        self.node(name).set_object(
            mg.LineSegments(mg.PointsGeometry(verts), mg.LineBasicMaterial(color=color))
        )

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
        pts = np.atleast_2d(_finite(points, None, "points [m]"))
        if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] == 0:
            raise InvalidArgumentError(f"points must have shape (n, 3), n >= 1; got {pts.shape}")
        d = vec3(direction, "direction", unit=True)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        center = 0.5 * (lo + hi)
        radius = max(0.25, 0.5 * float(np.linalg.norm(hi - lo)))
        self._center = center
        self.visualizer[ROOT].set_transform(translation(-center))
        # a floor that stays in front of the camera (lines passing behind it get lost)
        self.add_floor(center[:2], 0.95 * radius)
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
    def to_html(self, title: str = "swarm_ik") -> str:
        """The whole scene (animation included) as one self-contained HTML page; every mesh
        file is embedded once, however many robots use it."""
        return static_html(self._log.commands, title=title)

    def save_html(self, path: str | os.PathLike[str], title: str = "swarm_ik") -> Path:
        """Write :meth:`to_html` to ``path`` (``.html``/``.htm``); returns the path written.

        Raises:
            InvalidArgumentError: the path is a folder, lies in a missing folder, or has
                another suffix.
        """
        p = check_output_path(path, "HTML file", (".html", ".htm"))
        with written_in_place_of(p) as part:  # (never a partial page)
            part.write_text(self.to_html(title), encoding="utf-8")
        return p

    def publish(
        self, html: str | os.PathLike[str] | None, name: str, *, quick: bool = False
    ) -> str:
        """Hand the scene over: written to ``html`` when given; with ``quick`` (a test run)
        written to a temporary ``name`` and deleted; else served live: its address printed,
        then kept up until Enter on a terminal (:func:`served`).  Returns the line to print
        (the page written, or how the viewer ended)."""
        if html is not None:
            return f"wrote {self.save_html(html)}"
        if quick:
            with tempfile.TemporaryDirectory() as tmp:
                path = self.save_html(Path(tmp) / name)
                return f"wrote a {path.stat().st_size / 1e6:.1f} MB page (quick run: deleted)"
        print(f"meshcat viewer at {self.url}", flush=True)
        return served(self)  # (the URL of a viewer closed as the script ends is no use)

    def close(self) -> None:
        """Stop the meshcat server of this scene, if one was started (it also stops when
        Python exits)."""
        self._log.close()

    def __enter__(self) -> Scene:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def viewer_for(html: str | os.PathLike[str] | None) -> bool:
    """For a script that draws its answer: whether meshcat is there to draw it.  Without it,
    a page asked for (``html``) is a failure: one line on stderr and exit 2; else one line
    says the viewer is skipped and False is returned."""
    try:
        require_meshcat()
    except VizUnavailableError as exc:
        if html is not None:
            print(f"cannot write {os.fspath(html)}: {exc}", file=sys.stderr)
            raise SystemExit(2) from None
        print(f"viewer skipped: {exc}")
        return False
    return True


def served(*scenes: Scene, hint: str = "--html FILE writes a page") -> str:
    """Keep the live viewers of ``scenes`` up until Enter is pressed on a terminal (at once
    without one, or with ``SWARM_IK_NO_WAIT=1``), then close them; returns the line to print
    (``hint``: how the caller writes pages instead, said when no terminal waits)."""
    no_wait = os.environ.get("SWARM_IK_NO_WAIT", "") not in ("", "0")
    try:
        if no_wait or sys.stdin is None or not sys.stdin.isatty():
            return f"no terminal to wait on: the viewer closes ({hint})"
        input("open it in a browser; press Enter to quit ")
        return "viewer closed"
    finally:
        for sc in scenes:
            sc.close()


def _nice_step(x: float) -> float:
    """The largest of 1, 2, 5 × 10^k not above ``x`` (``x > 0``)."""
    k = np.floor(np.log10(x))
    for m in (5.0, 2.0, 1.0):
        if m * 10**k <= x:
            return float(m * 10**k)
    return float(10**k)


def text_png(lines: Sequence[str], font_px: int = 28) -> tuple[bytes, float]:
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


def _finite(value: Any, shape: tuple[int, ...] | None, what: str) -> FloatArray:
    """``value`` as finite floats of ``shape`` (None: any), or :class:`InvalidArgumentError`
    naming ``what``."""
    arr = floats_or(value, lambda: f"{what} must be numbers, got {value!r}")
    if shape is not None and arr.shape != shape:
        raise InvalidArgumentError(f"{what} must have shape {shape}, got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InvalidArgumentError(f"{what} must be finite, got {arr.tolist()}")
    return arr


def _rgba(value: Any, what: str) -> list[float]:
    """An RGBA colour: four numbers in ``[0, 1]``, or :class:`InvalidArgumentError`."""
    arr = _finite(value, (4,), f"{what} (RGBA)")
    if np.any(arr < 0.0) or np.any(arr > 1.0):
        raise InvalidArgumentError(f"{what} (RGBA) must lie in [0, 1], got {arr.tolist()}")
    return [float(v) for v in arr]
