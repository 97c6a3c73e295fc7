"""``AvoidCollisions``: no contact with the robot itself nor with a scene."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numba
import numpy as np

from swarm_ik.errors import InvalidArgumentError
from swarm_ik.goals.base import Encoded, FloatArray, Goal, State, non_negative, weight_value
from swarm_ik.kernels.spheres import SphereArrays, penetration

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel

_HEAD = 7
"""Integer header of the parameter block: body0, nb, ns, npair, nob, no, max_rows."""


@numba.njit(cache=True)
def collision_kernel(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Rows ``−max(0, margin + r_i + r_j − ‖c_i − c_j‖)`` of the deepest active sphere pairs
    (:func:`swarm_ik.kernels.spheres.penetration`), the unused rows zero; error: the deepest
    penetration [m].  The parameter block is the sphere model (:func:`pack`)."""
    b0, nb, ns, npair, nob, no, max_rows = (
        ipar[0], ipar[1], ipar[2], ipar[3], ipar[4], ipar[5], ipar[6]
    )  # fmt: skip
    o = 7
    sph_body = ipar[o : o + ns]
    o += ns
    body_start = ipar[o : o + nb + 1]
    o += nb + 1
    self_pairs = ipar[o : o + 2 * npair].reshape((npair, 2))
    o += 2 * npair
    obs_bodies = ipar[o : o + nob]
    o += nob
    obs_kind = ipar[o : o + no]
    o += no
    pair = ipar[o : o + 2 * max_rows].reshape((max_rows, 2))
    margin = par[0]
    p = 1
    sph_local = par[p : p + 3 * ns].reshape((ns, 3))
    p += 3 * ns
    sph_radius = par[p : p + ns]
    p += ns
    bound_local = par[p : p + 3 * nb].reshape((nb, 3))
    p += 3 * nb
    bound_radius = par[p : p + nb]
    p += nb
    obs_rot = par[p : p + 9 * no].reshape((no, 3, 3))
    p += 9 * no
    obs_pos = par[p : p + 3 * no].reshape((no, 3))
    p += 3 * no
    obs_dims = par[p : p + 3 * no].reshape((no, 3))
    p += 3 * no
    scratch = par[p : p + 6 * ns].reshape((ns, 6))
    model = SphereArrays(
        sph_body, sph_local, sph_radius, body_start, bound_local, bound_radius, self_pairs,
        obs_bodies, obs_kind, obs_rot, obs_pos, obs_dims,
    )  # fmt: skip
    nr = res.shape[0]
    b1 = b0 + nb
    used, _, worst = penetration(
        f_rot[b0:b1], f_pos[b0:b1], f_jac[b0:b1], model, margin, scratch, True, res, jac,
        pair[:nr],
    )  # fmt: skip
    for a in range(nr):
        if a < used:
            res[a] = -res[a]  # r = −penetration: r(q + δ) ≈ r − J δ
        else:
            res[a] = 0.0
            for j in range(jac.shape[1]):
                jac[a, j] = 0.0
    err[0] = worst
    err[1] = np.nan


def pack(arrays: SphereArrays, body0: int, margin: float, max_rows: int) -> Encoded:
    """The sphere model as the parameter block of :func:`collision_kernel` (with its
    scratch: the world sphere centres and the row pairs)."""
    a = arrays
    ns, nb = int(a.sph_body.shape[0]), int(a.bound_radius.shape[0])
    npair, nob, no = (
        int(a.self_pairs.shape[0]),
        int(a.obs_bodies.shape[0]),
        int(a.obs_kind.shape[0]),
    )
    i64 = np.int64
    ipar = np.concatenate([
        np.array([body0, nb, ns, npair, nob, no, max_rows], dtype=i64),
        np.asarray(a.sph_body, i64), np.asarray(a.body_start, i64),
        np.asarray(a.self_pairs, i64).ravel(), np.asarray(a.obs_bodies, i64),
        np.asarray(a.obs_kind, i64), np.zeros(2 * max_rows, i64),
    ])  # fmt: skip
    par = np.concatenate([
        [margin], np.ravel(a.sph_local), np.ravel(a.sph_radius), np.ravel(a.bound_local),
        np.ravel(a.bound_radius), np.ravel(a.obs_rot), np.ravel(a.obs_pos), np.ravel(a.obs_dims),
        np.zeros(6 * ns),
    ]).astype(float)  # fmt: skip
    return Encoded(par, ipar, max_rows)


