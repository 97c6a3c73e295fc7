"""Command line: ``swarm-ik robots | solve | show | batch | reach | bench …``.

One module per sub-command (:data:`COMMANDS`), each with ``add_parser(subparsers)`` and
``run(args) -> int``; this module builds the top parser, dispatches, and turns every error
into an exit code and one line:

* 0 success;
* 1 target not reached (the best found is still printed), or some targets of ``batch``;
* 2 bad input (one line on stderr, no traceback; with ``--json`` one JSON object
  ``{"error": …, "exit_code": 2, …}`` on stdout instead);
* 3 an unexpected error inside swarm_ik (one line; set ``SWARM_IK_DEBUG=1`` to see the
  traceback);
* 74 the output could not be written (a full disk, ``> /dev/full``: one line);
* 130 interrupted (Ctrl-C, at any point of the command; the Ctrl-C that closes a live viewer
  is its end, and the command exits with its own outcome);
* 141 the reader of the output went away (``swarm-ik … | head``), without a traceback.

Numbers may be negative in any notation (``--from-q -1e-3 0.5 -2``): the parser does not take
``-1e-3`` for an option.  Usage errors are one line too, naming the sub-command's ``--help``.

Importing this package loads the sub-command modules, which import what they need when they
run.  In the console script (or ``python -m swarm_ik.cli``) a Ctrl-C during these imports,
before :func:`main` runs, is one line and 130 too (:mod:`swarm_ik._startup`).
"""

from __future__ import annotations

import _thread
import argparse
import difflib
import errno
import gc
import importlib.metadata
import json
import os
import re
import signal
import sys
import threading
import warnings
from collections.abc import Sequence
from typing import Any, NoReturn

from swarm_ik import kernels
from swarm_ik.cli import batch, bench, path, reach, robots, show, solve, warmup
from swarm_ik.cli._args import (
    EXIT_BAD_INPUT,
    EXIT_BROKEN_PIPE,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_NOT_REACHED,
    EXIT_OK,
    EXIT_OUTPUT_FAILED,
    UsageError,
)
from swarm_ik.cli.bench import BENCHMARKS
from swarm_ik.errors import SwarmIKError

__all__ = [
    "BENCHMARKS",
    "COMMANDS",
    "EXIT_BAD_INPUT",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "EXIT_NOT_REACHED",
    "EXIT_OK",
    "Formatter",
    "Parser",
    "UsageError",
    "build_parser",
    "main",
]

COMMANDS = {
    "robots": robots,
    "warmup": warmup,
    "solve": solve,
    "path": path,
    "show": show,
    "batch": batch,
    "reach": reach,
    "bench": bench,
}
"""The sub-commands, in the order ``swarm-ik --help`` lists them: name -> module with
``add_parser(subparsers)`` and ``run(args) -> int``."""

_NEGATIVE_NUMBER = re.compile(
    r"^-(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?$|^-(?:inf|infinity|nan)$", re.IGNORECASE
)
"""What the parser reads as a negative number rather than an option: ``-1``, ``-.5``,
``-1e-3``, ``-2.5E+4``, ``-inf``."""


class Formatter(argparse.HelpFormatter):
    """Help layout: an option whose ``metavar`` is one string describing all its values
    (``--pose X Y Z [QX QY QZ QW]``) is shown with it as written, not repeated; an option
    given a ``help_text`` function after it was added shows what that function returns,
    made when the help is printed (names that need heavy imports; the plain ``help`` given
    to ``add_argument`` is what argparse checks there); and the
    column of the help texts counts the indent of sub-command names, so that a name as long
    as ``throughput`` keeps its help on its own line (argparse leaves it out); lines break
    between words, never at a hyphen inside a name."""

    def add_argument(self, action: argparse.Action) -> None:
        super().add_argument(action)
        if action.help is argparse.SUPPRESS or not isinstance(action, argparse._SubParsersAction):
            return
        names = [self._format_action_invocation(a) for a in action._get_subactions()]
        if names:
            width = max(map(len, names)) + self._current_indent + self._indent_increment
            self._action_max_length = max(self._action_max_length, width)

    def _expand_help(self, action: argparse.Action) -> str:
        text = getattr(action, "help_text", None)  # a help made only when it is shown
        if text is not None:
            return str(text())
        return super()._expand_help(action)

    def _format_args(self, action: argparse.Action, default_metavar: str) -> str:
        if getattr(action, "whole_metavar", False) and isinstance(action.metavar, str):
            return action.metavar
        return super()._format_args(action, default_metavar)

    def _split_lines(self, text: str, width: int) -> list[str]:
        # (lines broken between words only: a name such as pso-improved or --time-limit was
        # cut at its hyphen, "pso- improved")
        import textwrap

        return textwrap.wrap(" ".join(text.split()), width, break_on_hyphens=False)


