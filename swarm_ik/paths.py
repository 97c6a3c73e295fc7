"""Where swarm_ik finds and keeps files: its cache folder, the folders searched for
``package://`` meshes, the bundled robots and the ``example-robot-data`` package, and the
robots loadable by name.  (Imports nothing of swarm_ik but its errors: every layer may use
it, and ``swarm-ik robots`` lists the robots without loading the kernels.)"""

from __future__ import annotations

import contextlib
import os
import stat
import sys
import tempfile
from collections.abc import Iterator
from importlib import resources
from pathlib import Path

from swarm_ik.errors import InvalidArgumentError, RobotFileNotFoundError, SwarmIKError


def bundled_robot_dir() -> Path:
    """Folder holding the bundled URDFs (``robots/`` of the repository, installed as
    ``swarm_ik.robots``)."""
    return Path(str(resources.files("swarm_ik.robots")))


def example_robot_data_dir() -> Path:
    """The ``robots`` folder of the installed ``example-robot-data`` package.

    ``$EXAMPLE_ROBOT_DATA_DIR`` overrides the search.

    Raises:
        RobotFileNotFoundError: the package is not installed.
    """
    env = os.environ.get("EXAMPLE_ROBOT_DATA_DIR")
    candidates = [Path(env)] if env else []
    for entry in sys.path:
        candidates.append(Path(entry) / "cmeel.prefix" / "share" / "example-robot-data" / "robots")
    candidates.append(Path(sys.prefix) / "share" / "example-robot-data" / "robots")
    for c in candidates:
        if c.is_dir():
            return c
    raise RobotFileNotFoundError(
        "the example-robot-data package was not found; install it with "
        "`pip install example-robot-data` or set EXAMPLE_ROBOT_DATA_DIR"
    )


def configured_cache_dir() -> Path | None:
    """The cache folder asked for: ``$SWARM_IK_CACHE_DIR``, else ``$XDG_CACHE_HOME/swarm_ik``,
    else ``~/.cache/swarm_ik``; ``None`` when there is no home folder to put it in.  Neither
    created nor checked (:func:`cache_dir` does both)."""
    env = os.environ.get("SWARM_IK_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME")
    if not base:
        try:
            base = str(Path.home() / ".cache")
        except (RuntimeError, KeyError):  # no $HOME and no password entry
            return None
    return Path(base) / "swarm_ik"


def writable_dir(folder: str | os.PathLike[str]) -> bool:
    """Whether ``folder`` is, or can be made, a folder this process can create files in.

    numba's own test of a cache folder: the folder is created, then a temporary file in it
    (permission bits alone would say yes to root on a read-only mount).
    """
    try:
        os.makedirs(folder, exist_ok=True)
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True


_PRIVATE_DIR: Path | None = None
"""This process's own temporary cache folder, once :func:`_temporary_cache_dir` made one."""


def _temporary_cache_dir() -> Path | None:
    """``<temp>/swarm_ik-cache-<uid>`` (made private to the user), or a fresh folder of this
    process when that one is not ours (owned by another user, a link): cached compiled code
    and pickles are loaded from it, so a folder someone else planted is never used."""
    global _PRIVATE_DIR
    try:
        tmp = Path(tempfile.gettempdir())
        if hasattr(os, "getuid"):
            shared = tmp / f"swarm_ik-cache-{os.getuid()}"
            try:
                shared.mkdir(mode=0o700)
            except FileExistsError:
                pass
            st = shared.lstat()
            if stat.S_ISDIR(st.st_mode) and st.st_uid == os.getuid():
                if st.st_mode & 0o077:  # ours, made under a lax umask: made private
                    shared.chmod(0o700)
                if writable_dir(shared):
                    return shared
        elif writable_dir(tmp / "swarm_ik-cache"):
            return tmp / "swarm_ik-cache"
    except OSError:
        pass
    if _PRIVATE_DIR is None:
        try:
            _PRIVATE_DIR = Path(tempfile.mkdtemp(prefix="swarm_ik-cache-"))
        except OSError:  # no temporary folder can be written either
            return None
    return _PRIVATE_DIR


def cache_dir() -> Path:
    """Folder of swarm_ik's caches (sampled collision pairs, fitted spheres, and numba's
    compiled kernels when the package's own folder cannot hold them).

    :func:`configured_cache_dir`, created on first use.  Where that folder cannot be created
    or written (a read-only home, the variable naming a file), a folder in the system's
    temporary directory instead (``<temp>/swarm_ik-cache-<uid>``, private to the user): a
    cache never stops a solve.  Never raises; only when not even the temporary directory can
    be written is the returned folder unwritable, and the callers skip a failed cache write.
    """
    d = configured_cache_dir()
    if d is not None and writable_dir(d):
        return d
    fallback = _temporary_cache_dir()
    if fallback is not None:
        return fallback
    # nothing on disk can be written: a name the callers' writes fail in, and skip
    return d if d is not None else Path("swarm_ik-cache")


