"""swarm_ik: inverse kinematics for any URDF robot with swarm optimisers and Pinocchio.

>>> import swarm_ik
>>> robot = swarm_ik.load_robot("yumi_left")
>>> problem = swarm_ik.IKProblem.from_q(robot, [0.1, -0.5, 0.2, 0.3, -0.2, 0.4, 0.1])
>>> swarm_ik.solve(problem, seed=0).success
True
"""

from swarm_ik import goals, solvers
from swarm_ik.api import IKSolver, solve, verify
from swarm_ik.batch import solve_batch
from swarm_ik.errors import (
    InvalidArgumentError,
    InvalidTargetError,
    RobotFileNotFoundError,
    RobotModelError,
    SwarmIKError,
    UnknownNameError,
)
from swarm_ik.many import solve_many
from swarm_ik.optimize import OptimizeResult, minimize
from swarm_ik.pose import make_pose, project_to_se3
from swarm_ik.problem import IKProblem
from swarm_ik.result import Result
from swarm_ik.robot import RobotModel, load_robot, robot_names
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
    "goals",
    "solvers",
    "verify",
]
