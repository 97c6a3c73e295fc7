"""``swarm-ik bench collision``: collision-free IK in seeded scenes.

Scenes (world = the robot's root frame, metres; each drawn from ``numpy.random.default_rng``
seeded by ``--seed`` and the scene's index, the same geometry for every robot):

* ``table``: a table top (0.8 x 1.2 x 0.04 m, top face at z = 0, from x = 0.25 m) with three
  boxes and three spheres resting on it at random places, sizes and yaws;
* ``shelf``: a shelf unit in front of the robot: four horizontal boards and two side panels;
* ``cubby``: a five-walled box (floor, ceiling, two sides, back) open towards the robot
  (towards ``-x``), inner size 0.30 x 0.36 x 0.30 m; targets inside it;
* ``shelf-narrow``: five boards 0.18–0.22 m apart (0.16–0.20 m clear), 0.60 m wide and
  0.30 m deep, two side panels and a back panel; targets inside the slots, so the hand enters
  between boards (the ``shelf`` above is not narrow: 0.28–0.34 m between boards, and its
  targets need not lie in it);
* ``clutter10``, ``clutter20``, ``clutter40``, ``clutter60``: N boxes (edges 0.05–0.15 m,
  random orientations) with centres uniform in the annulus 0.25–0.80 m from the base axis,
  heights 0–0.90 m, none reaching into the column of radius 0.25 m around the base axis (the
  base and shoulder stay free); the scenes are nested (``clutterN`` is the first N boxes of
  one seeded stream, so more boxes only add obstacles).

``--scenes`` defaults to ``table,shelf,cubby``; ``hard`` stands for
:data:`HARD_SCENES` (``cubby``, ``shelf-narrow`` and the four clutter scenes) and ``all`` for
every scene.

Targets: FK of joint vectors drawn uniformly within the limits that the exact check
(:meth:`swarm_ik.collision.RobotCollision.check`, coal on the URDF's collision geometry, self
collision and the scene) finds collision-free, so an answer exists; for the cubby only those
whose tool frame lies inside the cubby's inner box.

Solvers, each given the same budget per target (``--budget-ms``, default 20 ms):

* ``ours+goal``: ``swarm_ik.solve(IKProblem(robot, T, goals=[AvoidCollisions(scene)]),
  time_limit=budget)``: one call; its ``success`` is its own claim (exact check inside);
* ``ours-reject``: ``swarm_ik.solve(IKProblem(robot, T))`` without the goal, from random
  seeds, until an answer passes the exact check or the budget is spent (rejection); each
  attempt's time limit is what is left of the budget;
* ``rtb-lm-reject``, ``tracik-reject``, ``dls-reject``: the same rejection loop around rtb's
  ``ik_LM`` (no time limit of its own), TRAC-IK (Speed, eps 1e-5/√3 per twist component, so
  that a claim meets the check; timeout a quarter of the
  budget per attempt, :data:`TRACIK_ATTEMPT_FRACTION`) and our ``dls``
  (:mod:`swarm_ik.bench.peers`; rtb and TRAC-IK need ``pip install 'swarm_ik[bench]'``).

* ``analytic-branches`` (6R arms eaik decomposes, e.g. UR5; needs ``eaik``): every closed-form
  branch (:func:`swarm_ik.solvers.analytic.solve_all`), the first the exact check finds
  collision-free; it tells how many targets have a collision-free answer at all.

In a rejection loop no attempt starts once the budget is spent; an attempt started before
runs to its end (rtb has no time limit of its own), and its time counts.

Every answer is judged by the benchmark, identically: **success** = position within 1e-5 m
and angle within 1e-5 rad (Pinocchio FK, :func:`swarm_ik.verify`), collision-free by the
exact check, within the joint limits.  ``claimed_colliding`` counts answers the solver
reported as successes that the exact check finds in contact (the rejection loops never
report one: they check; for ``ours+goal`` it must be 0).

Batch: ``ours+goal`` solving the scene's targets in a plain loop on one core (no checking in
the loop): queries per second = targets / wall time.

Unreachable: for every obstacle-bearing scene, targets placed inside obstacles (the centre
of each box, board or wall, with random orientations) must come back with
``reason == "unreachable"``.

Ablation of the default search (``--ablation``): the ``swarm`` solver on the same collision
problems (``IKProblem(robot, T, goals=[AvoidCollisions(scene)])``) at its own time limit
(``--ablation-budget-ms``, default 50 ms), in :data:`ABLATION_VARIANTS`:

* ``uniform``: ``swarm_fraction=0``: every start after the seed is a uniform random restart;
* ``default``: the default (``swarm_fraction=0.5``: half of each generation after the first
  is grey-wolf proposals from the archive of local minima);
* ``memory``: the default, with ``q0`` = the answer of the nearest earlier target of the same
  scene that this variant solved (nearest by ``|Δp| + 0.1 m/rad · angle`` between the targets;
  the first target of a scene has none and starts from the middle of the ranges);
* ``uniform+memory``: both changes.

Per target the variants run in a seeded random order with the same integer seed (paired:
``uniform`` and ``default`` share generation 0 and differ only in the later proposals) and
are judged as above.  Writes ``ablation.csv``; the summary gets a section.

Writes under ``--out`` (default ``./bench-collision``): ``collision.csv`` (one row per
target and solver), ``batch.csv``, ``unreachable.csv``, ``overhead.csv``, ``scenes/<scene>.json``,
``ablation.csv`` (with ``--ablation``), ``summary.md`` (from the CSVs) and ``run.json``.
"""

from __future__ import annotations

import argparse
import functools
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swarm_ik import argtypes
from swarm_ik._validate import positive_float
from swarm_ik.argtypes import count, positive_number
from swarm_ik.bench import common
from swarm_ik.errors import InvalidArgumentError
from swarm_ik.problem import largest_errors

HELP = (
    "collision-free IK: table, shelf, cubby, narrow shelf and clutter scenes; ours with the "
    "goal vs rejection; ablation of the default search"
)
COMMAND = "collision"
ROBOTS = ("panda", "ur5")
CLUTTER_COUNTS = (10, 20, 40, 60)
"""Box counts of the clutter scenes (``clutter10`` …)."""
SCENES = (
    "table", "shelf", "cubby", "shelf-narrow", *(f"clutter{k}" for k in CLUTTER_COUNTS),
)  # fmt: skip
"""Every scene, in report order (new scenes are appended: a scene's index keys its random
stream, so the earlier scenes and their targets stay as they were)."""
DEFAULT_SCENES = ("table", "shelf", "cubby")
"""Scenes of a run without ``--scenes``."""
HARD_SCENES = ("cubby", "shelf-narrow", *(f"clutter{k}" for k in CLUTTER_COUNTS))
"""``--scenes hard``: where the hand enters between boards, and the clutter."""
SOLVERS = (
    "ours+goal", "ours-reject", "analytic-branches", "rtb-lm-reject", "tracik-reject",
    "dls-reject",
)  # fmt: skip
TOL = 1e-5
"""Pose tolerance of the benchmark's check [m and rad]."""

FIELDS = (
    "robot", "scene", "target_id", "solver", "success", "claimed", "claimed_colliding",
    "pose_ok", "collision_free", "within_limits", "position_error", "rotation_error",
    "clearance", "time_ms", "own_ms", "attempts", "rejected", "reason", "note",
)  # fmt: skip
"""Columns of ``collision.csv`` (``time_ms``: the user-facing call, or the whole rejection loop;
``own_ms``: the solver's own part, summed over attempts; ``attempts``: solver calls;
``rejected``: calls whose answer reached the pose but collided)."""

BATCH_FIELDS = ("robot", "scene", "solver", "n", "wall_s", "queries_per_s", "success")
UNREACHABLE_FIELDS = ("robot", "scene", "obstacle", "index", "success", "reason", "time_ms")


