"""Solving from several threads of one process: the first use of the compiled goal kernels
raced (threads registered the same kernel in two slots, or made the kernels' list before the
last registration: IndexError inside the compiled search, then in every later solve)."""

from __future__ import annotations

import subprocess
import sys

CODE = """
import numpy as np, swarm_ik
from concurrent.futures import ThreadPoolExecutor
from swarm_ik.goals import Axis, Position
robot = swarm_ik.load_robot("panda")
T = robot.fk(robot.random_q(np.random.default_rng(0)))
ee = robot.ee_frame
def pose(i):
    return swarm_ik.solve(swarm_ik.IKProblem(robot, T), seed=i).success
def axis(i):
    goals = [Position(ee, T[:3, 3]), Axis(ee, [0, 0, 1], T[:3, 2])]
    return swarm_ik.solve(swarm_ik.IKProblem(robot, goals=goals), seed=i).success
with ThreadPoolExecutor(4) as ex:
    first = list(ex.map(pose, range(8)))
    second = list(ex.map(axis, range(8)))
after = pose(99) and axis(99)
print(all(first), all(second), after)
"""


def test_threads_that_first_meet_the_goal_kernels_together_all_solve() -> None:
    """A fresh process: four threads solve a pose at once, then a new goal type (Axis) at
    once; every solve succeeds, and the main thread solves after them."""
    proc = subprocess.run([sys.executable, "-c", CODE], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.split() == ["True", "True", "True"]
