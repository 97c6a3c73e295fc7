"""Compiled code only (numba): rotation helpers (``lie``), forward kinematics of every goal
frame in one pass over the tree (``fk``), the one Levenberg–Marquardt kernel over stacked goal
residuals (``lm``), and the conservative sphere approximation of collision geometry with its
penetration residual (``spheres``).

Each compiled function has a numpy twin or a Pinocchio reference it is tested against.
"""