# ------------------------------------------------------------------------------ scenes
def _yaw_pose(center: Sequence[float], yaw: float = 0.0) -> Any:
    """4x4 pose: a rotation of ``yaw`` [rad] about z, then a translation to ``center`` [m]."""
    t = np.eye(4)
    c, s = math.cos(yaw), math.sin(yaw)
    t[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    t[:3, 3] = center
    return t


@dataclass(frozen=True)
class BenchScene:
    """A scene of the benchmark.

    Attributes:
        name: One of :data:`SCENES`.
        scene: The obstacles (:class:`swarm_ik.scene.Scene`).
        inside: For the cubby and the narrow shelf, the inner box ``(lower (3,), upper (3,))``
            [m] the tool frame of a target must lie in; ``None`` otherwise.
    """

    name: str
    scene: Any
    inside: tuple[np.ndarray, np.ndarray] | None = None


def table_scene(rng: np.random.Generator) -> BenchScene:
    """A table top with three boxes and three spheres on it (sizes, places, yaws from rng)."""
    from swarm_ik.scene import Box, Scene, Sphere

    items: list[Any] = [Box((0.8, 1.2, 0.04), _yaw_pose((0.65, 0.0, -0.02)), name="table")]
    for k in range(3):
        sx, sy = rng.uniform(0.06, 0.16, 2)
        h = rng.uniform(0.06, 0.20)
        x, y = rng.uniform(0.40, 0.90), rng.uniform(-0.45, 0.45)
        pose = _yaw_pose((x, y, h / 2), rng.uniform(-math.pi, math.pi))
        items.append(Box((sx, sy, h), pose, name=f"box{k}"))
    for k in range(3):
        r = rng.uniform(0.04, 0.09)
        x, y = rng.uniform(0.40, 0.90), rng.uniform(-0.45, 0.45)
        items.append(Sphere(r, (x, y, r), name=f"ball{k}"))
    return BenchScene("table", Scene(items))


def shelf_scene(rng: np.random.Generator) -> BenchScene:
    """A shelf unit: four boards 0.30 m deep, 0.90 m wide, and two side panels."""
    from swarm_ik.scene import Box, Scene

    x0 = rng.uniform(0.45, 0.55)  # front edge
    depth, width, t = 0.30, 0.90, 0.02
    y0 = rng.uniform(-0.10, 0.10)
    z_first = rng.uniform(0.0, 0.10)
    gap = rng.uniform(0.28, 0.34)
    xc = x0 + depth / 2
    items = []
    heights = [z_first + k * gap for k in range(4)]
    for k, z in enumerate(heights):
        items.append(Box((depth, width, t), _yaw_pose((xc, y0, z)), name=f"board{k}"))
    top = heights[-1] + t / 2
    for side, sgn in (("left", 1.0), ("right", -1.0)):
        yc = y0 + sgn * (width / 2 + t / 2)
        items.append(Box((depth, t, top), _yaw_pose((xc, yc, top / 2)), name=f"side_{side}"))
    return BenchScene("shelf", Scene(items))


def cubby_scene(rng: np.random.Generator) -> BenchScene:
    """A five-walled box open towards the robot (``-x``); inner 0.30 x 0.36 x 0.30 m."""
    from swarm_ik.scene import Box, Scene

    d, w, h, t = 0.30, 0.36, 0.30, 0.02
    x0 = rng.uniform(0.38, 0.45)  # the open face
    yc = rng.uniform(-0.10, 0.10)
    z0 = rng.uniform(0.15, 0.30)  # inner floor
    xc, zc = x0 + d / 2, z0 + h / 2
    items = [
        Box((d, w + 2 * t, t), _yaw_pose((xc, yc, z0 - t / 2)), name="floor"),
        Box((d, w + 2 * t, t), _yaw_pose((xc, yc, z0 + h + t / 2)), name="ceiling"),
        Box((d, t, h), _yaw_pose((xc, yc + w / 2 + t / 2, zc)), name="wall_left"),
        Box((d, t, h), _yaw_pose((xc, yc - w / 2 - t / 2, zc)), name="wall_right"),
        Box((t, w + 2 * t, h + 2 * t), _yaw_pose((x0 + d + t / 2, yc, zc)), name="back"),
    ]
    lower = np.array([x0, yc - w / 2, z0])
    upper = np.array([x0 + d, yc + w / 2, z0 + h])
    return BenchScene("cubby", Scene(items), (lower, upper))


def narrow_shelf_scene(rng: np.random.Generator) -> BenchScene:
    """A narrow shelf: five boards 0.18–0.22 m apart, 0.60 m wide, 0.30 m deep, two side
    panels and a back; targets inside the slots (between the lowest and the highest board)."""
    from swarm_ik.scene import Box, Scene

    depth, width, t = 0.30, 0.60, 0.02
    x0 = rng.uniform(0.40, 0.48)  # front edge
    y0 = rng.uniform(-0.10, 0.10)
    z_first = rng.uniform(0.05, 0.15)
    gap = rng.uniform(0.18, 0.22)  # board to board (clear height gap - t)
    xc = x0 + depth / 2
    heights = [z_first + k * gap for k in range(5)]
    items = [
        Box((depth, width, t), _yaw_pose((xc, y0, z)), name=f"board{k}")
        for k, z in enumerate(heights)
    ]
    top = heights[-1] + t / 2
    for side, sgn in (("left", 1.0), ("right", -1.0)):
        yc = y0 + sgn * (width / 2 + t / 2)
        items.append(Box((depth, t, top), _yaw_pose((xc, yc, top / 2)), name=f"side_{side}"))
    items.append(Box((t, width + 2 * t, top), _yaw_pose((x0 + depth + t / 2, y0, top / 2)),
                     name="back"))  # fmt: skip
    lower = np.array([x0, y0 - width / 2, heights[0] + t / 2])
    upper = np.array([x0 + depth, y0 + width / 2, heights[-1] - t / 2])
    return BenchScene("shelf-narrow", Scene(items), (lower, upper))


CLUTTER_BASE_CLEAR = 0.25
"""Radius [m] of the column around the base axis (z) that no clutter box reaches into."""
CLUTTER_OUTER = 0.80
"""Largest distance [m] of a clutter box's centre from the base axis."""
CLUTTER_HEIGHT = (0.0, 0.90)
"""Range [m] of a clutter box's centre height."""
CLUTTER_EDGE = (0.05, 0.15)
"""Range [m] of a clutter box's edge lengths."""


def clutter_scene(rng: np.random.Generator, n: int) -> BenchScene:
    """``n`` boxes around the arm: edges from :data:`CLUTTER_EDGE`, uniformly random
    orientations, centres uniform (by area) in the annulus from the base axis out to
    :data:`CLUTTER_OUTER` and in height over :data:`CLUTTER_HEIGHT`; a box whose bounding
    sphere reaches into the column of radius :data:`CLUTTER_BASE_CLEAR` around the base axis
    is drawn again (the base and shoulder stay free).  The k-th box does not depend on ``n``
    (the scenes are nested)."""
    from scipy.spatial.transform import Rotation

    from swarm_ik.scene import Box, Scene

    items: list[Any] = []
    r0, r1 = CLUTTER_BASE_CLEAR, CLUTTER_OUTER
    while len(items) < n:
        size = rng.uniform(*CLUTTER_EDGE, 3)
        r = math.sqrt(rng.uniform(r0**2, r1**2))
        phi = rng.uniform(-math.pi, math.pi)
        z = rng.uniform(*CLUTTER_HEIGHT)
        quat = rng.standard_normal(4)
        if r - 0.5 * float(np.linalg.norm(size)) < r0:
            continue  # (every draw above is made whether kept or not: nested scenes)
        pose = np.eye(4)
        pose[:3, :3] = Rotation.from_quat(quat / np.linalg.norm(quat)).as_matrix()
        pose[:3, 3] = (r * math.cos(phi), r * math.sin(phi), z)
        items.append(Box(tuple(size), tuple(map(tuple, pose)), name=f"box{len(items)}"))
    return BenchScene(f"clutter{n}", Scene(items))


SCENE_BUILDERS: dict[str, Callable[[np.random.Generator], BenchScene]] = {
    "table": table_scene,
    "shelf": shelf_scene,
    "cubby": cubby_scene,
    "shelf-narrow": narrow_shelf_scene,
    **{f"clutter{k}": functools.partial(clutter_scene, n=k) for k in CLUTTER_COUNTS},
}

CLUTTER_KEY = 100
"""Random-stream key of every clutter scene (one stream: ``clutterN`` = its first N boxes)."""


def scene_key(name: str) -> int:
    """The key of scene ``name``'s random stream: its index in :data:`SCENES`, or
    :data:`CLUTTER_KEY` for every clutter scene."""
    return CLUTTER_KEY if name.startswith("clutter") else SCENES.index(name)


def make_scene(name: str, seed: int) -> BenchScene:
    """Scene ``name`` drawn with ``default_rng([seed, scene_key(name)])``.

    Raises:
        InvalidArgumentError: unknown name.
    """
    if name not in SCENE_BUILDERS:
        raise InvalidArgumentError(f"unknown scene {name!r}; valid: {', '.join(SCENES)}")
    return SCENE_BUILDERS[name](np.random.default_rng([int(seed), scene_key(name)]))


# ----------------------------------------------------------------------------- targets
def collision_free_targets(
    robot: Any, bench_scene: BenchScene, n: int, rng: np.random.Generator, batch: int = 4096,
    max_draws: int = 2_000_000,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """Reachable collision-free targets: FK of random in-limit ``q`` that the exact check
    finds collision-free (self and scene); for the cubby and the narrow shelf, the tool frame
    inside it.

    Args:
        robot: The robot.
        bench_scene: The scene.
        n: Number of targets.
        rng: Random generator.
        batch: Joint vectors drawn per round.
        max_draws: Most joint vectors drawn before giving up.

    Returns:
        ``(q (n, nq), targets (n, 4, 4))``.

    Raises:
        InvalidArgumentError: fewer than ``n`` found within ``max_draws`` draws.
    """
    keep: Callable[[np.ndarray], np.ndarray] | None = None
    if bench_scene.inside is not None:
        lo, hi = bench_scene.inside

        def keep(q: np.ndarray) -> np.ndarray:
            """The rows of ``q`` whose tool frame lies inside the cubby or the shelf."""
            p = np.asarray(robot.fk(q))[:, :3, 3]
            return q[np.all((p > lo) & (p < hi), axis=1)]

    return common.collision_free_targets(
        robot, bench_scene.scene, n, rng, batch=batch, max_draws=max_draws,
        where=f"{robot.name}/{bench_scene.name}", what="targets", keep=keep,
    )  # fmt: skip


# ----------------------------------------------------------------------------- judging
def judge(robot: Any, scene: Any, target: np.ndarray, q: np.ndarray | None) -> dict[str, Any]:
    """The benchmark's check of an answer: pose by Pinocchio FK, contact by the exact check,
    the joint limits."""
    import swarm_ik

    if q is None or not np.all(np.isfinite(q)):
        return dict(
            success=False, pose_ok=False, collision_free=False, within_limits=False,
            position_error=math.inf, rotation_error=math.inf, clearance=math.nan,
        )  # fmt: skip
    dp, dr = largest_errors(swarm_ik.verify(swarm_ik.IKProblem(robot, target), q))
    within = robot.within_limits(q, tol=1e-12)
    rep = robot.collision_model().check(np.clip(q, robot.lower, robot.upper), scene)
    pose_ok = bool(dp <= TOL and dr <= TOL)
    return dict(
        success=bool(pose_ok and within and rep.collision_free), pose_ok=pose_ok,
        collision_free=bool(rep.collision_free), within_limits=bool(within),
        position_error=float(dp), rotation_error=float(dr), clearance=float(rep.clearance),
    )  # fmt: skip


# ----------------------------------------------------------------------------- solvers
@dataclass
class Outcome:
    """One solver on one target: the answer and what the solver said."""

    q: np.ndarray | None
    claimed: bool
    time_s: float
    attempts: int
    rejected: int
    reason: str = ""
    own_s: float = math.nan


class OursGoal:
    """``swarm_ik.solve`` with ``AvoidCollisions(scene)`` in the problem: one call."""

    name = "ours+goal"

    def __init__(self, robot: Any, scene: Any, budget_s: float) -> None:
        import swarm_ik
        from swarm_ik import goals as G

        self._sik = swarm_ik
        self.robot, self.budget_s = robot, budget_s
        self.goal = G.AvoidCollisions(scene)

    def problem(self, target: np.ndarray) -> Any:
        return self._sik.IKProblem(self.robot, target, goals=[self.goal])

    def solve(self, target: np.ndarray, rng: np.random.Generator) -> Outcome:
        t0 = time.perf_counter()
        res = self._sik.solve(
            self.problem(target), seed=int(rng.integers(2**31)), time_limit=self.budget_s,
            tol_pos=TOL, tol_rot=TOL,
        )  # fmt: skip
        dt = time.perf_counter() - t0
        return Outcome(res.q, bool(res.success), dt, 1, 0, str(res.reason or ""), res.time_s)


class Rejection:
    """A plain IK call (no collision goal) repeated from random seeds until an answer reaches
    the pose, lies within the limits and passes the exact check, or the budget is spent.

    Args:
        name: CSV name.
        call: ``(target, q0, seed, seconds left) -> peers.Answer``.
        robot: The robot.
        scene: The obstacles.
        budget_s: Total budget per target [s].
    """

    def __init__(self, name: str, call: Callable[..., Any], robot: Any, scene: Any,
                 budget_s: float) -> None:  # fmt: skip
        import swarm_ik

        self._sik = swarm_ik
        self.name, self.call, self.robot, self.scene = name, call, robot, scene
        self.budget_s = budget_s
        self.rc = robot.collision_model()

    def solve(self, target: np.ndarray, rng: np.random.Generator) -> Outcome:
        t0 = time.perf_counter()
        attempts = rejected = 0
        q_last = None
        own = 0.0
        plain = self._sik.IKProblem(self.robot, target)
        while attempts == 0 or time.perf_counter() - t0 < self.budget_s:
            q0 = self.robot.random_q(rng)
            left = self.budget_s - (time.perf_counter() - t0)
            ans = self.call(target, q0, int(rng.integers(2**31)), left)
            attempts += 1
            own += ans.own_s
            if ans.q is None or not ans.claimed:
                continue
            q = np.asarray(ans.q, dtype=float)
            if not self.robot.within_limits(q, tol=1e-12):
                continue
            dp, dr = largest_errors(self._sik.verify(plain, q))
            if not (dp <= TOL and dr <= TOL):
                continue
            q_last = q
            if self.rc.collides(q, self.scene):
                rejected += 1
                continue
            return Outcome(q, True, time.perf_counter() - t0, attempts, rejected, "", own)
        dt = time.perf_counter() - t0
        return Outcome(q_last, False, dt, attempts, rejected, "budget", own)


class AnalyticBranches:
    """Every closed-form branch of a 6R arm (eaik), the first collision-free by the exact
    check (branches nearest the middle of the ranges first).

    Raises:
        InvalidArgumentError: eaik is missing or the chain is not decomposable.
    """

    name = "analytic-branches"

    def __init__(self, robot: Any, scene: Any) -> None:
        import swarm_ik
        from swarm_ik.solvers import analytic

        self._sik, self._an = swarm_ik, analytic
        self.robot, self.scene = robot, scene
        self.rc = robot.collision_model()
        try:
            reason = analytic.support(swarm_ik.IKProblem(robot, robot.fk(robot.mid_q())))
        except swarm_ik.SwarmIKError as exc:
            raise InvalidArgumentError(f"{self.name}: {exc}") from None
        if reason:
            raise InvalidArgumentError(f"{robot.name}: {reason}")

    def solve(self, target: np.ndarray, rng: np.random.Generator) -> Outcome:
        t0 = time.perf_counter()
        qs, _dp, _dr = self._an.solve_all(self._sik.IKProblem(self.robot, target), tol_pos=TOL,
                                          tol_rot=TOL)  # fmt: skip
        own = time.perf_counter() - t0
        for k, q in enumerate(qs):
            if not self.rc.collides(q, self.scene):
                return Outcome(q, True, time.perf_counter() - t0, 1, k, "", own)
        reason = "all branches collide" if len(qs) else "no branch"
        q_last = qs[0] if len(qs) else None
        return Outcome(q_last, False, time.perf_counter() - t0, 1, len(qs), reason, own)


TRACIK_ATTEMPT_FRACTION = 0.25
"""TRAC-IK's own timeout inside the rejection loop, as a fraction of the budget (its timeout
is fixed when it is built: a quarter of the budget bounds the overshoot of the last attempt
and leaves room for several attempts)."""


def make_solvers(
    robot: Any, scene: Any, budget_s: float, names: Sequence[str]
) -> tuple[list[Any], dict[str, str]]:
    """The solvers of ``names`` that can be built here, and why the others cannot (a missing
    optional package).

    Raises:
        InvalidArgumentError: an unknown solver name.
    """
    from swarm_ik.bench import peers

    out: list[Any] = []
    missing: dict[str, str] = {}
    for name in names:
        if name not in SOLVERS:
            raise InvalidArgumentError(f"unknown solver {name!r}; valid: {', '.join(SOLVERS)}")
        if name == "ours+goal":
            out.append(OursGoal(robot, scene, budget_s))
            continue
        try:
            if name == "analytic-branches":
                out.append(AnalyticBranches(robot, scene))
                continue
            if name in ("ours-reject", "dls-reject"):
                ours = peers.make("swarm" if name == "ours-reject" else "dls", robot, budget_s, TOL)
                call = _with_time_left(ours)
            elif name == "tracik-reject":
                peers.make("tracik", robot, budget_s, TOL)  # refused here when missing
                # (the `tracik` peer's eps: its claims meet the Euclidean check, where eps TOL
                # sent claimed answers to be rejected and tried again, 24 of 200 Panda claims)
                eps = peers.tracik_eps(TOL)
                tk = peers.TracIK(robot, TRACIK_ATTEMPT_FRACTION * budget_s, eps, name)
                call = _fixed(tk)
            else:
                call = _fixed(peers.make("rtb-lm", robot, budget_s, TOL))
        except InvalidArgumentError as exc:
            missing[name] = str(exc)
            continue
        out.append(Rejection(name, call, robot, scene, budget_s))
    return out, missing


def _with_time_left(peer: Any) -> Callable[..., Any]:
    """Our plain solvers in a rejection loop: each attempt's time limit is what is left of
    the budget (so the loop spends the same total as the goal solver)."""

    def call(target: np.ndarray, q0: np.ndarray, seed: int, left_s: float) -> Any:
        peer.budget_s = max(left_s, 1e-4)
        return peer.solve(target, q0, seed)

    return call


def _fixed(peer: Any) -> Callable[..., Any]:
    """A peer whose own time limit is fixed (TRAC-IK) or absent (rtb)."""

    def call(target: np.ndarray, q0: np.ndarray, seed: int, left_s: float) -> Any:
        return peer.solve(target, q0, seed)

    return call


# --------------------------------------------------------------------------- experiments
def _warm_up(robot: Any, solvers: Sequence[Any], target: np.ndarray) -> None:
    """One untimed solve each: kernels compiled, sphere models and checkers built."""
    rng = np.random.default_rng(12345)
    for s in solvers:
        s.solve(target, rng)


def run_scene(
    robot: Any, bench_scene: BenchScene, n: int, budget_s: float, seed: int,
    solvers: Sequence[str] = SOLVERS,
) -> tuple[list[dict[str, Any]], dict[str, str]]:  # fmt: skip
    """Every solver on ``n`` collision-free targets of one scene, in a seeded random order
    per target; one row per target and solver.

    Returns:
        ``(rows, {solver: why it is missing})``.
    """
    rng = np.random.default_rng([int(seed), SCENES.index(bench_scene.name), 7])
    _q, targets = collision_free_targets(robot, bench_scene, n, rng)
    built, missing = make_solvers(robot, bench_scene.scene, budget_s, solvers)
    _warm_up(robot, built, targets[0])
    rows: list[dict[str, Any]] = []
    for i, target in enumerate(targets):
        for k in rng.permutation(len(built)):
            s = built[int(k)]
            out = s.solve(target, np.random.default_rng([int(seed), i, int(k)]))
            ver = judge(robot, bench_scene.scene, target, out.q)
            rows.append(dict(
                robot=robot.name, scene=bench_scene.name, target_id=i, solver=s.name,
                success=int(ver["success"]), claimed=int(out.claimed),
                claimed_colliding=int(out.claimed and not ver["collision_free"]),
                pose_ok=int(ver["pose_ok"]), collision_free=int(ver["collision_free"]),
                within_limits=int(ver["within_limits"]),
                position_error=ver["position_error"], rotation_error=ver["rotation_error"],
                clearance=ver["clearance"], time_ms=1e3 * out.time_s,
                own_ms=1e3 * out.own_s, attempts=out.attempts,
                rejected=out.rejected, reason=out.reason, note="",
            ))  # fmt: skip
    return rows, missing


def batch_rate(
    robot: Any, bench_scene: BenchScene, n: int, budget_s: float, seed: int,
    solvers: Sequence[str] = ("ours+goal", "ours-reject"),
) -> list[dict[str, Any]]:  # fmt: skip
    """Each of ``solvers`` on the scene's targets in a plain loop (one core, the judging after
    the loop): queries per second = targets / wall time."""
    rng = np.random.default_rng([int(seed), SCENES.index(bench_scene.name), 7])
    _q, targets = collision_free_targets(robot, bench_scene, n, rng)
    built, _missing = make_solvers(robot, bench_scene.scene, budget_s, solvers)
    _warm_up(robot, built, targets[0])
    rows = []
    for s in built:
        srng = np.random.default_rng([int(seed), 13])
        t0 = time.perf_counter()
        outs = [s.solve(t, srng) for t in targets]
        wall = time.perf_counter() - t0
        ok = [
            judge(robot, bench_scene.scene, t, o.q)["success"]
            for t, o in zip(targets, outs, strict=True)
        ]
        rows.append(dict(
            robot=robot.name, scene=bench_scene.name, solver=s.name, n=n, wall_s=wall,
            queries_per_s=n / wall, success=float(np.mean(ok)),
        ))  # fmt: skip
    return rows


OVERHEAD_FIELDS = ("robot", "scene", "part", "n", "median_ms", "p95_ms")
OVERHEAD_PARTS = (
    "IKProblem(robot, T, goals=[AvoidCollisions])",
    "swarm_ik.solve (whole call)",
    "solver's own time (Result.time_s)",
    "exact check: RobotCollision.check (clearance)",
    "exact test: RobotCollision.collides",
)


def overhead(
    robot: Any, bench_scene: BenchScene, n: int, budget_s: float, seed: int
) -> list[dict[str, Any]]:
    """Where the time of one ``ours+goal`` call goes: problem construction, the whole
    ``swarm_ik.solve`` call, its own search time, and the exact check of the answer
    (``check``, with the clearance, as ``Result`` reports it; ``collides``, the contact test
    only)."""
    import swarm_ik

    rng = np.random.default_rng([int(seed), SCENES.index(bench_scene.name), 7])
    _q, targets = collision_free_targets(robot, bench_scene, n, rng)
    s = OursGoal(robot, bench_scene.scene, budget_s)
    _warm_up(robot, [s], targets[0])
    rc = robot.collision_model()
    times: dict[str, list[float]] = {p: [] for p in OVERHEAD_PARTS}
    for i, t in enumerate(targets):
        t0 = time.perf_counter()
        prob = s.problem(t)
        t1 = time.perf_counter()
        res = swarm_ik.solve(prob, seed=i, time_limit=budget_s, tol_pos=TOL, tol_rot=TOL)
        t2 = time.perf_counter()
        rc.check(res.q, bench_scene.scene)
        t3 = time.perf_counter()
        rc.collides(res.q, bench_scene.scene)
        t4 = time.perf_counter()
        parts = (t1 - t0, t2 - t1, res.time_s, t3 - t2, t4 - t3)
        for part, v in zip(OVERHEAD_PARTS, parts, strict=True):
            times[part].append(1e3 * v)
    return [
        dict(
            robot=robot.name,
            scene=bench_scene.name,
            part=p,
            n=n,
            median_ms=float(np.median(v)),
            p95_ms=float(np.percentile(v, 95)),
        )  # fmt: skip
        for p, v in times.items()
    ]


ABLATION_FIELDS = (
    "robot", "scene", "target_id", "variant", "success", "claimed", "pose_ok", "collision_free",
    "time_ms", "own_ms", "n_evals", "seeded", "seed_gap", "reason",
)  # fmt: skip
"""Columns of ``ablation.csv`` (``seeded``: ``q0`` came from the memory; ``seed_gap``: the
distance ``|Δp| + 0.1·angle`` [m] from the target to the remembered one, NaN when unseeded)."""


@dataclass(frozen=True)
class Variant:
    """A variant of the default search in the ablation.

    Attributes:
        name: CSV name.
        swarm_fraction: The ``swarm`` solver's share of grey-wolf proposals per generation.
        memory: Seed each query (``q0``) with the answer of the nearest earlier solved target
            of the same scene.
    """

    name: str
    swarm_fraction: float
    memory: bool


ABLATION_VARIANTS = (
    Variant("uniform", 0.0, False),
    Variant("default", 0.5, False),
    Variant("memory", 0.5, True),
    Variant("uniform+memory", 0.0, True),
)
"""The variants of ``--ablation`` (``default``: the ``swarm`` solver's defaults)."""

MEMORY_ROT_WEIGHT = 0.1
"""Weight [m/rad] of the angle in the distance between targets that picks the remembered
answer (``|Δp| + 0.1·angle``: a radian counts as 10 cm)."""


class SearchVariant:
    """The ``swarm`` solver with ``AvoidCollisions(scene)`` in the problem, one variant of
    :data:`ABLATION_VARIANTS`; with ``memory``, the answers it found (claimed successes, which
    the solver judges with Pinocchio and coal) are kept with their targets and the nearest one
    seeds the next query."""

    def __init__(self, robot: Any, scene: Any, budget_s: float, variant: Variant) -> None:
        import swarm_ik
        from swarm_ik import goals as G

        self._sik = swarm_ik
        self.robot, self.budget_s, self.variant = robot, budget_s, variant
        self.name = variant.name
        self.goal = G.AvoidCollisions(scene)
        self.mem_p: list[np.ndarray] = []
        self.mem_r: list[np.ndarray] = []
        self.mem_q: list[np.ndarray] = []

    def recall(self, target: np.ndarray) -> tuple[np.ndarray | None, float]:
        """The remembered answer whose target is nearest to ``target``, and the distance."""
        if not self.mem_q:
            return None, math.nan
        dp = np.linalg.norm(np.asarray(self.mem_p) - target[:3, 3], axis=1)
        rel = np.einsum("kji,jl->kil", np.asarray(self.mem_r), target[:3, :3])  # R_kᵀ R
        cos = np.clip((np.trace(rel, axis1=1, axis2=2) - 1.0) / 2.0, -1.0, 1.0)
        d = dp + MEMORY_ROT_WEIGHT * np.arccos(cos)
        k = int(np.argmin(d))
        return self.mem_q[k], float(d[k])

    def solve(self, target: np.ndarray, seed: int) -> tuple[Outcome, Any, bool, float]:
        """One query: ``(outcome, Result, seeded from the memory, seed gap)``."""
        t0 = time.perf_counter()
        q0, gap = self.recall(target) if self.variant.memory else (None, math.nan)
        res = self._sik.solve(
            self._sik.IKProblem(self.robot, target, goals=[self.goal]), "swarm", seed=seed,
            time_limit=self.budget_s, q0=q0, tol_pos=TOL, tol_rot=TOL,
            swarm_fraction=self.variant.swarm_fraction,
        )  # fmt: skip
        dt = time.perf_counter() - t0
        if self.variant.memory and res.success:
            self.mem_p.append(np.array(target[:3, 3]))
            self.mem_r.append(np.array(target[:3, :3]))
            self.mem_q.append(np.array(res.q))
        out = Outcome(res.q, bool(res.success), dt, 1, 0, str(res.reason or ""), res.time_s)
        return out, res, q0 is not None, gap


def ablation(
    robot: Any, bench_scene: BenchScene, n: int, budget_s: float, seed: int,
    variants: Sequence[Variant] = ABLATION_VARIANTS,
) -> list[dict[str, Any]]:  # fmt: skip
    """Every variant of the default search on the scene's first ``n`` collision-free targets
    (the targets of :func:`run_scene`), in order (the memory fills as it goes); per target the
    variants run in a seeded random order, all with the same integer seed.  One row per
    target and variant, judged by :func:`judge`."""
    idx = SCENES.index(bench_scene.name)
    rng = np.random.default_rng([int(seed), idx, 7])
    _q, targets = collision_free_targets(robot, bench_scene, n, rng)
    built = [SearchVariant(robot, bench_scene.scene, budget_s, v) for v in variants]
    for v in variants:  # warm-up: routes made, kernels loaded (untimed; no memory kept)
        SearchVariant(robot, bench_scene.scene, budget_s, v).solve(targets[0], 12345)
    order_rng = np.random.default_rng([int(seed), idx, 19])
    rows: list[dict[str, Any]] = []
    for i, target in enumerate(targets):
        solve_seed = int(order_rng.integers(2**31))
        for k in order_rng.permutation(len(built)):
            s = built[int(k)]
            out, res, seeded, gap = s.solve(target, solve_seed)
            ver = judge(robot, bench_scene.scene, target, out.q)
            rows.append(dict(
                robot=robot.name, scene=bench_scene.name, target_id=i, variant=s.name,
                success=int(ver["success"]), claimed=int(out.claimed),
                pose_ok=int(ver["pose_ok"]), collision_free=int(ver["collision_free"]),
                time_ms=1e3 * out.time_s, own_ms=1e3 * out.own_s, n_evals=int(res.n_evals),
                seeded=int(seeded), seed_gap=gap, reason=out.reason,
            ))  # fmt: skip
    return rows


DIAGNOSIS_FIELDS = ("robot", "scene", "tolerance", "budget_ms", "metric", "n", "value")
DIAGNOSIS_VARIANTS = ((0.02, 1.0), (0.02, 5.0), (0.01, 1.0))
"""``(sphere tolerance [m], budget multiplier)`` settings of ``ours+goal`` tried by
:func:`diagnose` (the first is the default goal at the default budget)."""


def _sphere_penetration(robot: Any, goal: Any, target: np.ndarray, qs: np.ndarray) -> np.ndarray:
    """Deepest penetration [m] of the goal's sphere model at each row of ``qs`` (0: none)."""
    import swarm_ik
    from swarm_ik.solvers.hybrid import Polisher

    pol = Polisher.from_problem(swarm_ik.IKProblem(robot, target, goals=[goal]))
    out = []
    for q in np.atleast_2d(qs):
        rows = pol.residual(q)[0][6:]  # after the pose rows: the penetration rows (<= 0)
        out.append(float(-rows.min()) if rows.size else 0.0)
    return np.maximum(np.array(out), 0.0)


def diagnose(
    robot: Any, bench_scene: BenchScene, n: int, budget_s: float, seed: int,
    variants: Sequence[tuple[float, float]] = DIAGNOSIS_VARIANTS,
) -> list[dict[str, Any]]:  # fmt: skip
    """Why ``ours+goal`` misses, on the scene's first ``n`` targets, per sphere tolerance:

    * ``q_true_sphere_contact``: fraction of targets whose generating ``q`` (collision-free by
      the exact check) the sphere model finds in contact (the spheres too conservative);
    * ``sphere_free_branch`` (6R arms with a closed form): fraction of targets with at least
      one branch the sphere model finds free: the ceiling of a search that trusts the spheres;
      ``exact_free_branch`` the same by the exact check;
    * ``success``: ``ours+goal`` success at that tolerance and budget (``budget_ms``).
    """
    import swarm_ik
    from swarm_ik import goals as G
    from swarm_ik.solvers import analytic

    rng = np.random.default_rng([int(seed), SCENES.index(bench_scene.name), 7])
    q_true, targets = collision_free_targets(robot, bench_scene, n, rng)
    rc = robot.collision_model()
    try:
        has_branches = not analytic.support(swarm_ik.IKProblem(robot, targets[0]))
    except swarm_ik.SwarmIKError:
        has_branches = False
    branches = (
        [analytic.solve_all(swarm_ik.IKProblem(robot, t))[0] for t in targets]
        if has_branches else []
    )  # fmt: skip
    rows: list[dict[str, Any]] = []

    def add(tol: float, budget_ms: float, metric: str, value: float) -> None:
        rows.append(dict(robot=robot.name, scene=bench_scene.name, tolerance=tol,
                         budget_ms=budget_ms, metric=metric, n=n, value=value))  # fmt: skip

    if branches:
        free = [any(not rc.collides(q, bench_scene.scene) for q in qs) for qs in branches]
        add(math.nan, math.nan, "exact_free_branch", float(np.mean(free)))
    for tol in sorted({v[0] for v in variants}, reverse=True):
        goal = G.AvoidCollisions(bench_scene.scene, tolerance=tol)
        pen = [
            _sphere_penetration(robot, goal, t, q)[0] for t, q in zip(targets, q_true, strict=True)
        ]
        add(tol, math.nan, "q_true_sphere_contact", float(np.mean(np.array(pen) > 1e-9)))
        if branches:
            ok = [
                len(qs) > 0 and bool(np.any(_sphere_penetration(robot, goal, t, qs) <= 1e-9))
                for t, qs in zip(targets, branches, strict=True)
            ]
            add(tol, math.nan, "sphere_free_branch", float(np.mean(ok)))
        for v_tol, mult in variants:
            if v_tol != tol:
                continue
            b = budget_s * mult
            solver = OursGoal(robot, bench_scene.scene, b)
            solver.goal = goal
            _warm_up(robot, [solver], targets[0])
            srng = np.random.default_rng([int(seed), 17])
            succ = [
                judge(robot, bench_scene.scene, t, solver.solve(t, srng).q)["success"]
                for t in targets
            ]
            add(tol, 1e3 * b, "success", float(np.mean(succ)))
    return rows


def unreachable(
    robot: Any, bench_scene: BenchScene, budget_s: float, seed: int, per_obstacle: int = 2
) -> list[dict[str, Any]]:
    """Targets at the centre of each obstacle (random orientations): the goal solver must
    answer ``reason == "unreachable"``."""
    from scipy.spatial.transform import Rotation

    from swarm_ik.scene import shape_pose

    rng = np.random.default_rng([int(seed), SCENES.index(bench_scene.name), 11])
    s = OursGoal(robot, bench_scene.scene, budget_s)
    rows = []
    for name, shape in zip(bench_scene.scene.names, bench_scene.scene, strict=True):
        for k in range(per_obstacle):
            t = np.eye(4)
            t[:3, :3] = Rotation.random(random_state=rng.integers(2**31)).as_matrix()
            t[:3, 3] = shape_pose(shape)[:3, 3]
            out = s.solve(t, rng)
            rows.append(dict(robot=robot.name, scene=bench_scene.name, obstacle=name, index=k,
                             success=int(out.claimed), reason=out.reason,
                             time_ms=1e3 * out.time_s))  # fmt: skip
    return rows


# ------------------------------------------------------------------------------ report
TARGET_SUCCESS = {"table": 0.99, "shelf": 0.99, "cubby": 0.97}
"""Issue targets: collision-free success of ``ours+goal`` within the budget, per scene."""
TARGET_MEDIAN_MS = 2.0
TARGET_QPS_2_CORES = 7000.0


def _f(v: float, digits: int = 2) -> str:
    return "—" if not np.isfinite(v) else f"{v:.{digits}f}"


def summarise(rows: Sequence[dict[str, str]]) -> list[dict[str, Any]]:
    """Per (robot, scene, solver): N, success, claimed colliding, median / p95 time [ms],
    mean attempts and rejections."""
    out = []
    groups = common.group_rows(rows, "robot", "scene", "solver")

    def order(key: tuple[Any, ...]) -> tuple[Any, ...]:
        robot, scene, solver = key
        return (robot, _index(SCENES, scene), _index(SOLVERS, solver), solver)

    for robot, scene, solver in sorted(groups, key=order):
        rs = groups[(robot, scene, solver)]
        t = common.timing(float(r["time_ms"]) for r in rs)
        own = common.timing(float(r["own_ms"]) for r in rs)
        out.append(dict(
            robot=robot, scene=scene, solver=solver, n=len(rs),
            success=common.success_rate(r["success"] == "1" for r in rs),
            claimed=common.success_rate(r["claimed"] == "1" for r in rs),
            claimed_colliding=sum(int(r["claimed_colliding"]) for r in rs),
            median_ms=t.median, p95_ms=t.p95, own_median_ms=own.median,
            attempts=float(np.mean([float(r["attempts"]) for r in rs])),
            rejected=float(np.mean([float(r["rejected"]) for r in rs])),
            reasons=", ".join(
                f"{k} {v}" for k, v in sorted(_count(r["reason"] for r in rs
                                                     if r["success"] != "1").items())
            ),
        ))  # fmt: skip
    return out


def summarise_ablation(rows: Sequence[dict[str, str]]) -> list[dict[str, Any]]:
    """Per (robot, scene, variant) of ``ablation.csv``, and per (robot, ``all``, variant) over
    its scenes: N, success, median / p95 time [ms], mean evaluations, share seeded from the
    memory, and the paired counts against ``default``: targets this variant solved and
    ``default`` did not, and the reverse; among the targets both solved, those where this
    variant spent fewer evaluations, and more."""
    ok = {(r["robot"], r["scene"], r["target_id"], r["variant"]): r["success"] == "1"
          for r in rows}  # fmt: skip
    evals = {(r["robot"], r["scene"], r["target_id"], r["variant"]): float(r["n_evals"])
             for r in rows}  # fmt: skip
    groups = common.group_rows(rows, "robot", "scene", "variant")
    pooled: dict[tuple[Any, ...], list[Mapping[str, Any]]] = {}
    for (robot, _scene, variant), rs in groups.items():
        pooled.setdefault((robot, "all", variant), []).extend(rs)
    names = [v.name for v in ABLATION_VARIANTS]

    def order(key: tuple[Any, ...]) -> tuple[Any, ...]:
        robot, scene, variant = key
        return (robot, scene == "all", _index(SCENES, scene), _index(names, variant), variant)

    out = []
    items = [*groups.items(), *pooled.items()]
    for key, rs in sorted(items, key=lambda kv: order(kv[0])):
        robot, scene, variant = key
        t = common.timing(float(r["time_ms"]) for r in rs)
        gained = lost = fewer = more = 0
        for r in rs:
            key_default = (r["robot"], r["scene"], r["target_id"], "default")
            other = ok.get(key_default)
            if other is None:
                continue
            mine = r["success"] == "1"
            gained += int(mine and not other)
            lost += int(other and not mine)
            if mine and other:
                fewer += int(float(r["n_evals"]) < evals[key_default])
                more += int(float(r["n_evals"]) > evals[key_default])
        out.append(dict(
            robot=robot, scene=scene, variant=variant, n=len(rs),
            success=common.success_rate(r["success"] == "1" for r in rs),
            median_ms=t.median, p95_ms=t.p95,
            evals=float(np.mean([float(r["n_evals"]) for r in rs])),
            seeded=float(np.mean([r["seeded"] == "1" for r in rs])),
            gained=gained, lost=lost, fewer=fewer, more=more,
        ))  # fmt: skip
    return out


def _union_success(rows: Sequence[dict[str, str]], a: str, b: str) -> dict[tuple[str, str], float]:
    """Per (robot, scene): fraction of targets solved by solver ``a`` or solver ``b``."""
    solved: dict[tuple[str, str, str], bool] = {}
    for r in rows:
        if r["solver"] in (a, b):
            key = (r["robot"], r["scene"], r["target_id"])
            solved[key] = solved.get(key, False) or r["success"] == "1"
    out: dict[tuple[str, str], list[bool]] = {}
    for (robot, scene, _t), ok in solved.items():
        out.setdefault((robot, scene), []).append(ok)
    return {k: float(np.mean(v)) for k, v in out.items()}


def _index(names: Sequence[str], name: str) -> int:
    return names.index(name) if name in names else len(names)


def _count(items: Any) -> dict[str, int]:
    c: dict[str, int] = {}
    for x in items:
        c[x or "—"] = c.get(x or "—", 0) + 1
    return c


def report(
    rows: Sequence[dict[str, str]], batch: Sequence[dict[str, str]],
    unreach: Sequence[dict[str, str]], over: Sequence[dict[str, str]], info: dict[str, Any],
    diag: Sequence[dict[str, str]] = (), abl: Sequence[dict[str, str]] = (),
) -> str:  # fmt: skip
    """The Markdown summary, from the CSV rows (strings) and the run information."""
    budget = float(info.get("budget_ms", 20.0))
    machine = info.get("machine", {})
    lines = [
        "# bench collision",
        "",
        f"N = {info.get('n')} collision-free targets per scene and robot, budget "
        f"{budget:g} ms per target, seed {info.get('seed')}"
        + (" (**quick run**)" if info.get("quick") else "")
        + ".",
        f"Machine: {machine.get('CPU', '?')}, {machine.get('cores', '?')} cores, load average "
        f"{info.get('load', '?')} at the start, {info.get('load_end', '?')} at the end (the "
        "machine is shared: times are wall-clock and include other processes' interference). "
        "One thread per library.",
        "",
        "Success = position ≤ 1e-5 m and angle ≤ 1e-5 rad (Pinocchio FK), collision-free by the "
        "exact coal check (self + scene), within the joint limits. `claimed colliding`: answers "
        "the solver reported as successes that the exact check finds in contact. Time: the "
        "user-facing call (for `*-reject`, the whole rejection loop); own: the solver's own "
        "search time.",
        "",
        "| robot | scene | solver | N | success % | claimed colliding | median ms | p95 ms | "
        "own median ms | attempts | rejected | failures |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    stats = summarise(rows)
    for s in stats:
        lines.append(
            f"| {s['robot']} | {s['scene']} | {s['solver']} | {s['n']} | "
            f"{100 * s['success']:.1f} | {s['claimed_colliding']} | {_f(s['median_ms'])} | "
            f"{_f(s['p95_ms'])} | {_f(s['own_median_ms'])} | {s['attempts']:.2f} | "
            f"{s['rejected']:.2f} | {s['reasons']} |"
        )
    missing = info.get("missing") or {}
    if missing:
        lines += ["", "Not run: " + "; ".join(f"`{k}`: {v}" for k, v in sorted(missing.items()))]
    union = _union_success(rows, "ours+goal", "ours-reject")
    lines += ["", "## Targets (ours+goal)", "",
              "`either`: targets solved by ours+goal or by ours-reject (each with its own "
              "budget): what exact-checking the pose-converged answers the sphere model rejects "
              "would add to the goal solver.", "",
              "| robot | scene | success % (target) | median ms (≤ 2) | either % | verdict |",
              "|---|---|---|---|---|---|"]  # fmt: skip
    for s in stats:
        if s["solver"] != "ours+goal":
            continue
        want = TARGET_SUCCESS.get(s["scene"], 0.99)
        ok = s["success"] >= want and s["median_ms"] <= TARGET_MEDIAN_MS
        miss = []
        if s["success"] < want:
            miss.append(f"success {100 * (want - s['success']):.1f} points short")
        if s["median_ms"] > TARGET_MEDIAN_MS:
            miss.append(f"median {s['median_ms'] / TARGET_MEDIAN_MS:.2f}x the target")
        lines.append(
            f"| {s['robot']} | {s['scene']} | {100 * s['success']:.1f} ({100 * want:.0f}) | "
            f"{_f(s['median_ms'])} | {_f(100 * union.get((s['robot'], s['scene']), math.nan), 1)} "
            f"| {'met' if ok else 'missed: ' + ', '.join(miss)} |"
        )
    if batch:
        lines += ["", "## Batch (a loop of solves on one core)", "",
                  "| robot | scene | solver | N | queries/s (1 core) | x2 cores (ideal) | "
                  "vs 7,000/s | success % |", "|---|---|---|---|---|---|---|---|"]  # fmt: skip
        for b in batch:
            qps = float(b["queries_per_s"])
            lines.append(
                f"| {b['robot']} | {b['scene']} | {b['solver']} | {b['n']} | {qps:.0f} | "
                f"{2 * qps:.0f} | {TARGET_QPS_2_CORES / (2 * qps):.0f}x short | "
                f"{100 * float(b['success']):.1f} |"
            )
    if over:
        lines += ["", "## Where the time of one `ours+goal` call goes", "",
                  "| robot | scene | part | N | median ms | p95 ms |",
                  "|---|---|---|---|---|---|"]  # fmt: skip
        for o in over:
            lines.append(
                f"| {o['robot']} | {o['scene']} | {o['part']} | {o['n']} | "
                f"{float(o['median_ms']):.3f} | {float(o['p95_ms']):.3f} |"
            )
    if unreach:
        ok = sum(r["reason"] == "unreachable" and r["success"] == "0" for r in unreach)
        t = common.timing(float(r["time_ms"]) for r in unreach)
        lines += ["", "## Targets inside obstacles", "",
                  f"{ok} of {len(unreach)} targets placed at the centre of an obstacle (random "
                  f"orientation) reported `reason == \"unreachable\"` by `ours+goal` "
                  f"(median {t.median:.1f} ms, max {t.max:.1f} ms)."]  # fmt: skip
        claimed = sum(r["success"] != "0" for r in unreach)
        lines[-1] += f" {claimed} reported a success."
        others: dict[tuple[str, str], int] = {}
        for r in unreach:
            if r["reason"] != "unreachable" or r["success"] != "0":
                key = (r["robot"], r["reason"])
                others[key] = others.get(key, 0) + 1
        if others:
            lines.append(
                "The others, by robot and reason: "
                + ", ".join(f"{rb} `{why}` {k}" for (rb, why), k in sorted(others.items()))
                + ". A target is proven `unreachable` only where the goal frame lies on the "
                "robot's own collision geometry (within 1 mm of its bodies), so that the body "
                "is in contact wherever the frame meets the point; a frame off the bodies (a "
                "grasp point, a flange face such as UR5's `tool0`) may lie inside an obstacle "
                "without contact, and such targets end with the budget's reason."
            )
    if diag:
        lines += ["", "## Diagnosis of ours+goal", "",
                  "`q_true_sphere_contact`: the generating q (exact check: free) is in contact "
                  "for the sphere model; `sphere_free_branch` / `exact_free_branch`: targets "
                  "with a closed-form branch free by the spheres / by the exact check; "
                  "`success`: ours+goal at that sphere tolerance and budget.", "",
                  "| robot | scene | metric | sphere tolerance m | budget ms | N | value % |",
                  "|---|---|---|---|---|---|---|"]  # fmt: skip
        for d in diag:
            tol = "" if d["tolerance"] == "nan" else d["tolerance"]
            bud = "" if d["budget_ms"] == "nan" else f"{float(d['budget_ms']):g}"
            lines.append(f"| {d['robot']} | {d['scene']} | {d['metric']} | {tol} | {bud} | "
                         f"{d['n']} | {100 * float(d['value']):.1f} |")  # fmt: skip
    if abl:
        lines += _ablation_lines(abl, info)
    notes = info.get("notes")
    if notes:
        lines += ["", "## Notes", "", *notes]
    return "\n".join(lines) + "\n"


def _ablation_lines(abl: Sequence[dict[str, str]], info: dict[str, Any]) -> list[str]:
    """The ablation section of the summary."""
    lines = [
        "", f"## Ablation of the default search (`swarm`, time limit "
        f"{float(info.get('ablation_budget_ms', 50.0)):g} ms)", "",
        "The `swarm` solver on `IKProblem(robot, T, goals=[AvoidCollisions(scene)])`, judged "
        "as above. `uniform`: `swarm_fraction=0` (every start after the seed a uniform random "
        "restart); `default`: `swarm_fraction=0.5` (half of each later generation grey-wolf "
        "proposals from the archive of local minima); `memory`: the default with `q0` = the "
        "answer of the nearest earlier target of the scene it solved (`|Δp| + 0.1 m/rad · "
        "angle`); `uniform+memory`: both. Per target every variant gets the same integer seed "
        "(paired), in a random order. `+` / `−`: targets this variant solved that `default` did "
        "not / that `default` solved and this variant did not; `fewer` / `more evals`: among the "
        "targets both solved, those where this variant spent fewer / more evaluations than "
        "`default` (the rest: the same). `all`: the scenes pooled.", "",
        "| robot | scene | variant | N | success % | median ms | p95 ms | mean evals | "
        "seeded % | + vs default | − vs default | fewer evals | more evals |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]  # fmt: skip
    for a in summarise_ablation(abl):
        scene = "**all**" if a["scene"] == "all" else a["scene"]
        lines.append(
            f"| {a['robot']} | {scene} | {a['variant']} | {a['n']} | {100 * a['success']:.1f} | "
            f"{_f(a['median_ms'])} | {_f(a['p95_ms'])} | {a['evals']:.0f} | "
            f"{100 * a['seeded']:.0f} | {a['gained']} | {a['lost']} | {a['fewer']} | "
            f"{a['more']} |"
        )
    return lines


# --------------------------------------------------------------------------------- CLI
def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``swarm-ik bench collision``."""
    parser.add_argument("--n", type=count(1), default=200, help="targets per scene and robot")
    parser.add_argument(
        "--budget-ms", type=positive_number, default=20.0, help="budget per target [ms]"
    )
    argtypes.add_seed(parser, "seed of the scenes and targets")
    parser.add_argument("--robots", default=",".join(ROBOTS), help="comma-separated robots")
    parser.add_argument(
        "--scenes", default=",".join(DEFAULT_SCENES),
        help=f"comma-separated scenes of {', '.join(SCENES)}; 'hard' = "
        f"{','.join(HARD_SCENES)}; 'all' = every scene",
    )  # fmt: skip
    parser.add_argument("--solvers", default=",".join(SOLVERS), help="comma-separated solvers")
    parser.add_argument("--batch-n", type=count(1), default=None,
                        help="targets of the batch loop (default --n)")  # fmt: skip
    parser.add_argument(
        "--diagnose", type=count(0), default=0, metavar="N",
        help="also diagnose ours+goal on the first N targets of each scene (sphere "
        "tolerances, budgets, closed-form branches; slow the first time: fits spheres)"
    )  # fmt: skip
    parser.add_argument(
        "--ablation", action="store_true",
        help="also run the ablation of the default search (uniform restarts only, default, "
        "memory of collision-free answers as q0, both) on each scene",
    )  # fmt: skip
    parser.add_argument("--ablation-budget-ms", type=float, default=50.0,
                        help="time limit per target of the ablation [ms]")  # fmt: skip
    parser.add_argument("--ablation-n", type=count(1), default=None,
                        help="targets per scene of the ablation (default --n)")  # fmt: skip
    parser.add_argument("--quick", action="store_true", help="N = 10 (a smoke run)")
    common.add_out(parser, COMMAND)


def _names(text: str, valid: Sequence[str], what: str,
           groups: dict[str, Sequence[str]] | None = None) -> list[str]:  # fmt: skip
    names: list[str] = []
    for t in (t.strip() for t in str(text).split(",")):
        for name in (groups or {}).get(t, [t] if t else []):
            if name not in names:
                names.append(name)
    bad = [t for t in names if t not in valid]
    if bad or not names:
        raise InvalidArgumentError(f"--{what}: unknown {bad or text!r}; valid: {', '.join(valid)}")
    return names


def write_report(out: Path) -> str:
    """(Re)build ``summary.md`` from the CSVs and ``run.json`` of ``out``."""
    import json

    info = json.loads((out / common.RUN_INFO).read_text())
    text = report(
        common.read_csv(out / "collision.csv"), common.read_csv(out / "batch.csv"),
        common.read_csv(out / "unreachable.csv"), common.read_csv(out / "overhead.csv"), info,
        common.read_csv(out / "diagnosis.csv"), common.read_csv(out / "ablation.csv"),
    )  # fmt: skip
    (out / "summary.md").write_text(text)
    return text


def run(args: argparse.Namespace) -> int:
    """Run the benchmark; write the CSVs, the scenes and ``summary.md`` under ``--out``."""
    import os

    robots = [r.strip() for r in str(args.robots).split(",") if r.strip()]
    scenes = _names(args.scenes, SCENES, "scenes", {"hard": HARD_SCENES, "all": SCENES})
    solvers = _names(args.solvers, SOLVERS, "solvers")
    n = 10 if args.quick else common.positive_int(args.n, "--n")
    budget_ms = positive_float(args.budget_ms, "--budget-ms")
    budget = budget_ms / 1e3
    nb = n if args.batch_n is None else int(args.batch_n)
    abl_ms = positive_float(args.ablation_budget_ms, "--ablation-budget-ms")
    na = (
        n if args.ablation_n is None or args.quick
        else common.positive_int(args.ablation_n, "--ablation-n")
    )  # fmt: skip
    out = common.resolve_out(args.out, COMMAND, args.quick)
    if not robots:
        raise InvalidArgumentError(f"--robots: no robot in {args.robots!r}")
    common.check_robots(robots)  # every name, before the first scene is written
    common.single_thread()

    load = f"{os.getloadavg()[0]:.2f}" if hasattr(os, "getloadavg") else "?"
    t_start = time.perf_counter()
    rows: list[dict[str, Any]] = []
    batch: list[dict[str, Any]] = []
    unreach: list[dict[str, Any]] = []
    over: list[dict[str, Any]] = []
    diag: list[dict[str, Any]] = []
    abl: list[dict[str, Any]] = []
    missing: dict[str, str] = {}
    for rname in robots:
        robot = common.cached_robot(rname)
        for sname in scenes:
            bs = make_scene(sname, args.seed)
            (out / "scenes").mkdir(parents=True, exist_ok=True)
            bs.scene.to_json(out / "scenes" / f"{sname}.json")
            r, miss = run_scene(robot, bs, n, budget, args.seed, solvers)
            rows += r
            missing.update({f"{k} on {rname}": v for k, v in miss.items()})
            looped = [s for s in ("ours+goal", "ours-reject") if s in solvers]
            batch += batch_rate(robot, bs, nb, budget, args.seed, looped)
            over += overhead(robot, bs, min(nb, 100), budget, args.seed)
            unreach += unreachable(robot, bs, budget, args.seed)
            if args.diagnose:
                diag += diagnose(robot, bs, int(args.diagnose), budget, args.seed)
            if args.ablation:
                abl += ablation(robot, bs, na, abl_ms / 1e3, args.seed)
            print(f"{rname}/{sname}: {len(r)} rows, {time.perf_counter() - t_start:.0f} s",
                  flush=True)  # fmt: skip
    common.write_csv(out / "collision.csv", FIELDS, rows)
    common.write_csv(out / "batch.csv", BATCH_FIELDS, batch)
    common.write_csv(out / "unreachable.csv", UNREACHABLE_FIELDS, unreach)
    common.write_csv(out / "overhead.csv", OVERHEAD_FIELDS, over)
    if diag:
        common.write_csv(out / "diagnosis.csv", DIAGNOSIS_FIELDS, diag)
    if abl:
        common.write_csv(out / "ablation.csv", ABLATION_FIELDS, abl)
    extra = dict(ablation_n=na, ablation_budget_ms=abl_ms) if abl else {}
    common.write_run_info(
        out, COMMAND, args.quick, n=n, budget_ms=budget_ms, seed=args.seed, robots=robots,
        scenes=scenes, solvers=solvers, missing=missing, load=load,
        load_end=f"{os.getloadavg()[0]:.2f}" if hasattr(os, "getloadavg") else "?",
        wall_s=round(time.perf_counter() - t_start, 1),
        machine=common.machine_info(("pytracik", "roboticstoolbox-python", "coal")), **extra,
    )  # fmt: skip
    text = write_report(out)
    print(text)
    return 0


main = common.module_main(add_arguments, run, "collision", HELP)


if __name__ == "__main__":
    raise SystemExit(main())
