"""Compiled code only (numba): rotation helpers (``lie``), forward kinematics of every goal
frame in one pass over the tree (``fk``), the one Levenberg–Marquardt kernel over stacked goal
residuals (``lm``), and the conservative sphere approximation of collision geometry with its
penetration residual (``spheres``).

Each compiled function has a numpy twin or a Pinocchio reference it is tested against.
"""

from typing import Any

import numba

leaf: Any = numba.njit(cache=True, _nrt=False)  # type: ignore[call-overload]
"""Decorator of the kernels that only read and write their callers' arrays (no allocation):
compiled without numba's reference counting.  A compiled call that passes arrays (or tuples
of them) otherwise costs an atomic increment and decrement per array, about 0.4 µs per call
of :func:`swarm_ik.kernels.fk.fk_one` inside the LM loop; the callers own the arrays and
keep them alive.  (A leaf that tried to allocate would fail to compile, not misbehave.)  A
leaf calls only kernels that allocate nothing: numba compiles a callee first reached from a
leaf with the leaf's flags, runtime off (hence the compiled clock's stack-allocated
``timespec`` in ``search.now``, which the leaf ``search.swarm_search`` calls)."""
