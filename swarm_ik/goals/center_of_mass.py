"""``CenterOfMass``: the whole robot's centre of mass at a point, or over a support polygon."""

from __future__ import annotations

import math
import reprlib
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numba
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from swarm_ik._validate import floats_or
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.goals.base import Encoded, FloatArray, Goal, State, non_negative, vec3

if TYPE_CHECKING:
    from swarm_ik.robot import RobotModel

AXES = {"x": 0, "y": 1, "z": 2}


@numba.njit(cache=True, inline="always")
def _polygon_distance(
    cx: float, cy: float, vx: FloatArray, vy: FloatArray
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """Signed distance [m] of the point ``(cx, cy)`` to a simple polygon (vertices ``vx``,
    ``vy``, ``(k,)``): negative inside; and the unit gradient ``(gx, gy)`` of that distance
    (pointing away from the polygon outside, towards the nearest edge inside)."""
    k = vx.shape[0]
    best = np.inf
    bx = 0.0
    by = 0.0
    inside = False
    for e in range(k):
        ax, ay = vx[e], vy[e]
        ex, ey = vx[(e + 1) % k] - ax, vy[(e + 1) % k] - ay
        t = ((cx - ax) * ex + (cy - ay) * ey) / (ex * ex + ey * ey)
        t = min(1.0, max(0.0, t))
        px, py = ax + t * ex, ay + t * ey
        d2 = (cx - px) * (cx - px) + (cy - py) * (cy - py)
        if d2 < best:
            best, bx, by = d2, px, py
        if (ay > cy) != (ay + ey > cy):  # crossing number (even-odd rule)
            if cx < ax + (cy - ay) * ex / ey:
                inside = not inside
    d = math.sqrt(best)
    if d < 1e-12:
        return 0.0, 0.0, 0.0
    gx, gy = (cx - bx) / d, (cy - by) / d
    if inside:
        return -d, -gx, -gy
    return d, gx, gy


@numba.njit(cache=True)
def center_of_mass_kernel(par, ipar, q, f_pos, f_rot, f_jac, want_jac, res, jac, err, work):  # type: ignore[no-untyped-def]  # pragma: no cover
    """Rows of the centre of mass ``c = Σ_b μ_b p_b`` (``μ_b = m_b / M``, ``p_b`` the world
    position of body ``b``'s centre of mass, a frame of the tree); Jacobian ``Σ_b μ_b J_v,b``.

    ``ipar = [nb, frame0, n_axes, has_support, axis ids…]``; ``par = [μ (nb), point (3),
    margin, vertices x (k), vertices y (k)]``.  Rows: ``p*_a − c_a`` for each axis, then, with a
    support polygon, ``−max(0, d + margin)`` (``d`` the signed distance of ``(c_x, c_y)`` to
    the polygon, negative inside) with Jacobian ``∇d · J_c,xy`` while active.
    """
    nb, f0, na, has_support = ipar[0], ipar[1], ipar[2], ipar[3]
    mu = par[0:nb]
    nq = q.shape[0]
    c = work[0:3]
    for a in range(3):
        s = 0.0
        for b in range(nb):
            s += mu[b] * f_pos[f0 + b, a]
        c[a] = s
    e2 = 0.0
    for r in range(na):
        a = ipar[4 + r]
        d = par[nb + a] - c[a]
        res[r] = d
        e2 += d * d
        if want_jac:
            for j in range(nq):
                s = 0.0
                for b in range(nb):
                    s += mu[b] * f_jac[f0 + b, a, j]
                jac[r, j] = s
    if has_support == 1:
        margin = par[nb + 3]
        k = (par.shape[0] - nb - 4) // 2
        vx = par[nb + 4 : nb + 4 + k]
        vy = par[nb + 4 + k : nb + 4 + 2 * k]
        d, gx, gy = _polygon_distance(c[0], c[1], vx, vy)
        out = max(0.0, d + margin)
        res[na] = -out
        e2 += out * out
        if want_jac:
            for j in range(nq):
                s = 0.0
                if out > 0.0:
                    for b in range(nb):
                        s += mu[b] * (gx * f_jac[f0 + b, 0, j] + gy * f_jac[f0 + b, 1, j])
                jac[na, j] = s
    err[0] = math.sqrt(e2)
    err[1] = np.nan


MAX_SUPPORT_VERTICES = 256
"""Most vertices of a support polygon (:func:`support_polygon`): a polygon of feet or wheels
has a few dozen; the goal's row measures the distance to every edge at each evaluation, and
its checks pair every edge with every other (review 133: 2,000 vertices took 10 s to check)."""


def _crossing_edges(poly: FloatArray) -> tuple[int, int] | None:
    """The first pair ``(i, j)``, ``i < j``, of non-adjacent edges of the closed polygon
    ``poly`` ``(k, 2)`` that intersect (edge ``i`` runs from vertex ``i`` to ``i + 1``), or
    None: every pair at once, by the signs of the orientations (collinear overlaps count)."""
    k = poly.shape[0]
    a, b = poly, np.roll(poly, -1, axis=0)  # edge i: a[i] → b[i]

    def orient(p: FloatArray, q: FloatArray, r: FloatArray) -> FloatArray:
        return (q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1]) - (q[..., 1] - p[..., 1]) * (
            r[..., 0] - p[..., 0]
        )

    def on(p: FloatArray, q: FloatArray, r: FloatArray) -> NDArray[np.bool_]:
        return (
            (np.minimum(p[..., 0], q[..., 0]) <= r[..., 0])
            & (r[..., 0] <= np.maximum(p[..., 0], q[..., 0]))
            & (np.minimum(p[..., 1], q[..., 1]) <= r[..., 1])
            & (r[..., 1] <= np.maximum(p[..., 1], q[..., 1]))
        )

    p1, p2 = a[:, None], b[:, None]  # edge i (rows)
    p3, p4 = a[None, :], b[None, :]  # edge j (columns)
    d1, d2 = orient(p3, p4, p1), orient(p3, p4, p2)
    d3, d4 = orient(p1, p2, p3), orient(p1, p2, p4)
    proper = ((d1 > 0) != (d2 > 0)) & ((d3 > 0) != (d4 > 0)) & (d1 != 0) & (d2 != 0)
    proper &= (d3 != 0) & (d4 != 0)
    touch = (d1 == 0) & on(p3, p4, p1) | (d2 == 0) & on(p3, p4, p2)
    touch |= (d3 == 0) & on(p1, p2, p3) | (d4 == 0) & on(p1, p2, p4)
    i, j = np.triu_indices(k, 1)
    pairs = (j != i + 1) & ~((i == 0) & (j == k - 1))  # (adjacent edges share a vertex)
    hit = np.flatnonzero((proper | touch)[i, j] & pairs)
    return None if hit.size == 0 else (int(i[hit[0]]), int(j[hit[0]]))