def package_dirs(urdf_path: str | os.PathLike[str]) -> list[str]:
    """Folders searched for ``package://`` meshes: the URDF's folder and its two parents (a
    ``<pkg>/urdf/robot.urdf`` layout), the ``example-robot-data`` folders when installed,
    and ``$ROS_PACKAGE_PATH`` (the resolver of :mod:`swarm_ik.viz`)."""
    dirs: list[Path] = []
    here = Path(urdf_path).resolve().parent
    dirs += [here, here.parent, here.parent.parent]
    try:
        erd = example_robot_data_dir()
        dirs += [erd, erd.parent, erd.parent.parent]
    except SwarmIKError:
        pass
    dirs += [Path(p) for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
    out: list[str] = []
    for d in dirs:
        s = str(d)
        if s not in out and d.is_dir():
            out.append(s)
    return out


# --------------------------------------------------------------------------- robots by name
BUNDLED: dict[str, tuple[str, str]] = {
    "yumi_left": ("yumi_left.urdf", "yumi_tool"),
    "loading_manipulator": ("loading_manipulator.urdf", "spreader"),
    "loading_manipulator_long": ("loading_manipulator_long.urdf", "spreader"),
}
"""Bundled robots: name -> (file in ``robots/``, end-effector frame)."""

EXAMPLE_ROBOTS: dict[str, tuple[str, str | tuple[str, ...]]] = {
    "panda": ("panda_description/urdf/panda.urdf", "panda_hand_tcp"),
    "ur3": ("ur_description/urdf/ur3_robot.urdf", "tool0"),
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "tool0"),
    "ur10": ("ur_description/urdf/ur10_robot.urdf", "tool0"),
    "kinova": ("kinova_description/robots/kinova.urdf", "j2s6s200_end_effector"),
    "xarm7": ("xarm_description/urdf/xarm7.urdf", "link_eef"),
    "z1": ("z1_description/urdf/z1.urdf", "link06"),
    "baxter_left": ("baxter_description/urdf/baxter.urdf", "left_gripper"),
    "baxter": ("baxter_description/urdf/baxter.urdf", ("left_gripper", "right_gripper")),
    "talos": (
        "talos_data/robots/talos_reduced.urdf",
        ("gripper_left_base_link", "gripper_right_base_link"),
    ),
}
"""Robots of the ``example-robot-data`` package with a curated default: name -> (URDF path
under its ``robots/`` folder, default end-effector frame(s)).  Joints off the root →
end-effector chain (grippers) are locked at their neutral value.  Every other URDF of the
package loads by its file name too (:func:`example_robot_files`), with the default frame
rule of a file."""


def example_robot_files() -> dict[str, str]:
    """Every URDF of the installed example-robot-data by name: the file's stem with hyphens
    as underscores (``tiago``, ``romeo``, ``solo12``, ``b1_z1``), the first in path order where
    two files share a stem; name -> path under its ``robots/`` folder.  Empty when the
    package is not installed."""
    try:
        root = example_robot_data_dir()
    except RobotFileNotFoundError:
        return {}
    out: dict[str, str] = {}
    for p in sorted(root.rglob("*.urdf")):
        out.setdefault(p.stem.replace("-", "_"), p.relative_to(root).as_posix())
    return out


def robot_names() -> dict[str, list[str]]:
    """Robots loadable by name: ``{"bundled": [...], "example-robot-data": [...]}`` (the
    curated :data:`EXAMPLE_ROBOTS`, with their usual tool frames, and every other URDF of the
    package, :func:`example_robot_files`)."""
    return {
        "bundled": sorted(BUNDLED),
        "example-robot-data": sorted(set(EXAMPLE_ROBOTS) | set(example_robot_files())),
    }


def _umask() -> int:
    """This process's umask (read once: setting it back and forth is not thread-safe)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


_UMASK = _umask()


def file_kind(mode: int) -> str:
    """What a path of ``st_mode`` ``mode`` is, in words (for a refusal)."""
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a named pipe (FIFO)"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


@contextlib.contextmanager
def written_in_place_of(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A new file beside ``path`` for the body to write, renamed onto ``path`` when the body
    ends (removed if it raises): an interruption (Ctrl-C, a full disk) leaves ``path`` as it
    was, never a partial file (a full disk truncated a reachability map's page in place).

    The temporary file has a name of its own per call (two writers of one path do not share
    it), ends in ``.part`` (a writer that adds a suffix to a name without its own must be given
    a file object or a format), and gets the mode of the file it replaces (else the umask's).
    A symbolic link is followed: the file it points to is replaced, the link kept.  Where no
    file can be made beside ``path`` (a folder that is not writable, holding a writable file)
    the body writes ``path`` itself, as a plain write would.  The replaced file's other hard
    links keep its old content.  A path that is not a regular file (a device, a FIFO, a
    folder, or a link to one) is refused with :class:`InvalidArgumentError`.
    """
    p = Path(os.path.realpath(path))
    if p.exists() and not p.is_file():  # (a device, a FIFO, a folder: replaced by a file,
        # /dev/null became a page; what a writer is given to replace is a file)
        raise InvalidArgumentError(
            f"{str(path)!r} is {file_kind(p.stat().st_mode)}; give a file name"
        )
    try:
        fd, name = tempfile.mkstemp(dir=p.parent, prefix=f".{p.name[:40]}.", suffix=".part")
    except OSError:
        yield p
        return
    os.close(fd)
    part = Path(name)
    try:
        mode = stat.S_IMODE(p.stat().st_mode) if p.exists() else 0o666 & ~_UMASK
        os.chmod(part, mode)
        yield part
        os.replace(part, p)
    except OSError as exc:
        part.unlink(missing_ok=True)
        if exc.filename is None:  # (a failed write names no file: the one asked for is named)
            raise OSError(exc.errno, exc.strerror, str(path)) from None
        raise
    except BaseException:
        part.unlink(missing_ok=True)
        raise