class Parser(argparse.ArgumentParser):
    """``argparse.ArgumentParser`` that takes ``-1e-3`` for a number and reports usage errors
    as :class:`UsageError` (printed as one line by :func:`main`) instead of eight lines of
    usage.  Sub-parsers inherit the class (and with it the :class:`Formatter`)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", Formatter)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER

    _deepest: Parser | None = None
    """The parser that parsed last (a command's, under the top one): the one whose options an
    unknown one is compared with, and whose help is named."""

    def parse_known_args(self, args: Any = None, namespace: Any = None) -> Any:
        Parser._deepest = self
        self._given = [str(a) for a in (sys.argv[1:] if args is None else args)]
        return super().parse_known_args(args, namespace)

    def error(self, message: str) -> NoReturn:
        # (review 136: `solve --target` said only that --pose or --goals is required, and an
        # unknown flag pointed at `swarm-ik --help`, which lists no command's flags)
        deepest = Parser._deepest or self
        known = getattr(deepest, "_option_string_actions", {})  # (argparse's table of flags)
        unknown = [
            a.split("=", 1)[0]
            for a in getattr(deepest, "_given", [])
            if a.startswith("--") and a != "--" and a.split("=", 1)[0] not in known
        ]
        if unknown:
            if "unrecognized arguments" not in message:
                message = f"unrecognized arguments: {' '.join(unknown)}; {message}"
            flag = unknown[0]
            close = [k for k in known if k.startswith("--") and min(len(k), len(flag)) > 4
                     and (flag.startswith(k) or k.startswith(flag))]  # fmt: skip
            for k in difflib.get_close_matches(flag, list(known), n=2, cutoff=0.6):
                if k not in close:
                    close.append(k)
            close = close[:2]
            if close:
                message += f"; did you mean {' or '.join(close)}?"
        prog = deepest.prog
        raise UsageError(f"{prog}: error: {message} (see `{prog} --help`)")

    def _print_message(self, message: str, file: Any = None) -> None:
        """The help, written and flushed; a write that fails (``--help > /dev/full``) raises
        (argparse's own passes it over, and the command exited 0 having written nothing)."""
        if message:
            out = sys.stderr if file is None else file
            out.write(message)
            out.flush()


EPILOG = (
    "exit codes: 0 success, 1 target not reached (the best found is printed), 2 bad input "
    "(one line on stderr), 3 internal error (one line; SWARM_IK_DEBUG=1 shows the "
    "traceback), 74 output could not be written (a full disk), 130 interrupted (Ctrl-C; "
    "one that closes a live viewer ends it, and the command exits with its own outcome), "
    "141 output pipe closed.  `swarm-ik COMMAND "
    "--help` describes a command."
)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The whole parser; given the ``command`` about to run (``argv[0]``), the benchmarks'
    options are added (their modules imported) only if it is ``bench``."""
    parser = Parser(
        prog="swarm-ik",
        description="Inverse kinematics for URDF robots with swarm optimisers and Pinocchio.",
        epilog=EPILOG,
    )
    parser.add_argument("--version", action="version", version=f"swarm-ik {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in COMMANDS.values():
        if module is bench:
            bench.add_parser(sub, with_options=command in (None, "bench"))
        else:
            module.add_parser(sub)
    return parser


def _version() -> str:
    """The installed package's version (``swarm-ik --version``)."""
    try:
        return importlib.metadata.version("swarm_ik")
    except importlib.metadata.PackageNotFoundError:  # (run from a source tree, not installed)
        return "(not installed)"


def _fail(message: str, code: int, as_json: bool, kind: str) -> int:
    """Report an error as one line on stderr (or one JSON object on stdout); returns ``code``."""
    message = " ".join(str(message).split())
    if as_json:
        try:
            print(json.dumps({"error": message, "kind": kind, "exit_code": code}), flush=True)
            return code
        except OSError:  # (standard output cannot be written: the line on stderr instead)
            pass
    prefix = "" if message.startswith("swarm-ik") else "swarm-ik: error: "
    try:
        print(prefix + message, file=sys.stderr, flush=True)
    except OSError:  # (standard error cannot be written, `2>/dev/full`: the exit code says it)
        pass
    return code


def _dispatch(args: argparse.Namespace) -> int:
    module = COMMANDS.get(args.command)
    if module is None:  # pragma: no cover - argparse refuses unknown commands first
        raise UsageError(f"swarm-ik: error: unknown command {args.command!r}")
    return int(module.run(args))


def _one_line_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: Any = None,
    line: str | None = None,
) -> None:
    """A warning as the command line prints it: one line, ``swarm-ik: warning: …``, without
    the package's file, line and source (a ``q0`` clipped into the limits, say); none where
    standard error cannot be written (``2>/dev/full``: the command goes on, its exit code
    its own)."""
    try:
        print(f"swarm-ik: warning: {message}", file=sys.stderr if file is None else file)
    except OSError:
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``swarm-ik`` console script; returns the exit code.

    Never raises (except ``SystemExit`` from ``--help``): bad input gives 2 and one line,
    anything unexpected 3 and one line (``SWARM_IK_DEBUG=1`` re-raises it), Ctrl-C 130.
    """
    script = argv is None  # the console script: this process is ours to tune
    console = script
    if sys.stdout is None:  # (started with standard output closed, `>&-`: what it prints
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115  # goes nowhere, as with >/dev/null)
    argv = list(sys.argv[1:] if argv is None else argv)
    as_json = "--json" in argv
    try:
        if script:
            _own_process()
        parser = build_parser(argv[0] if argv else None)
        args = parser.parse_args(argv)
        as_json = bool(getattr(args, "json", False))
        if script and args.command not in SHORT_COMMANDS:
            gc.enable()
            script = False  # a long command: collect, and exit the usual way
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            warnings.showwarning = _one_line_warning  # (restored with the filters)
            # Dask's start-up chatter (dashboard port taken, sockets) is not the user's concern
            warnings.filterwarnings("ignore", module=r"distributed(\.|$)")
            warnings.filterwarnings("ignore", category=ResourceWarning)
            # numba's note that first-class functions (the goal kernels' table) are
            # experimental: a design choice of the package, not the user's concern
            warnings.filterwarnings("ignore", message="First-class function type feature")
            # (a numba cache damaged inside its files, met by any compiled call of the
            # command: the files removed, the command run again, compiling anew)
            code = kernels.loaded_despite_damage(lambda: _dispatch(args))
            sys.stdout.flush()  # (a full disk is met here, not after main returns)
            return code
    except UsageError as exc:
        return _fail(str(exc), EXIT_BAD_INPUT, as_json, "UsageError")
    except SwarmIKError as exc:
        return _fail(str(exc), EXIT_BAD_INPUT, as_json, type(exc).__name__)
    except KeyboardInterrupt:
        return _interrupted(as_json)
    except BrokenPipeError:  # the reader went away (`swarm-ik … | head`): no traceback
        _quiet_stdout()
        return EXIT_BROKEN_PIPE
    except OSError as exc:
        if exc.errno in _FULL_ERRNOS or (exc.errno == errno.EIO and _stdout_fails()):
            return _cannot_write(exc, as_json, script)
        return _unexpected(exc, as_json)
    except Exception as exc:
        return _unexpected(exc, as_json)
    finally:
        if script:  # shutdown then skips the ~10^6 objects numba made (~0.25 s): a short
            gc.freeze()  # command only (extensions that report leaks at exit stay quiet)
        if console:  # the exit code is decided: a Ctrl-C during the interpreter's shutdown
            # (its exit handlers take 0.1-0.3 s after a batch) no longer kills the process by
            # the signal (status -2 to a caller, no line), the code stands
            signal.signal(signal.SIGINT, signal.SIG_IGN)


_FULL_ERRNOS = (errno.ENOSPC, errno.EFBIG, errno.EDQUOT)
"""Errors of a write on a full disk or past a quota (``> /dev/full``, ``--out`` on a full
disk): exit :data:`EXIT_OUTPUT_FAILED` with one line, not an internal error; so is an
input/output error of standard output itself (:func:`_stdout_fails`)."""


def _stdout_fails() -> bool:
    """Whether writing standard output fails now (an input/output error met elsewhere, reading
    a file on a failing disk, is not the output's)."""
    try:
        sys.stdout.flush()
    except OSError:
        return True
    return False


def _cannot_write(exc: OSError, as_json: bool, script: bool) -> int:
    """Exit :data:`EXIT_OUTPUT_FAILED` with one line naming the file when known (with
    ``--json``, the JSON object when standard output still takes it: :func:`_fail`); the
    console script's standard output then points at the null device, so that
    the exit's flush of what could not be written fails quietly."""
    where = f" {exc.filename!r}" if exc.filename else ""
    try:
        return _fail(
            f"swarm-ik: cannot write{where} ({exc.strerror})", EXIT_OUTPUT_FAILED, as_json,
            type(exc).__name__,
        )  # fmt: skip
    finally:
        if script:
            _quiet_stdout()


def _quiet_stdout() -> None:
    """Point standard output at the null device, so that the exit's flush of what could not
    be written fails quietly (no "Exception ignored" lines)."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())


def _unexpected(exc: Exception, as_json: bool) -> int:
    """Exit 3 and one line for an error inside swarm_ik (or 130 for one that a Ctrl-C
    caused); ``SWARM_IK_DEBUG=1`` raises it again."""
    if kernels.SIGINTS[0]:  # (a Ctrl-C that cut a C routine short: SystemError and the like)
        return _interrupted(as_json)
    if os.environ.get("SWARM_IK_DEBUG"):
        raise exc
    what = "out of memory" if isinstance(exc, MemoryError) else f"{type(exc).__name__}: {exc}"
    return _fail(
        f"swarm-ik: internal error ({what}); please report it, with the command line "
        "(set SWARM_IK_DEBUG=1 for the traceback)",
        EXIT_INTERNAL,
        as_json,
        type(exc).__name__,
    )


def _interrupted(as_json: bool) -> int:
    """Exit 130 with one line; a second Ctrl-C while it is printed changes nothing."""
    try:
        return _fail("swarm-ik: interrupted", EXIT_INTERRUPTED, as_json, "KeyboardInterrupt")
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED


SHORT_COMMANDS = ("solve", "robots")
"""Commands run with the cyclic garbage collector off: they make few objects after start-up,
and its passes over numba's ~10^6 import-time objects cost ~0.08 s of a ~0.7 s solve."""


def _own_process() -> None:
    """Start-up tuning for the console script only (never for :func:`main` called with
    ``argv``, in someone else's process).

    The collector is off until the command is known (:data:`SHORT_COMMANDS` keep it off).
    A Ctrl-C is counted (:func:`swarm_ik.kernels.counted_sigint`), and one that lands in a
    callback from compiled code while kernels load, where Python swallows it ("Exception
    ignored on calling ctypes callback"), is raised again (:func:`_unraisable`).
    """
    gc.disable()
    signal.signal(signal.SIGINT, kernels.counted_sigint)
    sys.unraisablehook = _unraisable


def _unraisable(args: Any) -> None:
    """``sys.unraisablehook``: a ``KeyboardInterrupt`` raised where it cannot propagate (a
    callback from compiled code) is raised again in the main thread; anything else as
    Python reports it."""
    if isinstance(args.exc_value, KeyboardInterrupt):  # (raised a moment later: out of the
        # callback, where it would be swallowed again)
        timer = threading.Timer(0.02, _thread.interrupt_main)
        timer.daemon = True
        timer.start()
        return
    sys.__unraisablehook__(args)