def support_polygon(value: Any) -> FloatArray:
    """A support polygon as ``(k, 2)`` world (x, y) vertices [m], validated: 3 to
    :data:`MAX_SUPPORT_VERTICES` finite vertices, no repeated vertex, not self-intersecting,
    non-zero area.

    Raises:
        InvalidArgumentError: naming what is wrong.
    """
    poly = floats_or(
        value, lambda: f"CenterOfMass.support must be (x, y) vertices, got {reprlib.repr(value)}"
    )
    if poly.ndim != 2 or poly.shape[1] != 2 or poly.shape[0] < 3:
        raise InvalidArgumentError(
            f"CenterOfMass.support must be at least 3 (x, y) vertices, got shape {poly.shape}"
        )
    if poly.shape[0] > MAX_SUPPORT_VERTICES:
        raise InvalidArgumentError(
            f"CenterOfMass.support has {poly.shape[0]} vertices, more than "
            f"{MAX_SUPPORT_VERTICES}: give a simpler polygon (e.g. the convex hull of the "
            "contacts, scipy.spatial.ConvexHull)"
        )
    if not np.all(np.isfinite(poly)):
        raise InvalidArgumentError("CenterOfMass.support vertices must be finite")
    _, first, counts = np.unique(poly, axis=0, return_index=True, return_counts=True)
    if np.any(counts > 1):
        repeated = poly[int(np.min(first[counts > 1]))]
        raise InvalidArgumentError(f"CenterOfMass.support repeats vertex {repeated.tolist()}")
    # (first: a bow-tie's two halves can cancel to a zero area)
    crossing = _crossing_edges(poly)
    if crossing is not None:
        raise InvalidArgumentError(
            f"CenterOfMass.support is self-intersecting (edges {crossing[0]} and {crossing[1]})"
        )
    area = 0.5 * float(
        np.sum(poly[:, 0] * np.roll(poly[:, 1], -1) - np.roll(poly[:, 0], -1) * poly[:, 1])
    )
    if abs(area) < 1e-12:
        raise InvalidArgumentError("CenterOfMass.support has zero area")
    return poly


