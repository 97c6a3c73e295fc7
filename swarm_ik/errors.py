"""Error hierarchy of swarm_ik.

Every error raised on bad user input is a :class:`SwarmIKError` and also inherits the
matching built-in exception, so ``except ValueError`` keeps working.  Messages name the bad
value and, where there is a set of valid values, list them.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable


class SwarmIKError(Exception):
    """Base class of every error swarm_ik raises on purpose."""


class RobotFileNotFoundError(SwarmIKError, FileNotFoundError):
    """A URDF path that does not exist."""


class RobotModelError(SwarmIKError, ValueError):
    """A URDF that cannot be turned into a serial-chain robot (bad XML, loops, limits...)."""


class RobotModelWarning(UserWarning):
    """A URDF loaded with a part that could not be read (an ``<inertial>`` whose mass is not a
    number: the link loaded without mass).  :func:`swarm_ik.load_robot` silences the warnings
    of the libraries it calls while loading, not these."""


class GoalWarning(UserWarning):
    """A goal written in Python that is accepted but may slow or stall the search (a
    ``jacobian`` whose size disagrees with its ``residual``'s change)."""


class UnknownNameError(SwarmIKError, KeyError):
    """A name (robot, frame, solver, fitness, joint) that is not among the valid ones."""

    def __str__(self) -> str:  # KeyError would otherwise repr() the message
        return str(self.args[0]) if self.args else ""


class InvalidTargetError(SwarmIKError, ValueError):
    """A target pose that is not a finite rigid transform."""


class InvalidArgumentError(SwarmIKError, ValueError):
    """Any other bad argument: shapes, budgets, solver parameters, seeds."""


def unknown(kind: str, name: object, valid: Iterable[str]) -> UnknownNameError:
    """Build an :class:`UnknownNameError` naming ``name`` and listing the valid choices.

    Args:
        kind: What was looked up, e.g. ``"solver"`` or ``"frame"``.
        name: The value the user gave.
        valid: The names that would have been accepted.
    """
    names = sorted({str(v) for v in valid})  # (each name once)
    plural = kind + ("es" if kind.endswith("s") else "s")  # "fitnesses", "solvers"
    close = difflib.get_close_matches(str(name), names, n=3, cutoff=0.6)
    if not close:  # (a name in other case: "Panda")
        close = [n for n in names if n.lower() == str(name).lower()]
    hint = f"did you mean {' or '.join(repr(c) for c in close)}? " if close else ""
    return UnknownNameError(f"unknown {kind} {name!r}; {hint}valid {plural}: {', '.join(names)}")
