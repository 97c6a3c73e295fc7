"""Input checks shared by the API and the command line (issue 16).

Each helper turns a bad value into a :class:`~swarm_ik.errors.SwarmIKError` that names it,
instead of the ``ValueError``/``TypeError``/``OSError`` numpy, ``float()`` or the file system
would raise deep inside.  They are meant to be called at the door of the public functions:

* :func:`float_array` — ``solve_batch(robot, "abc")``, ``check_targets``;
* :func:`positive_float` — ``solve_batch(..., tol_pos="a")``;
* :func:`joint_vector` — ``verify(problem, [0, 0])``;
* :func:`check_output_path` — output files of ``batch``/``reach``/``solve --html``, checked
  *before* computing;
* :func:`read_targets_file` — ``batch --targets`` with a corrupt ``.npz`` or an object
  ``.npy``.
"""

from __future__ import annotations

import functools
import inspect
import math
import os
import reprlib
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any, ParamSpec, TypeVar

import numpy as np

from swarm_ik._types import FloatArray
from swarm_ik.argtypes import SEED_LIMIT
from swarm_ik.errors import InvalidArgumentError, InvalidTargetError
from swarm_ik.paths import file_kind

P = ParamSpec("P")
R = TypeVar("R")


def keywords_checked(func: Callable[P, R]) -> Callable[P, R]:
    """``func`` whose arguments that do not fit its signature (an unknown keyword, a
    missing or extra argument) are refused with :class:`InvalidArgumentError` naming them and
    listing its arguments, as the solvers' own parameters are, instead of Python's bare
    ``TypeError`` (which ``except SwarmIKError`` would miss).  A ``TypeError`` raised inside
    ``func`` is left alone: only one raised by the call itself (no frame of ``func`` in its
    traceback) is the signature's."""
    names = [n for n in inspect.signature(func).parameters if n != "self"]

    @functools.wraps(func)
    def checked(*args: P.args, **kwargs: P.kwargs) -> R:
        try:
            return func(*args, **kwargs)
        except TypeError as exc:
            if exc.__traceback__ is None or exc.__traceback__.tb_next is not None:
                raise  # (raised inside func)
            raise InvalidArgumentError(f"{exc}; its arguments: {', '.join(names)}") from None

    return checked


DEGREES_HINT = "radians and metres are expected: degrees?"
"""What a refusal or warning of joint values beyond their limits adds where they look like
degrees (a target's ``q``, a ``q0`` or a locked value beyond a full turn)."""


def degrees_hint(values: Any) -> str:
    """`` (`` :data:`DEGREES_HINT` ``)`` where one of ``values`` (joint values beyond their
    limits) lies beyond a full turn, as degrees given for radians do; else ``""``."""
    beyond = np.abs(np.asarray(values, dtype=float)) > 2 * np.pi
    return f" ({DEGREES_HINT})" if bool(np.any(beyond)) else ""


def one_line(text: object, limit: int | None = None) -> str:
    """``text`` on one line (whitespace runs, newlines included, become one space), cut at
    ``limit`` characters with an ellipsis at the end (the start of a message says most)."""
    out = " ".join(str(text).split())
    return out if limit is None or len(out) <= limit else out[: limit - 1] + "…"


def quoted_error(exc: BaseException, limit: int = 200) -> str:
    """The text of ``exc`` (a user's code raised it) quoted on one line for a message of
    ours: its start kept whole (``reprlib.repr`` cut it in the middle to 30 characters)."""
    return repr(one_line(exc, limit))


def user_stacklevel() -> int:
    """The ``stacklevel`` that makes a warning of the calling function name the first frame
    outside swarm_ik (the user's line, not a line of the package)."""
    frame = inspect.currentframe()
    frame = frame.f_back if frame is not None else None  # (the function that warns)
    level = 1
    while frame is not None and str(frame.f_globals.get("__name__", "")).startswith("swarm_ik"):
        frame = frame.f_back
        level += 1
    return level