@numba.njit(cache=True)
def _deepest_bound(
    vx: FloatArray, vy: FloatArray, box: FloatArray, n: int, tol: float, cap: int, enough: float
) -> float:  # pragma: no cover - compiled
    """Branch and bound on the depth ``−d`` inside the polygon (``vx``, ``vy``)
    (:func:`_polygon_distance`): the bounding box ``lo``–``hi`` cut into square cells, ``n``
    along its longer side, each
    cell bounded by the depth at its centre plus its half diagonal (the distance changes by at
    most the distance moved); cells that may hold a point deeper than the deepest centre seen
    by more than ``tol`` are split in four, the others dropped.  Returns an upper bound on the
    depth of every point, within ``tol`` of the true largest depth, or the bound of the cells
    left when ``cap`` cells would be exceeded; or, as soon as a centre at least ``enough``
    deep is found, its depth (the question "is any point that deep?" answered: yes).  ``box``:
    the bounding box, rows ``lo``, ``hi``."""
    lo, hi = box[0], box[1]
    h = 0.5 * max(hi[0] - lo[0], hi[1] - lo[1]) / n  # (square cells)
    ni = int(math.ceil(0.5 * (hi[0] - lo[0]) / h))
    nj = int(math.ceil(0.5 * (hi[1] - lo[1]) / h))
    hx, hy = h, h
    cx = np.empty(ni * nj)
    cy = np.empty(ni * nj)
    for i in range(ni):
        for j in range(nj):
            cx[i * nj + j] = lo[0] + (2 * i + 1) * h
            cy[i * nj + j] = lo[1] + (2 * j + 1) * h
    best = 0.0  # (depth 0: a point of the boundary)
    while True:
        m = cx.shape[0]
        depth = np.empty(m)
        for c in range(m):
            depth[c] = -_polygon_distance(cx[c], cy[c], vx, vy)[0]
            best = max(best, depth[c])
        if best >= enough:
            return best
        r = math.sqrt(hx * hx + hy * hy)
        keep = depth + r > best + tol
        k = int(keep.sum())
        if k == 0:
            return best + tol
        if 4 * k > cap:
            return max(best + tol, float(np.max(depth[keep])) + r)
        hx, hy = 0.5 * hx, 0.5 * hy
        nx = np.empty(4 * k)
        ny = np.empty(4 * k)
        o = 0
        for c in range(m):
            if keep[c]:
                for sx in (-1.0, 1.0):
                    for sy in (-1.0, 1.0):
                        nx[o] = cx[c] + sx * hx
                        ny[o] = cy[c] + sy * hy
                        o += 1
        cx, cy = nx, ny


DEEPEST_TOL = 1e-6
"""How far above the true inscribed radius [m] :func:`deepest_inside`'s bound may lie."""


def deepest_inside(
    poly: FloatArray, n: int = 32, max_cells: int = 1 << 18, enough: float = math.inf
) -> float:
    """An upper bound [m] on how far inside the simple polygon ``poly`` ``(k, 2)`` a point
    can lie (the radius of its largest inscribed circle), so that a margin beyond it is
    surely unmet: within :data:`DEEPEST_TOL` of the radius (:func:`_deepest_bound`, square
    cells, ``n`` along the longer side, split where they may hold the deepest point), except
    for a polygon whose deepest points fill a segment (a rectangle's), whose cells reach
    ``max_cells`` first: there within about ``1e-5`` of the segment's length.  With
    ``enough``: the depth of a point at least that deep as soon as one is found (the usual
    margin is met by one of the first cells: tens of µs, where the whole bound of a foot's
    rectangle takes milliseconds, once per solve of a new goal)."""
    box = np.stack([poly.min(axis=0), poly.max(axis=0)]).astype(float)
    return float(
        _deepest_bound(
            np.ascontiguousarray(poly[:, 0]), np.ascontiguousarray(poly[:, 1]), box, n,
            DEEPEST_TOL, max_cells, float(enough),
        )
    )  # fmt: skip


