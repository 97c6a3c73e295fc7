"""Solver registry.  Each module registers its solvers when imported (see ``base.py``).

>>> from swarm_ik import solvers
>>> "dls" in solvers.names()
True
"""

from swarm_ik.solvers.base import Evaluator, SolverSpec, get, names, register, search_names

# Importing a module registers its solvers; one line per module.
from swarm_ik.solvers import analytic  # noqa: E402,F401  isort: skip
from swarm_ik.solvers import cs  # noqa: E402,F401  isort: skip
from swarm_ik.solvers import dls  # noqa: E402,F401  isort: skip
from swarm_ik.solvers import gwo  # noqa: E402,F401  isort: skip
from swarm_ik.solvers import foa  # noqa: E402,F401  isort: skip
from swarm_ik.solvers import hlfoa  # noqa: E402,F401  isort: skip
from swarm_ik.solvers import hybrid  # noqa: E402,F401  isort: skip
from swarm_ik.solvers import mgwo  # noqa: E402,F401  isort: skip
from swarm_ik.solvers import pso  # noqa: E402,F401  isort: skip

__all__ = ["Evaluator", "SolverSpec", "get", "names", "register", "search_names"]
