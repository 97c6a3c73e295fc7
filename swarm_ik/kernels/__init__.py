"""Compiled code only (numba): rotation helpers, forward kinematics of every goal frame in one
pass over the tree, and the one Levenberg–Marquardt kernel over stacked goal residuals.

Each compiled function has a numpy twin or a Pinocchio reference it is tested against.
"""
