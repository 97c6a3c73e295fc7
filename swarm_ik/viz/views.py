"""Composed views: a solve (robot, target and reached triads, errors, a ghosted comparison,
the convergence animated), several configurations side by side or stepped through.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, cast

import numpy as np
import pinocchio as pin

from swarm_ik._types import FloatArray
from swarm_ik._validate import count, nonnegative, positive_float
from swarm_ik.errors import InvalidArgumentError, unknown
from swarm_ik.pose import as_pose
from swarm_ik.problem import IKProblem
from swarm_ik.result import Result
from swarm_ik.robot import RobotModel
from swarm_ik.viz.geometry import full_configuration, reach_length
from swarm_ik.viz.scene import GHOST_COLOR, LAYOUTS, ROOT, Scene, text_png, translation
from swarm_ik.viz.trace import Trace


def _seconds(value: Any) -> float:
    """``hold_s`` as a finite number of seconds ``>= 0`` (:func:`swarm_ik._validate.nonnegative`;
    NaN made ``int(round(hold_s * fps))`` a bare ``ValueError``)."""
    what = "hold_s must be a finite number of seconds >= 0"
    if value is None:
        raise InvalidArgumentError(f"{what}, got None")
    return float(nonnegative(value, what, ()))  # type: ignore[arg-type]


def _is(value: Any, cls: type, what: str) -> None:
    """Refuse ``value`` unless it is a ``cls`` (``None`` or another object gave a bare
    ``AttributeError`` deep in the drawing)."""
    if not isinstance(value, cls):
        raise InvalidArgumentError(f"{what} must be a {cls.__name__}, got {type(value).__name__}")


def error_lines(result: Result, label: str | None = None) -> list[str]:
    """Text lines stating a result's solver, status and errors."""
    _is(result, Result, "result")
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
    return 0.12 * reach_length(robot)


DRAWN_ORTH_TOL = 1.0
"""How far from a rotation a target's rotation block may be and still be drawn (a problem
accepted with a loose ``orth_tol`` is drawn as it was given)."""


def _drawn_target(target: Any) -> FloatArray | None:
    """A target to draw, in any pose form the solvers take (4×4, 7 numbers, ``(position,
    quaternion)``), checked for its shape and finite values (one line otherwise: a 3×3 or 7
    numbers raised ``IndexError``, a NaN pose was drawn); its rotation block as given."""
    return None if target is None else as_pose(target, orth_tol=DRAWN_ORTH_TOL)


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
        target: Optional target pose (4x4 [m], or any form ``IKProblem`` takes: 7 numbers,
            ``(position, quaternion)``); drawn as a larger triad with a yellow ball.
        lines: Text shown on a sign beside the robot (e.g. the errors).
        ghost_q: Optional second configuration drawn ghosted (translucent orange), e.g. another
            solver's answer to the same target.
        scene: Scene to draw into (default: a new one).

    Returns:
        The scene (``scene.url`` for the live view, ``scene.save_html(path)`` to export).
    """
    _is(robot, RobotModel, "robot")
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
    target = _drawn_target(target)
    if target is not None:
        scene.add_triad(
            "target", target, length=length, radius=length / 18, sphere=(1.0, 0.85, 0.1, 0.45)
        )
    _label_and_frame(scene, _view_points(robot, q_list, target), lines, reach_length(robot))
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
        _, aspect = text_png(lines)
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
    if name not in scene.robots:
        raise unknown("drawing", name, list(scene.robots))
    if len(trace) == 0:
        raise InvalidArgumentError("animate_trace needs a trace of at least one iteration")
    fps = int(count(fps, "fps"))
    hold_s = _seconds(hold_s)
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
    _is(problem, IKProblem, "problem")
    _is(result, Result, "result")
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
    if layout not in LAYOUTS:
        raise unknown("layout", layout, LAYOUTS)
    hold_s = _seconds(hold_s)
    if spacing is not None:
        spacing = positive_float(spacing, "spacing [m] (or None)")
    if len(qs) == 0:
        raise InvalidArgumentError("show_configurations needs at least one configuration")
    qs = [robot.check_q(q, f"configuration #{k + 1}") for k, q in enumerate(qs)]
    target = _drawn_target(target)
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
        step = max(0.3 * reach_length(robot), 1.3 * max(widths))
    else:
        step = float(spacing)
    length = _triad_length(robot)
    pts = []
    for k, q in enumerate(qs):
        # the camera looks from +x: +y is on the left, so the first robot gets the largest y
        off = np.array([0.0, (0.5 * (len(qs) - 1) - k) * step, 0.0])
        scene.add_robot(robot, q, name=f"solutions/{k}/robot", offset=off)
        scene.add_triad(
            f"solutions/{k}/reached", translation(off) @ robot.fk(q), length=0.8 * length
        )
        if target is not None:
            scene.add_triad(
                f"solutions/{k}/target",
                translation(off) @ np.asarray(target),
                length=length,
                radius=length / 18,
                sphere=(1.0, 0.85, 0.1, 0.45),
            )
        pts.append(_view_points(robot, [q], target) + off)
    _label_and_frame(scene, np.vstack(pts), lines, reach_length(robot), direction=(1.0, 0.15, 0.35))
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
    min_distance: float | None = 0.5,
    seed: int = 0,
    **solve_kwargs: Any,
) -> list[Result]:
    """Up to ``n`` distinct solutions of ``problem``.

    Without ``solver``, :func:`swarm_ik.solve_many`; with one, solves from successive seeds
    (each after the first from a random start ``q0`` drawn with ``seed``, unless ``q0`` is
    given) keeping the successes at least ``min_distance`` apart (joint-space distance, rad /
    m, continuous joints wrapped as in ``solve_many``; at most ``4 n`` solves).

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
    if solver is None:
        found = cast(
            "list[Result]",
            swarm_ik.solve_many(problem, n, min_distance=min_distance, seed=seed, **solve_kwargs),
        )
        return found or [swarm_ik.solve(problem, seed=seed, **solve_kwargs)]
    # (checked as solve_many checks it: NaN kept one solution, a negative distance the same one
    # n times)
    least = 0.0 if min_distance is None else positive_float(min_distance, "min_distance (or None)")
    robot = problem.robot
    kept: list[Result] = []
    best: Result | None = None
    starts = np.random.default_rng(seed)  # (the starts after the first: a seeded draw)
    for s in range(seed, seed + 4 * n):
        kwargs = dict(solve_kwargs)
        if s > seed and "q0" not in solve_kwargs:  # (from one start, a local solver finds
            kwargs["q0"] = starts.uniform(problem.lower, problem.upper)  # one branch only)
        r = swarm_ik.solve(problem, solver, seed=s, **kwargs)
        if best is None or r.fitness < best.fitness:
            best = r
        far = all(np.linalg.norm(robot.wrap(r.q - k.q)) >= least for k in kept)
        if r.success and far:
            kept.append(r)
            if len(kept) == n:
                break
    kept.sort(key=lambda r: r.fitness)
    return kept or ([best] if best is not None else [])
