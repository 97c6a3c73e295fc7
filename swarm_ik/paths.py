"""Where swarm_ik finds and keeps files: its cache folder, the folders searched for
``package://`` meshes, the bundled robots and the ``example-robot-data`` package.  (Imports
nothing of swarm_ik but its errors: every layer may use it.)"""

from __future__ import annotations

import os
import sys
import tempfile
from importlib import resources
from pathlib import Path

from swarm_ik.errors import RobotFileNotFoundError, SwarmIKError


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


def cache_dir() -> Path:
    """Folder of swarm_ik's caches (sampled collision pairs, fitted spheres).

    ``$SWARM_IK_CACHE_DIR``, else ``$XDG_CACHE_HOME/swarm_ik``, else ``~/.cache/swarm_ik``;
    created on first use.  Where that folder cannot be created or written (a read-only home,
    the variable naming a file), a folder in the system's temporary directory instead: a
    cache never stops a solve.
    """
    env = os.environ.get("SWARM_IK_CACHE_DIR")
    if env:
        d = Path(env)
    else:
        base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
        d = Path(base) / "swarm_ik"
    try:
        d.mkdir(parents=True, exist_ok=True)
        if os.access(d, os.W_OK):
            return d
    except OSError:
        pass
    # an unwritable (or not a folder) cache location: a private folder of this process
    fallback = (
        Path(tempfile.gettempdir())
        / f"swarm_ik-cache-{os.getuid() if hasattr(os, 'getuid') else 0}"
    )
    fallback.mkdir(parents=True, exist_ok=True)
    return fallback


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
