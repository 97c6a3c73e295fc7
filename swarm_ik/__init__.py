"""swarm_ik: inverse kinematics for any URDF robot with swarm optimisers and Pinocchio.

>>> import swarm_ik
>>> robot = swarm_ik.load_robot("yumi_left")
>>> problem = swarm_ik.IKProblem.from_q(robot, [0.1, -0.5, 0.2, 0.3, -0.2, 0.4, 0.1])
>>> swarm_ik.solve(problem, seed=0).success
True
"""

# (first: in the console script, a Ctrl-C while these modules load is one line, exit 130)
import swarm_ik._startup  # noqa: F401  # isort: skip
from typing import TYPE_CHECKING, Any

# numba's cache folder is settled before any swarm_ik module imports numba (a read-only
# install, a damaged cache file: swarm_ik.kernels); this loads neither numba nor numpy
import swarm_ik.kernels  # noqa: F401  # isort: skip
from swarm_ik.errors import (
    InvalidArgumentError,
    InvalidTargetError,
    RobotFileNotFoundError,
    RobotModelError,
    SwarmIKError,
    UnknownNameError,
)

# Everything else is imported on first use (PEP 562): ``import swarm_ik`` loads neither
# numba, Pinocchio nor numpy's linear algebra until a name that needs them is touched
# (docs/performance.md, "Start-up").
_LAZY = {
    "IKSolver": "swarm_ik.api",
    "solve": "swarm_ik.api",
    "verify": "swarm_ik.api",
    "solve_batch": "swarm_ik.batch",
    "solve_many": "swarm_ik.many",
    "windings_of": "swarm_ik.many",
    "solve_path": "swarm_ik.path",
    "OptimizeResult": "swarm_ik.optimize",
    "minimize": "swarm_ik.optimize",
    "make_pose": "swarm_ik.pose",
    "project_to_se3": "swarm_ik.pose",
    "IKProblem": "swarm_ik.problem",
    "Result": "swarm_ik.result",
    "Solutions": "swarm_ik.result",
    "RobotModel": "swarm_ik.robot",
    "load_robot": "swarm_ik.robot",
    "robot_names": "swarm_ik.paths",
    "Scene": "swarm_ik.scene",
}
_SUBMODULES = (
    "api", "argtypes", "batch", "bench", "branches", "cli", "collision", "distributed",
    "errors", "fitness", "goals", "kernels", "many", "optimize", "path", "paths", "periodic",
    "pose", "problem", "reach", "result", "robot", "scene", "solvers", "spheres",
    "testfunctions", "urdf", "viz",
)  # fmt: skip
"""The public modules, each loaded on first use as ``swarm_ik.<name>`` (``help(swarm_ik.many)``
works without ``import swarm_ik.many`` first)."""


def __getattr__(name: str) -> Any:
    import importlib

    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
    elif name in _SUBMODULES:
        value = importlib.import_module(f"swarm_ik.{name}")
    else:
        raise AttributeError(f"module 'swarm_ik' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY) | set(_SUBMODULES))


if TYPE_CHECKING:  # for type checkers and IDEs: the names as if imported eagerly
    from swarm_ik import goals, solvers
    from swarm_ik.api import IKSolver, solve, verify
    from swarm_ik.batch import solve_batch
    from swarm_ik.many import solve_many, windings_of
    from swarm_ik.optimize import OptimizeResult, minimize
    from swarm_ik.path import solve_path
    from swarm_ik.paths import robot_names
    from swarm_ik.pose import make_pose, project_to_se3
    from swarm_ik.problem import IKProblem
    from swarm_ik.result import Result, Solutions
    from swarm_ik.robot import RobotModel, load_robot
    from swarm_ik.scene import Scene

__version__ = "0.1.0"

__all__ = [
    "IKProblem",
    "IKSolver",
    "InvalidArgumentError",
    "InvalidTargetError",
    "OptimizeResult",
    "Result",
    "RobotFileNotFoundError",
    "RobotModel",
    "RobotModelError",
    "Scene",
    "Solutions",
    "SwarmIKError",
    "UnknownNameError",
    "load_robot",
    "make_pose",
    "minimize",
    "project_to_se3",
    "robot_names",
    "solve",
    "solve_batch",
    "solve_many",
    "solve_path",
    "goals",
    "solvers",
    "verify",
    "windings_of",
]
