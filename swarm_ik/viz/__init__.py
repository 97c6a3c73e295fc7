"""Look at a solution before sending it to a robot: meshcat scenes, convergence animations and
self-contained HTML exports.

meshcat is an optional extra (``pip install swarm_ik[viz]``) imported only when a scene is
built; ``import swarm_ik`` never imports it.  The robot is drawn from the URDF's visual geometry
through Pinocchio's geometry model (meshes resolved from ``package://`` paths, including those
of ``example-robot-data``), with the joints off the chain held at the robot's ``q_locked``.

The rooms: :mod:`~swarm_ik.viz.trace` (convergence traces), :mod:`~swarm_ik.viz.geometry`
(meshes and configurations), :mod:`~swarm_ik.viz.scene` (the scene), :mod:`~swarm_ik.viz.export`
(the command record and the HTML page), :mod:`~swarm_ik.viz.views` (composed views).

>>> import swarm_ik
>>> from swarm_ik import viz
>>> robot = swarm_ik.load_robot("yumi_left")
>>> problem = swarm_ik.IKProblem.from_q(robot, [0.1, -0.5, 0.2, 0.3, -0.2, 0.4, 0.1])
>>> result, trace = viz.solve_traced(problem, "pso", seed=0, max_evals=3000)
>>> len(trace) == len(result.history) or len(trace) == len(result.history) + 1
True
>>> scene = viz.show_result(problem, result, trace=trace)      # doctest: +SKIP
>>> scene.save_html("result.html")                             # doctest: +SKIP
"""

from __future__ import annotations

from swarm_ik.viz.export import CommandLog, check_output_path, output_file, static_html
from swarm_ik.viz.geometry import full_configuration, package_dirs, reach_length, visual_model
from swarm_ik.viz.obstacles import add_contact_bodies, add_obstacles, show_collision
from swarm_ik.viz.scene import (
    AXIS_COLORS,
    GHOST_COLOR,
    INSTALL_HINT,
    LAYOUTS,
    ROOT,
    RobotDrawing,
    Scene,
    VizUnavailableError,
    require_meshcat,
    served,
    viewer_for,
)
from swarm_ik.viz.trace import Trace, TraceRecorder, solve_traced
from swarm_ik.viz.views import (
    animate_trace,
    error_lines,
    several_solutions,
    show_configurations,
    show_pose,
    show_result,
    show_solutions,
)

__all__ = [
    "add_contact_bodies",
    "add_obstacles",
    "show_collision",
    "AXIS_COLORS",
    "GHOST_COLOR",
    "INSTALL_HINT",
    "LAYOUTS",
    "ROOT",
    "CommandLog",
    "RobotDrawing",
    "Scene",
    "Trace",
    "TraceRecorder",
    "VizUnavailableError",
    "animate_trace",
    "check_output_path",
    "output_file",
    "error_lines",
    "full_configuration",
    "package_dirs",
    "reach_length",
    "require_meshcat",
    "served",
    "several_solutions",
    "show_configurations",
    "show_pose",
    "show_result",
    "show_solutions",
    "viewer_for",
    "solve_traced",
    "static_html",
    "visual_model",
]
