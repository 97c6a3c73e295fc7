"""Compiled code only (numba): kernels of the solver and of the collision approximation."""
