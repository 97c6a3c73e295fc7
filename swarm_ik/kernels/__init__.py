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


hot: Any = numba.njit(cache=True, _nrt=False, forceinline=True)  # type: ignore[call-overload]
"""A :data:`leaf` that LLVM inlines into every compiled caller (``alwaysinline``): the
forward kinematics, the goal residuals, the success test and the evaluation around them.
A call of a kernel taking the tree, goal table and scratch tuples passes every array of them
field by field (a few hundred words); inlined, an LM evaluation went from 1.13-1.2 µs to
0.75-0.85 µs (Panda, batch), for 16 s more of first compile (46 s -> 62 s for
:func:`swarm_ik.load_robot`'s kernels).  (numba's own ``inline="always"``, which types the
callee again at each site, made that compile 4x longer.)"""
