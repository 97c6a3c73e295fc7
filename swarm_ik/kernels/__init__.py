"""Compiled code only (numba's public API: ``njit`` with ``cache=True``, ``objmode`` for the
clock, first-class function types for the goal kernels): rotation helpers (``lie``), forward
kinematics of every goal frame in one pass over the tree (``fk``), the one
Levenberg–Marquardt kernel over the stacked residual of any goal set (``lm``), the restart
search around it (``search``) and the sphere distances of collision goals (``spheres``).

Nothing here imports a module above ``swarm_ik.kernels``: goals register their compiled
residual kernels with :mod:`swarm_ik.goals`, which hands them to these kernels as a typed list
of functions of one signature (:data:`swarm_ik.kernels.lm.GOAL_SIGNATURE`).

Each compiled function has a numpy twin or a Pinocchio reference it is tested against.

Where numba keeps the compiled kernels is settled here, on import, so a module defining a
``cache=True`` kernel imports this package before its first one (``tests/test_install.py``
checks each): :func:`settle_numba_cache` gives numba a writable folder when the package's own
``__pycache__`` folders cannot be written (a read-only install), and
:func:`drop_damaged_cache_files` removes truncated cache files, which numba would otherwise
fail to load on every run.  docs/robustness.md, "Real installs".
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import platform
import shutil
import signal
import stat
import sys
import threading
from collections.abc import Callable, Iterable, Iterator
from typing import IO, Any, ParamSpec, TypeVar

from swarm_ik import paths
from swarm_ik.errors import SwarmIKError

T = TypeVar("T")
P = ParamSpec("P")
R = TypeVar("R")

KERNEL_PACKAGES = ("", "goals", "kernels", "solvers")
"""The sub-packages of swarm_ik (``""``: the package itself) whose modules define
``cache=True`` kernels (``tests/test_install.py`` checks the list)."""

_PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def source_dirs() -> list[str]:
    """The folders of the modules defining swarm_ik's cached kernels, as numba names them
    (absolute, links not resolved)."""
    return [os.path.join(_PACKAGE, p) if p else _PACKAGE for p in KERNEL_PACKAGES]


def _notice(message: str) -> None:
    """One line on stderr: a cache problem worked around, never an error."""
    print(f"swarm_ik: {message}", file=sys.stderr, flush=True)


def settle_numba_cache() -> str | None:
    """Make sure numba has a writable folder for swarm_ik's compiled kernels.

    numba writes them into ``$NUMBA_CACHE_DIR`` when it is set, else next to each module
    (``__pycache__``), else into the user's cache folder, and refuses to define a
    ``cache=True`` function where none can be written (``cannot cache function …: no locator
    available``).  When ``$NUMBA_CACHE_DIR`` is not a writable folder and the package's
    ``__pycache__`` folders cannot be written, ``NUMBA_CACHE_DIR`` is set to
    ``cache_dir() / "numba"`` (:func:`swarm_ik.paths.cache_dir`, which falls back to a
    private temporary folder), and to ``numba.config.CACHE_DIR`` when numba is already
    imported (numba reads its variables once, on import).  One line on stderr says so when
    that folder is a temporary one or replaces the user's ``$NUMBA_CACHE_DIR``.

    Returns:
        The folder numba caches swarm_ik's kernels under (``$NUMBA_CACHE_DIR``, given or
        set), or ``None`` for the ``__pycache__`` folders next to the modules.
    """
    given = os.environ.get("NUMBA_CACHE_DIR")
    if given and paths.writable_dir(given) and _subfolders_usable(given):
        return given
    if all(paths.writable_dir(os.path.join(d, "__pycache__")) for d in source_dirs()):
        return None  # numba's default, next to the sources
    asked = paths.configured_cache_dir()
    folder = paths.cache_dir() / "numba"
    if not paths.writable_dir(folder):
        _notice(
            "no folder can be written for numba's compiled kernels (the package's, "
            f"{asked}, the temporary directory); set NUMBA_CACHE_DIR to a writable folder"
        )
        return None
    if given:
        _notice(
            f"NUMBA_CACHE_DIR {given!r} cannot be written; numba's compiled kernels are "
            f"cached in {folder}"
        )
    elif asked is None or folder.parent != asked:
        _notice(
            f"neither the package's folder nor {asked} can be written; numba's compiled "
            f"kernels are cached in {folder} (set SWARM_IK_CACHE_DIR to keep them elsewhere)"
        )
    os.environ["NUMBA_CACHE_DIR"] = str(folder)
    # numba imported before this package has read its variables already: its documented
    # mirror of them, ``numba.config.<NAME>`` for ``NUMBA_<NAME>``, takes the same value
    config = getattr(sys.modules.get("numba"), "config", None)
    if config is not None:
        config.CACHE_DIR = str(folder)
    return str(folder)


def _subfolders_usable(numba_cache_dir: str) -> bool:
    """Whether numba can write swarm_ik's kernels under ``numba_cache_dir``: each module
    folder's sub-folder there (:func:`cache_folders`) absent or a writable folder.  A file in
    its place is removed (numba would find no place to cache in: ``no locator available``)."""
    for sub in cache_folders(numba_cache_dir):
        if os.path.lexists(sub) and not os.path.isdir(sub):
            try:
                os.remove(sub)
            except OSError:
                return False
        elif os.path.isdir(sub) and not os.access(sub, os.W_OK | os.X_OK):
            return False
    return True


def cache_folders(numba_cache_dir: str | None) -> list[str]:
    """The folders numba keeps swarm_ik's kernels in: the ``__pycache__`` next to each
    module, or, under ``numba_cache_dir``, the one numba names for each module folder
    (``<folder name>_<SHA-1 of its path>``)."""
    if numba_cache_dir is None:
        return [os.path.join(d, "__pycache__") for d in source_dirs()]
    return [
        os.path.join(
            numba_cache_dir, f"{os.path.basename(d)}_{hashlib.sha1(d.encode()).hexdigest()}"
        )
        for d in source_dirs()
    ]


_PROTO, _STOP = 0x80, 0x2E
_SIZED = {0x95: 8, 0x8E: 8, 0x96: 8, 0x8D: 8, 0x42: 4, 0x58: 4, 0x43: 1, 0x8C: 1, 0x94: 0}
"""Opcodes followed by a little-endian length of that many bytes, then that many bytes: a
frame (protocol 4+), and what a pickler writes outside frames: large bytes and strings
(``BINBYTES8``, ``BYTEARRAY8``, ``BINUNICODE8``, ``BINBYTES``, ``BINUNICODE``,
``SHORT_BINBYTES``, ``SHORT_BINUNICODE``) and the ``MEMOIZE`` after them (no argument)."""


def _whole_pickles(f: IO[bytes], size: int, count: int) -> bool:
    """Whether the file ``f`` of ``size`` bytes is ``count`` whole pickles end to end (numba's
    ``.nbi``: two, the version and the index; its ``.nbc``: one), walked frame by frame
    without unpickling anything: a truncated file ends inside a frame or a length, lacks the
    final ``STOP``, or holds fewer pickles."""
    f.seek(max(size - 1, 0))
    if f.read(1) != bytes([_STOP]):
        return False
    pos = found = 0
    while pos < size:
        f.seek(pos)
        head = f.read(9)
        if not head:  # shorter than it was a moment ago
            return False
        op = head[0]
        if op == _PROTO:
            pos += 2
            found += 1
        elif op in _SIZED:
            width = _SIZED[op]
            if len(head) < 1 + width:
                return False
            pos += 1 + width + int.from_bytes(head[1 : 1 + width], "little")
        else:  # any other opcode outside a frame (protocols before 4): read it the slow way
            import pickletools

            f.seek(pos)
            try:
                next(pickletools.genops(f))
            except (ValueError, StopIteration):
                return False
            pos = f.tell()
    return pos == size and found == count


def drop_damaged_cache_files(folders: Iterable[str]) -> list[str]:
    """Remove the numba cache files (``.nbi`` index, ``.nbc`` data) in ``folders`` that are
    not whole pickles: numba fails to load a truncated one (``UnpicklingError``,
    ``EOFError``) on every call, and never rewrites it; without it, the kernel is compiled
    again on first use and saved anew.  A file that cannot be read or removed is left.

    Returns:
        The paths removed.
    """
    removed = []
    for path in _cache_files(folders):
        if os.path.isdir(path) and not os.path.islink(path):  # (a folder in its place)
            shutil.rmtree(path, ignore_errors=True)
            if not os.path.exists(path):
                removed.append(path)
            continue
        try:
            if not stat.S_ISREG(os.stat(path).st_mode):  # (a FIFO or device in its place:
                os.remove(path)  # opened, it blocked the import for good)
                removed.append(path)
                continue
            with open(path, "rb") as f:
                size = os.fstat(f.fileno()).st_size
                if _whole_pickles(f, size, 2 if path.endswith(".nbi") else 1):
                    continue
            os.remove(path)
        except OSError:
            continue
        removed.append(path)
    return removed


def _cache_files(folders: Iterable[str]) -> Iterator[str]:
    """The paths of the numba cache entries (``.nbi``, ``.nbc``) in ``folders`` (those that
    cannot be listed skipped)."""
    for folder in folders:
        try:
            names = sorted(os.listdir(folder))
        except OSError:
            continue
        for name in names:
            if name.endswith((".nbi", ".nbc")):
                yield os.path.join(folder, name)


_SETTLED: list[str | None] = [None]
"""The folder numba caches swarm_ik's kernels under, as :func:`settle_numba_cache` settled
it on import (None: the ``__pycache__`` folders)."""


def drop_cache_files(folders: Iterable[str]) -> list[str]:
    """Remove every numba cache file (``.nbi``, ``.nbc``) in ``folders``; returns the paths
    removed (those that could not be are left)."""
    removed = []
    for path in _cache_files(folders):
        try:
            os.remove(path)
        except OSError:
            continue
        removed.append(path)
    return removed


def _raised_loading_a_cache(exc: BaseException) -> bool:
    """Whether ``exc`` was raised while numba read a cache file (a frame of its caching
    module in the traceback), not because numba found no folder to cache in: only then are
    the cache files removed."""
    if "no locator available" in str(exc):
        return False
    tb = exc.__traceback__
    while tb is not None:
        name = tb.tb_frame.f_code.co_filename.replace("\\", "/")
        if name.endswith("numba/core/caching.py"):
            return True
        tb = tb.tb_next
    return False


def cut_by_ctrl_c(exc: BaseException) -> bool:
    """Whether ``exc`` is what a Ctrl-C leaves when it cuts a C routine short (a
    ``SystemError``, or an error raised while a ``KeyboardInterrupt`` was handled): an
    interruption, not a damaged cache (whose files would all be removed for nothing)."""
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        if isinstance(e, (SystemError, KeyboardInterrupt)):
            return True
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return False


NOTICE_AFTER = 1.0
"""Seconds of loading the compiled kernels after which one line on stderr says so."""

_SAID: list[bool] = []


def say_preparing() -> None:
    """The one line on stderr while kernels load (once per process: a warm-up of several
    routes, as ``swarm-ik warmup`` runs, or a solve and then a batch, say it once)."""
    if not _SAID:
        _SAID.append(True)
        print(
            "swarm_ik: preparing the compiled kernels (compiled once, then loaded from "
            "numba's cache)…",
            file=sys.stderr,
            flush=True,
        )


@contextlib.contextmanager
def announced() -> Iterator[None]:
    """The body loads compiled kernels (numba's cache, or a compile on a cold one): when it
    takes longer than :data:`NOTICE_AFTER` seconds, :func:`say_preparing` says so (TTY or
    not), so that a first run never waits in silence."""
    timer = threading.Timer(NOTICE_AFTER, say_preparing)
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()


SIGINTS = [0]
"""Ctrl-Cs this process received, counted by :func:`counted_sigint` where swarm_ik's own
entry points (the console script, ``python -m swarm_ik.bench.NAME``) make it the SIGINT
handler; 0 elsewhere (a user's process keeps its own handler)."""


def counted_sigint(signum: int, frame: object) -> None:
    """Python's own Ctrl-C handler (``KeyboardInterrupt``), counted in :data:`SIGINTS`: an
    error that follows one (a C routine cut short, ``SystemError``) is the interruption it
    is, and one that a kernel lost is raised again (:func:`raise_lost_ctrl_c`)."""
    SIGINTS[0] += 1
    signal.default_int_handler(signum, frame)  # type: ignore[arg-type]


@contextlib.contextmanager
def ctrl_c_counted(raise_at_end: bool = False) -> Iterator[None]:
    """Python's own Ctrl-C handler counted (:func:`counted_sigint`) while the body runs, where
    it is the handler in place in the main thread (a program that set its own keeps it, and
    the command line counts already): a Ctrl-C that a kernel's clock read loses is then
    raised by :func:`raise_lost_ctrl_c` after that kernel call, where a batch of far targets
    ran on for good (still running 20 s after the Ctrl-C, once on CI), and, with
    ``raise_at_end`` (a body that handles no Ctrl-C of its own), at the latest when the body
    ends (review 135: a paper solver's run and ``solve_many`` returned a normal answer at the
    end of their budget after 1 in 10 to 1 in 75 Ctrl-Cs).  The count is the body's: put back
    after it, so that a later call starts clean."""
    if (
        threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGINT) is not signal.default_int_handler
    ):
        yield
        return
    before = SIGINTS[0]
    signal.signal(signal.SIGINT, counted_sigint)
    try:
        yield
        if raise_at_end:  # (a Ctrl-C lost on the way: the body never returns normally)
            raise_lost_ctrl_c()
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        SIGINTS[0] = before


def counts_ctrl_c(func: Callable[P, R]) -> Callable[P, R]:
    """``func`` run inside :func:`ctrl_c_counted` (a call of the API whose loops raise a
    Ctrl-C a kernel lost: :func:`raise_lost_ctrl_c`)."""

    @functools.wraps(func)
    def counted(*args: P.args, **kwargs: P.kwargs) -> R:
        with ctrl_c_counted(raise_at_end=True):
            return func(*args, **kwargs)

    return counted


def raise_lost_ctrl_c() -> None:
    """Raise ``KeyboardInterrupt`` when :data:`SIGINTS` counted a Ctrl-C and yet the work goes
    on (called around compiled calls): in the processes that count them, the interruption
    ends the process, so a count that is not zero here is a ``KeyboardInterrupt`` that was
    lost on its way (about 1 of 40 Ctrl-Cs of ``python -m swarm_ik.bench.path``, landing in a
    kernel's object-mode clock read or in a peer's extension, ran on for good)."""
    if SIGINTS[0]:
        raise KeyboardInterrupt


def raise_ctrl_c(exc: BaseException) -> None:
    """Raise the ``KeyboardInterrupt`` behind ``exc`` when a Ctrl-C cut a compiled kernel's
    clock read short, else return (the caller raises ``exc`` again).

    The kernels read the clock in ``numba.objmode`` (:func:`swarm_ik.kernels.search.now`,
    ``wall_clock``), which enters Python through numba's unpickling of the object-mode
    function; a Ctrl-C handled there comes out of the kernel as ``SystemError: … returned a
    result with an exception set``, caused by the ``KeyboardInterrupt``.  A caller's ``except
    KeyboardInterrupt`` (``solve_batch(keep_on_interrupt=True)``, a notebook's interrupt) must
    see the interruption it is."""
    if isinstance(exc, SystemError) and isinstance(exc.__cause__, KeyboardInterrupt):
        raise exc.__cause__ from None


LOADING_MARK = "swarm_ik-loading"
"""The name's prefix of the file a process keeps in swarm_ik's cache folder while it loads
compiled kernels (:func:`loading_marked`; ``<prefix>-<host>-<pid>``)."""

_MARK: list[Any] = [0, None]  # (how deep this process is in marked loads; its file's path)
_MARK_LOCK = threading.Lock()


def _mark_path(host: str, pid: int) -> str | None:
    """Where the loading mark of process ``pid`` on ``host`` lives (None: no cache folder)."""
    folders = cache_folders(_SETTLED[0])
    return os.path.join(folders[0], f"{LOADING_MARK}-{host}-{pid}") if folders else None


@contextlib.contextmanager
def loading_marked() -> Iterator[None]:
    """The body loads compiled kernels from numba's cache: a mark in the cache folder says so
    until it returns or raises.  A process that dies inside, an abort that no Python handler
    sees (LLVM's bitcode reader failing an assertion on a cache file damaged inside), leaves
    its mark, and the next process to import swarm_ik on this host finds it, with its process
    gone, and removes every cache file (:func:`_recover_from_dead_loads`): one run aborts,
    the next compiles anew.  A mark that cannot be written is skipped (a read-only cache)."""
    with _MARK_LOCK:
        if _MARK[0] == 0:
            path = _mark_path(platform.node(), os.getpid())
            try:
                if path is not None:
                    os.makedirs(os.path.dirname(path), exist_ok=True)
                    with open(path, "w"):
                        pass
            except OSError:
                path = None
            _MARK[1] = path
        _MARK[0] += 1
    try:
        yield
    finally:
        with _MARK_LOCK:
            _MARK[0] -= 1
            if _MARK[0] == 0 and _MARK[1] is not None:
                with contextlib.suppress(OSError):
                    os.remove(_MARK[1])
                _MARK[1] = None


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs (or may: one this user cannot signal)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (OSError, OverflowError):  # (PermissionError among them: another user's)
        return True
    return True


def _recover_from_dead_loads() -> list[str]:
    """Remove every swarm_ik cache file when a process of this host died while it loaded
    compiled kernels (its :func:`loading_marked` file left, the process gone), and the marks
    of such processes; returns the cache files removed."""
    folders = cache_folders(_SETTLED[0])
    if not folders:
        return []
    host = platform.node()
    prefix = f"{LOADING_MARK}-{host}-"
    try:
        names = [n for n in os.listdir(folders[0]) if n.startswith(prefix)]
    except OSError:
        return []
    dead = [n for n in names if n[len(prefix) :].isdigit() and not _alive(int(n[len(prefix) :]))]
    if not dead:
        return []
    removed = clear_cache()
    for name in dead:
        with contextlib.suppress(OSError):
            os.remove(os.path.join(folders[0], name))
    return removed


def loaded_despite_damage(load: Callable[[], T], mark: bool = False) -> T:
    """``load()``, a first call that loads compiled kernels from numba's cache; when it fails
    and swarm_ik's cache holds files, they are all removed (one line on stderr) and ``load``
    runs once more, compiling anew.  A cache file whole in length but damaged inside (flipped
    bytes: numba's ``LLVM bitcode parsing error`` or a ``UnicodeDecodeError`` on every run),
    which the check on import cannot see, so costs one compile instead of every solve.  An
    error that is not the cache's comes back from the second call as it was; a Ctrl-C that
    cut the kernel's clock read short as ``KeyboardInterrupt`` (:func:`raise_ctrl_c`).
    ``mark``: the call is a load that returns soon (a route's warm-up, the goal kernels'
    table, the first batched FK), marked for the next process if it aborts
    (:func:`loading_marked`); a call that runs the work itself (a batch, a command) is not
    marked: a kill in the middle of it is no sign of a damaged cache."""
    try:
        if mark:
            with loading_marked():
                return load()
        return load()
    except (KeyboardInterrupt, SwarmIKError):
        raise
    except Exception as exc:
        raise_ctrl_c(exc)
        raise_lost_ctrl_c()  # (a Ctrl-C counted: what failed is its doing, not the cache's)
        if not _raised_loading_a_cache(exc) or cut_by_ctrl_c(exc):
            raise
        removed = clear_cache()
        if not removed:
            raise
        _notice(
            f"loading the compiled kernels failed ({type(exc).__name__}: "
            f"{str(exc).strip().splitlines()[0][:120] if str(exc).strip() else ''}); removed "
            f"{len(removed)} numba cache file(s) under "
            f"{os.path.commonpath([os.path.dirname(p) for p in removed])}; compiling again"
        )
        return load()


def clear_cache() -> list[str]:
    """Remove every numba cache file of swarm_ik's kernels (in the folder settled on import),
    so that each kernel is compiled again on its next first call; returns the paths removed.
    ``swarm-ik warmup --fresh`` runs it first: the remedy for a cache file damaged so that
    loading it aborts the process inside LLVM (an assertion in its bitcode reader, which no
    Python handler can catch)."""
    return drop_cache_files(cache_folders(_SETTLED[0]))


def _settle() -> None:
    """Settle the cache folder, then drop the damaged files in it, or all of them after a
    process died loading them (one line on stderr)."""
    _SETTLED[0] = settle_numba_cache()
    after_abort = _recover_from_dead_loads()
    if after_abort:
        _notice(
            f"a process died while it loaded the compiled kernels (an abort on a damaged cache "
            f"file?); removed {len(after_abort)} numba cache file(s) under "
            f"{os.path.commonpath([os.path.dirname(p) for p in after_abort])}; their kernels "
            "are compiled again on first use"
        )
    removed = drop_damaged_cache_files(cache_folders(_SETTLED[0]))
    if removed:
        names = ", ".join(os.path.basename(p) for p in removed[:3])
        more = f" and {len(removed) - 3} more" if len(removed) > 3 else ""
        _notice(
            f"removed {len(removed)} damaged numba cache file(s) ({names}{more}) under "
            f"{os.path.commonpath([os.path.dirname(p) for p in removed])}; their kernels are "
            "compiled again on first use"
        )


_settle()