MAX_ROWS_LIMIT = 4096
"""Most penetration rows an AvoidCollisions goal may ask for (each row is a row of the
Jacobian the LM factors)."""


@dataclass(frozen=True)
class AvoidCollisions(Goal):
    """No contact between the robot's collision bodies (self-collision) nor with a scene.

    A primary constraint.  In the search, every collision body is covered by spheres
    (conservative: spheres apart ⇒ bodies apart, :mod:`swarm_ik.spheres`) and each active
    sphere pair contributes a row ``r = −max(0, margin + r_i + r_j − ‖c_i − c_j‖)``
    (obstacles: their exact signed distance) with its Jacobian, up to ``max_rows`` rows (the
    deepest first).  The answer is judged by the exact check with coal on the URDF's collision
    geometry (:meth:`swarm_ik.collision.RobotCollision.check`): success only without contact
    closer than ``margin``; ``Result.goal_errors[i].details`` (a
    :class:`~swarm_ik.collision.CollisionReport`) gives the clearance and the pairs in contact.
    At most one per problem.

    Args:
        scene: Obstacles: a :class:`swarm_ik.scene.Scene`, a list of shapes, a scene JSON
            file, or None (self-collision only).
        self_collision: Check the robot against itself (pairs: all link pairs minus adjacent
            links minus the SRDF's disabled pairs, see :mod:`swarm_ik.collision`).
        margin: Wanted clearance [m], ``>= 0``.
        max_rows: Most penetration rows per evaluation, 1 to 4096 (keyword-only).
        tolerance: Sphere fitting tolerance [m], at least 1 mm (how far a sphere may stick out
            of its body; keyword-only).
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only).
    """

    scene: Any = None
    self_collision: bool = True
    margin: float = 0.0
    max_rows: int = field(default=24, kw_only=True)
    tolerance: float = field(default=0.02, kw_only=True)
    kernel: ClassVar[Any] = collision_kernel

    def __post_init__(self) -> None:
        from swarm_ik.scene import as_scene

        object.__setattr__(self, "scene", as_scene(self.scene))
        super().__post_init__()
        if not isinstance(self.self_collision, (bool, np.bool_)):
            raise InvalidArgumentError(
                f"AvoidCollisions.self_collision must be true or false, got {self.self_collision!r}"
            )
        object.__setattr__(self, "margin", non_negative(self.margin, "AvoidCollisions.margin"))
        rows = self.max_rows
        if (
            isinstance(rows, bool)
            or not isinstance(rows, (int, np.integer))
            or not (1 <= rows <= MAX_ROWS_LIMIT)
        ):
            raise InvalidArgumentError(
                f"AvoidCollisions.max_rows must be a positive integer (at most {MAX_ROWS_LIMIT}), "
                f"got {rows!r}"
            )
        object.__setattr__(self, "max_rows", int(rows))
        tol = weight_value(self.tolerance, "AvoidCollisions.tolerance")
        if tol < 1e-3:
            raise InvalidArgumentError(
                "AvoidCollisions.tolerance must be at least 0.001 m (finer sphere fits grow "
                f"without bound), got {self.tolerance!r}"
            )
        object.__setattr__(self, "tolerance", tol)

    def describe(self) -> str:
        return "AvoidCollisions"

    def obstacle_containing(self, point: Any, depth: float = 0.0) -> str | None:
        """Name of a scene obstacle whose inside holds the world ``point`` [m] deeper than
        ``depth`` [m], if any (coal's signed distance of a point-sized probe)."""
        if len(self.scene) == 0:
            return None
        import coal

        p = np.asarray(point, dtype=float)
        probe = coal.CollisionObject(coal.Sphere(1e-9), coal.Transform3s(np.eye(3), p))
        lo, hi = self.scene.boxes()
        objects = self.scene.coal_objects()
        for k in np.flatnonzero(np.all((lo <= p) & (p <= hi), axis=1)).tolist():
            name, obj = objects[k]  # (only an obstacle whose box holds the point can)
            req, res = coal.DistanceRequest(), coal.DistanceResult()
            if coal.distance(obj, probe, req, res) < -depth:
                return str(name)
        return None

    def spheres(self, robot: RobotModel) -> Any:
        """The sphere model of the robot and the scene (cached on the robot)."""
        from swarm_ik.spheres import SphereModel

        key = ("spheres", self.scene, bool(self.self_collision), self.tolerance)
        sm = robot._cache.get(key)
        if sm is None:
            sm = SphereModel.from_collision(
                robot.collision_model(), self.scene, tolerance=self.tolerance,
                self_collision=bool(self.self_collision),
            )  # fmt: skip
            robot._cache[key] = sm
            self.scene.boxes()  # (the exact check's coal objects, made before any clock)
        return sm

    def extra_frames(self, robot: RobotModel) -> tuple[Any, Any, Any] | None:
        sm = self.spheres(robot)
        return sm.body_joint, sm.body_frame_rot, sm.body_frame_pos

    def encode(
        self, robot: RobotModel, q0: FloatArray | None, frame0: int | None = None
    ) -> Encoded:
        """The sphere model as the goal's parameter block; its bodies are the frames from
        ``frame0`` on (default: right after the robot's goal frames; :meth:`extra_frames`,
        appended by the problem; made once per robot, scene and settings, read-only: each
        problem of the goal encodes it, and a goal table copies it)."""
        body0 = len(robot.frames) if frame0 is None else frame0
        key = (self.scene, bool(self.self_collision), self.tolerance, body0, self.margin,
               self.max_rows)  # fmt: skip
        packed = robot._cache.setdefault("packed", {})
        enc = packed.get(key)
        if enc is None:
            self._warn_always_in_contact(robot)
            enc = pack(self.spheres(robot).arrays, body0, float(self.margin), self.max_rows)
            enc.par.flags.writeable = False
            enc.ipar.flags.writeable = False
            if len(packed) >= 32:  # (many scenes: keep memory bounded)
                packed.clear()
            packed[key] = enc
        return enc

    def _warn_always_in_contact(self, robot: RobotModel) -> None:
        """One warning per robot, scene and margin naming the pairs closer than the margin in
        every sampled configuration
        (:meth:`~swarm_ik.collision.RobotCollision.pairs_always_in_contact`): solves that
        cannot meet this goal otherwise end without saying why."""
        from swarm_ik._validate import user_stacklevel
        from swarm_ik.collision import ALWAYS_SAMPLES

        key = (self.scene, bool(self.self_collision), self.margin)
        seen = robot._cache.setdefault("always_in_contact", set())
        if key in seen:
            return
        seen.add(key)
        pairs = robot.collision_model().pairs_always_in_contact(
            self.scene, self.margin, bool(self.self_collision)
        )
        if pairs:
            near = "closer than the margin" if self.margin > 0 else "in contact"
            warnings.warn(
                f"AvoidCollisions(margin={self.margin:g} m): "
                f"{', '.join(f'{a}–{b}' for a, b in pairs)} {near} in each of "
                f"{ALWAYS_SAMPLES} random configurations: no answer may be free of contact "
                "(lower the margin, disable a self pair in the robot's SRDF, or move the "
                "obstacle)",
                stacklevel=user_stacklevel(),
            )

    def met(self, state: State, tol_pos: float, tol_rot: float) -> tuple[float, float, bool, Any]:
        """The exact check with coal: met only without contact closer than ``margin``; the
        details are a :class:`~swarm_ik.collision.CollisionReport` (for a free answer a
        :class:`~swarm_ik.collision.DeferredReport`, whose clearance is computed when read)."""
        from swarm_ik.collision import DeferredReport

        rc = state.robot.collision_model()
        self_col = bool(self.self_collision)
        if not rc.collides(state.q, self.scene, self.margin, self_col):
            return (
                0.0,
                float("nan"),
                True,
                DeferredReport(rc, state.q, self.scene, self.margin, self_col),
            )
        rep = rc.check(state.q, self.scene, self.margin, self_col)
        depth = 0.0 if rep.collision_free else max(0.0, self.margin - rep.clearance)
        return depth, float("nan"), bool(rep.collision_free), rep

    def errors(self, state: State) -> tuple[float, float]:
        depth, nan, _met, _report = self.met(state, 0.0, 0.0)
        return depth, nan

    def residual(self, state: State) -> FloatArray:
        raise InvalidArgumentError(
            "AvoidCollisions has no numpy residual: see swarm_ik.spheres.SphereModel.evaluate"
        )
