"""Compiled code only (numba's public API: ``njit`` with ``cache=True``, ``objmode`` for the
clock, first-class function types for the goal kernels): rotation helpers (``lie``), forward
kinematics of every goal frame in one pass over the tree (``fk``), the one
Levenberg–Marquardt kernel over the stacked residual of any goal set (``lm``), the restart
search around it (``search``) and the sphere distances of collision goals (``spheres``).

Nothing here imports a module above ``swarm_ik.kernels``: goals register their compiled
residual kernels with :mod:`swarm_ik.goals`, which hands them to these kernels as a typed list
of functions of one signature (:data:`swarm_ik.kernels.lm.GOAL_SIGNATURE`).

Each compiled function has a numpy twin or a Pinocchio reference it is tested against.
"""
