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


def inline_copy(kernel: Any) -> Any:
    """A copy of the leaf ``kernel`` (or a plain function) that numba inlines into each
    compiled caller (its code typed in place of a call), for the one hot call site that
    needs it.

    A call of a kernel taking the tree, goal table and scratch tuples passes every array of
    them field by field (a few hundred words).  Inlining FK, the goal residuals and the
    success test into the LM step took an evaluation from 1.13-1.2 µs to 0.79 µs (Panda,
    batch).  Only the LM loop's trial evaluation uses the copies: every inlined site is
    compiled again in each caller, and inlining them at every site made the first compile
    4x longer (this one site: 46 s -> 71 s for :func:`swarm_ik.load_robot`'s kernels).
    """
    return numba.njit(_nrt=False, inline="always")(getattr(kernel, "py_func", kernel))