def check_seed(seed: Any) -> int | np.random.Generator:
    """A seed as every solver takes it: an integer in ``[0, 2**63)`` (as an ``int``) or a
    Generator, as it is (None is seed 0).

    Raises:
        InvalidArgumentError: the seed is negative, too large, or not an integer.
    """
    if type(seed) is int and 0 <= seed < SEED_LIMIT:  # (the common case, first)
        return seed
    seed = plain_number(seed)
    if isinstance(seed, np.random.Generator):
        return seed
    if seed is None:
        return 0
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)):
        raise InvalidArgumentError(f"seed must be a non-negative integer, got {seed!r}")
    if not 0 <= seed < SEED_LIMIT:
        raise InvalidArgumentError(f"seed must be in [0, 2**63), got {seed}")
    return int(seed)


def floats_or(
    value: Any, message: Callable[[], str], cls: type[Exception] = InvalidArgumentError
) -> FloatArray:
    """``np.array(value, dtype=float)``, or ``cls(message())`` where numpy cannot convert it
    (letters, ragged nesting, None, other objects): the one conversion behind the checks of
    joint vectors, goal vectors, polygons and step bounds (the message made only on a
    refusal); complex values are refused too (numpy would drop their imaginary parts with a
    warning)."""
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError, OverflowError):  # (ragged nesting)
        raise cls(message()) from None
    kind = not_numbers(raw)
    if kind is not None:
        raise cls(f"{message()} (got {kind})")
    try:
        return np.array(raw, dtype=float)
    except (TypeError, ValueError, OverflowError):  # (None, other objects)
        raise cls(message()) from None


def not_numbers(raw: np.ndarray) -> str | None:
    """What ``raw`` holds when it is not real numbers (``"complex values"``, ``"text"``,
    ``"booleans"``), else None: numpy would read ``"0.4"`` as 0.4, ``True`` as 1.0 and drop
    an imaginary part with a warning, where a number was due."""
    kind = raw.dtype.kind
    if kind == "O":  # (a list mixing numbers and other objects)
        if any(isinstance(v, (str, bytes)) for v in raw.flat):
            return "text"
        if any(isinstance(v, (bool, np.bool_)) for v in raw.flat):
            return "booleans"
        if any(isinstance(v, complex) for v in raw.flat):
            return "complex values"
        return None
    return {"c": "complex values", "U": "text", "S": "text", "b": "booleans"}.get(kind)