@dataclass(frozen=True)
class CenterOfMass(Goal):
    """The whole robot's centre of mass ``c = Σ m_b p_b / M`` (masses and centres from the
    URDF's inertials; as ``pinocchio.centerOfMass`` on the whole URDF: every link a joint of
    the URDF moves, locked and off-path ones included, without the links fixed to the world)
    at a point on the given axes, and/or its ground projection inside a support polygon.

    * ``point``: rows ``r_a = p*_a − c_a`` for each axis of ``axes`` (metres).
    * ``support``: one inequality row ``r = −max(0, d + margin)``, ``d`` the signed distance
      [m] of ``(c_x, c_y)`` to the polygon (negative inside): met anywhere at least
      ``margin`` inside it.

    The Jacobian is ``J_c = Σ_b (m_b / M) J_v,b`` over the bodies' centres (each body a frame
    of the kernels' tree), checked against ``pinocchio.jacobianCenterOfMass``.

    Args:
        point: World point [m] (3 numbers), or None.
        support: Support polygon: ``(k, 2)`` world (x, y) vertices [m], ``k >= 3``, simple
            (not self-intersecting), either orientation; or None.
        axes: Axes of ``point`` that count, any of ``"x"``, ``"y"``, ``"z"`` (default
            ``"xy"``: the ground projection).
        margin: Wanted distance inside the polygon [m], ``>= 0`` (keyword-only).
        weight, primary: As :class:`~swarm_ik.goals.Goal` (keyword-only).
    """

    point: Any = None
    support: Any = None
    axes: str = "xy"
    margin: float = field(default=0.0, kw_only=True)
    kernel: ClassVar[Any] = center_of_mass_kernel

    def __post_init__(self) -> None:
        if self.point is None and self.support is None:
            raise InvalidArgumentError("CenterOfMass needs a point, a support polygon or both")
        if self.point is not None:
            object.__setattr__(self, "point", vec3(self.point, "CenterOfMass.point"))
        if self.support is not None:
            object.__setattr__(self, "support", support_polygon(self.support))
        if (
            not isinstance(self.axes, str)
            or not self.axes
            or any(a not in AXES for a in self.axes)
            or len(set(self.axes)) != len(self.axes)
        ):
            raise InvalidArgumentError(
                f"CenterOfMass.axes must be distinct letters of 'xyz', got {self.axes!r}"
            )
        object.__setattr__(self, "margin", non_negative(self.margin, "CenterOfMass.margin"))
        if self.margin > 0.0 and self.support is None:  # (a field that would do nothing)
            raise InvalidArgumentError(
                "CenterOfMass.margin applies to a support polygon; give support= or leave "
                "margin out"
            )
        if self.axes != "xy" and self.point is None:
            raise InvalidArgumentError(
                f"CenterOfMass.axes ({self.axes!r}) applies to a point; give point= or leave "
                "axes out"
            )
        super().__post_init__()

    def describe(self) -> str:
        return "CenterOfMass"

    def infeasible(self, robot: RobotModel, tol_pos: float, tol_rot: float) -> str | None:
        """A support polygon no centre of mass can be ``margin`` inside (deeper than its
        inscribed radius, :func:`deepest_inside`, plus ``tol_pos``), or a ground point
        (``axes`` with x and y) outside the polygon, or less than ``margin`` inside it, by
        more than ``2·tol_pos`` (the rows are judged together: the point's rows and the
        support row may each take up to the tolerance)."""
        if self.support is None:
            return None
        deepest = deepest_inside(self.support, enough=self.margin + tol_pos)
        if self.margin > deepest + tol_pos:
            return (
                f"CenterOfMass margin {self.margin:g} m deeper than its support polygon allows "
                f"(no point lies more than {deepest:.3g} m inside it)"
            )
        if self.point is None:
            return None
        poly = self.support
        if ("x" in self.axes) != ("y" in self.axes):  # one ground axis: a point margin inside
            # the polygon has that coordinate within its range, shrunk by the margin
            a = 0 if "x" in self.axes else 1
            lo = float(poly[:, a].min()) + self.margin
            hi = float(poly[:, a].max()) - self.margin
            v = float(self.point[a])
            if v < lo - 2 * tol_pos or v > hi + 2 * tol_pos:
                return (
                    f"CenterOfMass point {'xy'[a]} = {v:g} outside its support polygon's range "
                    f"[{lo:.3g}, {hi:.3g}] m (less the margin {self.margin:g} m)"
                )
            return None
        if "x" not in self.axes or "y" not in self.axes:
            return None
        d, _, _ = _polygon_distance(
            float(self.point[0]), float(self.point[1]), poly[:, 0].copy(), poly[:, 1].copy()
        )
        if d + self.margin <= 2 * tol_pos:
            return None
        where = f"{d:.3g} m outside" if d > 0 else f"only {-d:.3g} m inside"
        short = f", less than the margin {self.margin:g} m" if d <= 0 else ""
        return (
            f"CenterOfMass point (x, y) = {self.point[:2].tolist()} {where} its support "
            f"polygon{short}"
        )

    def _axis_ids(self) -> list[int]:
        return [AXES[a] for a in self.axes] if self.point is not None else []

    # ------------------------------------------------------------- compiled form
    def extra_frames(self, robot: RobotModel) -> tuple[Any, Any, Any] | None:
        ids, rots, lever, _ = robot.mass_frames()
        return ids, rots, lever

    def encode(
        self, robot: RobotModel, q0: FloatArray | None, frame0: int | None = None
    ) -> Encoded:
        """The parameter block; the bodies' frames start at ``frame0`` (default: right after
        the robot's goal frames)."""
        ids, _, _, mu = robot.mass_frames()
        axis_ids = self._axis_ids()
        has_support = self.support is not None
        ipar = np.array(
            [len(ids), len(robot.frames) if frame0 is None else frame0, len(axis_ids),
             int(has_support), *axis_ids],
            dtype=np.int64,
        )  # fmt: skip
        point = np.zeros(3) if self.point is None else self.point
        poly = np.zeros((0, 2)) if self.support is None else self.support
        par = np.concatenate([mu, point, [self.margin], poly[:, 0], poly[:, 1]]).astype(float)
        return Encoded(par, ipar, len(axis_ids) + int(has_support))

    # ------------------------------------------------------------- numpy reference
    def _com(self, state: State, jacobian: bool = True) -> tuple[FloatArray, FloatArray | None]:
        """The centre of mass (3,) and, with ``jacobian``, its Jacobian (3, nq) through
        Pinocchio on the robot's (reduced) model."""
        robot = state.robot
        model = robot.model
        data = robot._data()  # (one Data per thread, reused)
        q_pin = robot.to_pinocchio(state.q)
        if jacobian:
            jac = np.array(pin.jacobianCenterOfMass(model, data, q_pin)).reshape(3, model.nv)
        else:
            pin.centerOfMass(model, data, q_pin)
        com, moving = np.array(data.com[0]), float(data.mass[0])
        # the links held fixed to the world (merged into the reduced model's world body, which
        # pinocchio.centerOfMass leaves out): one fixed point of their mass
        m_w, c_w = robot.held_world_mass()
        share = moving / (moving + m_w)
        com = share * com + (1.0 - share) * c_w
        if not jacobian:
            return com, None
        return com, robot.velocity_to_q(share * jac, state.q)

    def _support_row(self, c: FloatArray) -> tuple[float, FloatArray]:
        poly = np.ascontiguousarray(self.support, dtype=float)
        d, gx, gy = _polygon_distance(
            float(c[0]), float(c[1]), poly[:, 0].copy(), poly[:, 1].copy()
        )
        return max(0.0, d + self.margin), np.array([gx, gy])

    def residual(self, state: State) -> FloatArray:
        c, _ = self._com(state, jacobian=False)
        rows = [self.point[a] - c[a] for a in self._axis_ids()]
        if self.support is not None:
            rows.append(-self._support_row(c)[0])
        return np.array(rows, dtype=float)

    def jacobian(self, state: State) -> FloatArray:
        """``∂r/∂q`` (the derivative of :meth:`residual`: minus the step Jacobian)."""
        c, jc = self._com(state)
        assert jc is not None
        rows = [-jc[a] for a in self._axis_ids()]
        if self.support is not None:
            out, g = self._support_row(c)
            rows.append(-(g @ jc[:2]) if out > 0.0 else np.zeros(jc.shape[1]))
        return np.array(rows, dtype=float).reshape(len(rows), -1)

    def errors(self, state: State) -> tuple[float, float]:
        return math.hypot(*self.residual(state).tolist()), float("nan")  # (no overflow)

    def center(self, robot: RobotModel, q: Any) -> FloatArray:
        """The centre of mass [m] at ``q`` through ``pinocchio.centerOfMass`` on the whole
        URDF model (:meth:`RobotModel.full_configuration`), shape ``(3,)``."""
        full = robot.full_model
        return np.array(pin.centerOfMass(full, full.createData(), robot.full_configuration(q)))
