"""The console script's start-up: a Ctrl-C while ``swarm-ik`` (or ``python -m swarm_ik.cli``)
imports its modules, before :func:`swarm_ik.cli.main` runs, is one line and exit 130, not
a traceback of the imports.  Imported first by ``swarm_ik/__init__.py``; standard library
only, and nothing is changed in any other process (one that imports swarm_ik, pytest's
included)."""

from __future__ import annotations

import os
import signal
import sys


def console_script() -> bool:
    """Whether this process is the ``swarm-ik`` console script or ``python -m swarm_ik.cli``
    (read from ``sys.orig_argv``, the interpreter's own command line)."""
    argv = list(getattr(sys, "orig_argv", []))
    script = len(argv) > 1 and os.path.basename(argv[1]) in ("swarm-ik", "swarm-ik.exe")
    return script or any(
        a == "-m" and b == "swarm_ik.cli" for a, b in zip(argv, argv[1:], strict=False)
    )


def _interrupted_at_start(signum: int, frame: object) -> None:
    """One line and exit 130 (the imports need no clean-up)."""
    os.write(2, b"swarm-ik: interrupted\n")
    os._exit(130)


if console_script():  # (replaced by the command's own handling once main runs)
    signal.signal(signal.SIGINT, _interrupted_at_start)
