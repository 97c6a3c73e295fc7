"""The console script's start-up: a Ctrl-C while ``swarm-ik`` (or ``python -m swarm_ik.cli``)
imports its modules, before :func:`swarm_ik.cli.main` runs, is one line and exit 130, not
a traceback of the imports.  Imported first by ``swarm_ik/__init__.py``; standard library
only, and nothing is changed in any other process (one that imports swarm_ik, pytest's
included)."""

from __future__ import annotations

import os
import signal
import sys

_OPTIONS_WITH_VALUE = ("-X", "-W")
"""The interpreter's options that take the next word as their value."""


def console_script() -> bool:
    """Whether this process is the ``swarm-ik`` console script or ``python -m swarm_ik.cli``:
    read from ``sys.orig_argv``, the interpreter's own command line, up to what it runs (its
    options skipped; ``python x.py -m swarm_ik.cli`` is ``x.py``'s process, not ours)."""
    argv = list(getattr(sys, "orig_argv", []))
    k = 1
    while k < len(argv) and argv[k].startswith("-") and argv[k] not in ("-m", "-c", "-"):
        k += 2 if argv[k] in _OPTIONS_WITH_VALUE else 1
    if k >= len(argv):
        return False
    if argv[k] == "-m":
        return argv[k + 1 : k + 2] == ["swarm_ik.cli"]
    return os.path.basename(argv[k]) in ("swarm-ik", "swarm-ik.exe")


def _interrupted_at_start(signum: int, frame: object) -> None:
    """One line and exit 130 (the imports need no clean-up)."""
    os.write(2, b"swarm-ik: interrupted\n")
    os._exit(130)


if console_script():  # (replaced by the command's own handling once main runs)
    signal.signal(signal.SIGINT, _interrupted_at_start)