def nonnegative(
    value: Any, what: str, shape: tuple[int, ...], bad_value: str | None = None
) -> FloatArray | None:
    """None for None, else ``value`` as finite floats ``>= 0`` of ``shape``: the check of a
    goal's optional tolerance or radius.

    Args:
        value: What the user gave.
        what: The message's first part when ``value`` is not numbers of ``shape`` (text,
            booleans, letters, another shape).
        shape: The expected shape (``()``: one number).
        bad_value: The first part when a number is negative or not finite (default ``what``).

    Raises:
        InvalidArgumentError: ``"{what}, got …"`` or ``"{bad_value}, got …"``.
    """
    if value is None:
        return None
    if isinstance(value, (str, bytes, bool)):
        raise InvalidArgumentError(f"{what}, got {value!r}")
    arr = floats_or(value, lambda: f"{what}, got {value!r}")
    if arr.shape != shape:
        raise InvalidArgumentError(f"{what}, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)) or np.any(arr < 0.0):
        raise InvalidArgumentError(f"{bad_value or what}, got {arr.tolist()}")
    return arr


def float_array(value: Any, what: str = "targets", *, target: bool = True) -> FloatArray:
    """``value`` as a float array, or a SwarmIKError naming ``what``.

    Args:
        value: Anything array-like.
        what: Name for the message.
        target: Raise :class:`InvalidTargetError` (True) or :class:`InvalidArgumentError`.

    Raises:
        InvalidTargetError | InvalidArgumentError: strings, ``None``, ragged nesting,
            objects that are not numbers.
    """
    cls = InvalidTargetError if target else InvalidArgumentError
    if value is None or isinstance(value, (str, bytes)):
        raise cls(f"{what} must be an array of numbers, got {reprlib.repr(value)}")
    if isinstance(value, np.ndarray) and value.dtype == np.float64:
        return value  # (the common case: no copy)
    return floats_or(
        value, lambda: f"{what} must be an array of numbers, got {reprlib.repr(value)}", cls
    )


def json_int(digits: str) -> int | float:
    """``json.loads``'s ``parse_int`` for files users write: an integer of more than 300
    digits is read as a float (``inf`` beyond a float's range, which the value's own check
    then refuses by name), where ``int()`` raises ``ValueError`` past Python's 4,300-digit
    cap."""
    return int(digits) if len(digits) <= 300 else float(digits)


INT_PARAM_MAX = 2**31 - 1
"""The largest count or iteration number a parameter takes (the compiled kernels' integers
hold far more; a larger one is a typo, and one beyond 64 bits would reach numba's typing)."""


def plain_number(value: Any) -> Any:
    """A 0-d numpy array of real numbers as its Python number (``np.array(1.0)`` is taken where
    ``1.0`` is), anything else as it is."""
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
        return value.item()
    return value


def count(value: Any, what: str, lo: int = 1, hi: int = INT_PARAM_MAX) -> int:
    """``value`` as an ``int`` in ``[lo, hi]`` (booleans, floats, strings refused).

    Raises:
        InvalidArgumentError: naming ``what``, the range and the value.
    """
    value = plain_number(value)
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise InvalidArgumentError(
            f"{what} must be an integer in [{lo}, {hi}], got {reprlib.repr(value)}"
        )
    if not lo <= value <= hi:
        raise InvalidArgumentError(f"{what} must be an integer in [{lo}, {hi}], got {value}")
    return int(value)


def flag(value: Any, what: str) -> bool:
    """``value`` as a ``bool``: True or False (numpy's too); anything else (``"False"``, 1,
    None) refused, never read by its truthiness.

    Raises:
        InvalidArgumentError: naming ``what`` and the value.
    """
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise InvalidArgumentError(f"{what} must be True or False, got {reprlib.repr(value)}")


def positive_float(value: Any, what: str) -> float:
    """``value`` as a positive finite float (booleans, strings, NaN, ≤ 0 refused; a 0-d
    array is its number).

    Raises:
        InvalidArgumentError: naming ``what`` and the value.
    """
    value = plain_number(value)
    if not isinstance(value, (bool, np.bool_)) and isinstance(
        value, (int, float, np.integer, np.floating)
    ):
        v = float(value)
        if 0.0 < v < np.inf:
            return v
    raise InvalidArgumentError(f"{what} must be a positive number, got {value!r}")


def joint_vector(robot: Any, q: Any, what: str = "q") -> FloatArray:
    """``q`` checked against ``robot`` (``robot.check_q``): ``nq`` finite numbers.

    Raises:
        InvalidArgumentError: wrong length or non-finite values (the joints listed).
    """
    return np.asarray(robot.check_q(q, what), dtype=float)


def check_output_path(
    path: str | os.PathLike[str], what: str, suffixes: tuple[str, ...] | None = None
) -> Path:
    """Refuse an output file that cannot be written, before any work is done.

    Args:
        path: The file to write.
        what: The option, for the message (e.g. ``"--out"``).
        suffixes: Accepted suffixes (lower case, with the dot); ``None``: any.

    Returns:
        The path.

    Raises:
        InvalidArgumentError: the path is a folder or another file that is not a regular one
            (a device, a FIFO), its folder does not exist or is not a folder, it is not
            writable, or its suffix is not accepted.
    """
    p = Path(path)
    if p.exists() and not p.is_file():  # a folder, a device, a FIFO (a link followed)
        raise InvalidArgumentError(
            f"{what} {str(p)!r} is {file_kind(p.stat().st_mode)}; give a file name"
        )
    if suffixes is not None and p.suffix.lower() not in suffixes:
        raise InvalidArgumentError(
            f"{what} {str(p)!r}: unknown suffix {p.suffix!r}; valid: {', '.join(suffixes)}"
        )
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.exists():
        raise InvalidArgumentError(
            f"{what} {str(p)!r}: folder {str(parent)!r} does not exist (create it first)"
        )
    if not parent.is_dir():
        raise InvalidArgumentError(f"{what} {str(p)!r}: {str(parent)!r} is not a folder")
    if p.exists():  # overwritten in place: it must open for writing
        try:
            with open(p, "ab"):  # opened for writing, not truncated
                pass
        except OSError as exc:
            raise InvalidArgumentError(
                f"{what} {str(p)!r}: not writable ({exc.strerror})"
            ) from None
        return p
    reason = probe_folder(parent)
    if reason is not None:
        raise InvalidArgumentError(
            f"{what} {str(p)!r}: cannot write in folder {str(parent)!r} ({reason})"
        )
    return p


def probe_folder(folder: Path) -> str | None:
    """Why a new file cannot be created in ``folder`` (``None``: it can), found by creating
    and removing an empty one: permission bits alone do not tell (root, read-only mounts)."""
    try:
        fd, name = tempfile.mkstemp(prefix=".swarm-ik-probe-", dir=folder)
    except OSError as exc:
        return exc.strerror or type(exc).__name__
    os.close(fd)
    os.unlink(name)
    return None


MAX_GRID_CELLS = 10_000_000
"""Most voxels a reachability grid may have (its centres alone take 0.24 GB at this size,
the intermediate arrays about 0.6 GB); checked before any array is allocated."""


def grid_cells(lower: Any, upper: Any, resolution: float) -> int | float:
    """Voxels of the grid :func:`swarm_ik.reach.grid_axes` would build, counted without
    allocating it (``ceil(extent / resolution)`` per axis, at least one; ``inf`` for an
    extent beyond a float)."""
    lo = np.asarray(lower, dtype=float).reshape(3)
    hi = np.asarray(upper, dtype=float).reshape(3)
    n = 1
    for a in range(3):
        per_axis = (float(hi[a]) - float(lo[a])) / resolution - 1e-9  # (Python floats: an
        if not math.isfinite(per_axis):  # extent beyond 1.8e308 m is inf, without a warning)
            return math.inf
        n *= max(1, math.ceil(per_axis))
    return n


def finest_edge(lower: Any, upper: Any, cap: int) -> float | None:
    """The finest voxel edge [m] whose grid over the box ``lower``–``upper`` (``(3,)`` each)
    has at most ``cap`` voxels (:func:`grid_cells`, which rounds each axis up), rounded up to
    three digits (so that it fits); None where no edge can be named (an extent beyond a
    float, or a box of no extent)."""
    lo = np.asarray(lower, dtype=float).reshape(3)
    hi = np.asarray(upper, dtype=float).reshape(3)
    sizes = [float(hi[a]) - float(lo[a]) for a in range(3)]
    sides = [e for e in sizes if e > 0.0]  # (the others are one voxel thick at any edge)
    if not sides or not all(math.isfinite(e) for e in sizes) or cap < 1:
        return None
    # by bisection (the count falls as the edge grows) between the root of volume / cap (too
    # fine: a box never has fewer voxels) and the longest side (one voxel); in logarithms,
    # for boxes of 1e-300 or 1e300 m
    a = (sum(math.log(e) for e in sides) - math.log(cap)) / len(sides) - 1e-9
    b = math.log(max(sides))
    for _ in range(200):
        mid = 0.5 * (a + b)
        a, b = (mid, b) if grid_cells(lo, hi, math.exp(mid)) > cap else (a, mid)
    fits = math.exp(b)
    step = 10.0 ** (math.floor(math.log10(fits)) - 2)
    return math.ceil(fits / step * (1 - 1e-12)) * step


def size_text(x: float) -> str:
    """A count or size for a message: three digits, or ``"over 1e300"`` (a grid beyond a
    float's range has an infinite count)."""
    return format(x, ".3g") if x < 1e300 else "over 1e300"


def check_grid_size(
    lower: Any, upper: Any, resolution: Any, max_cells: int = MAX_GRID_CELLS
) -> int:
    """Refuse a voxel grid too large to allocate, before allocating it.

    Args:
        lower: Box corner ``(3,)`` [m].
        upper: Opposite corner ``(3,)`` [m].
        resolution: Voxel edge [m], positive.
        max_cells: Most voxels accepted (default :data:`MAX_GRID_CELLS`).

    Returns:
        The number of voxels.

    Raises:
        InvalidArgumentError: a non-positive or non-finite resolution, or more voxels than
            ``max_cells`` (the message says which resolution would fit).
    """
    res = positive_float(resolution, "resolution")
    n = grid_cells(lower, upper, res)
    if n > max_cells:
        fit = finest_edge(lower, upper, max_cells)
        hint = "" if fit is None else f"--resolution {fit:.3g} or coarser, or "
        raise InvalidArgumentError(
            f"a grid of {res:g} m voxels over this box has {size_text(n)} voxels, more than "
            f"the cap of {max_cells}; use {hint}smaller --bounds"
        )
    return int(n)  # (finite here: at most max_cells)
