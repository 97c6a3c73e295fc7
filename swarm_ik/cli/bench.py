"""``swarm-ik bench NAME``: the benchmarks of :mod:`swarm_ik.bench`, one module each (its
``add_arguments(parser)`` and ``run(args)``; the same module runs as
``python -m swarm_ik.bench.NAME``).

The output folder (``--out``, or the benchmark's default) is checked before any work: a
file, or a folder where nothing can be written, exits 2 with one line.  So is every size or
count option (:data:`swarm_ik.bench.sizes.SIZE_OPTIONS`): a value above its cap exits 2 with
one line naming the option, its value and the cap, before a robot is loaded or anything is
computed (:func:`swarm_ik.bench.sizes.check_sizes`; ``python -m swarm_ik.bench.NAME`` checks
the same).
"""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path
from typing import Any

from swarm_ik.bench.sizes import check_sizes
from swarm_ik.cli._args import UsageError, check_output_folder

BENCHMARKS = {
    "paper": "swarm_ik.bench.paper",
    "ik": "swarm_ik.bench.ik",
    "throughput": "swarm_ik.bench.throughput",
    "goals": "swarm_ik.bench.goals",
    "many": "swarm_ik.bench.many",
    "collision": "swarm_ik.bench.collision",
    "wholebody": "swarm_ik.bench.wholebody",
}
"""Benchmark name -> its module."""

MEASURES = {
    "paper": "the papers' experiments rerun, beside their published numbers",
    "ik": "success and time per IK call against peers (TRAC-IK, DLS, ...)",
    "throughput": "poses per second of batched IK against loops of single solves",
    "goals": "success on goal sets beyond one pose (two arms, axis, look-at)",
    "many": "distinct IK branches found, against eaik's analytic solutions",
    "collision": "collision-free IK success and time in seeded obstacle scenes",
    "wholebody": "a standing humanoid reaching, against placo and pink",
}
"""Benchmark name -> what it measures (one line of ``swarm-ik bench --help``)."""


def add_parser(subparsers: Any, *, with_options: bool = True) -> argparse.ArgumentParser:
    """Add ``bench`` and its benchmarks to the ``swarm-ik`` sub-parsers; ``with_options``
    imports each benchmark module to add its options (only when ``bench`` is the command)."""
    b: argparse.ArgumentParser = subparsers.add_parser(
        "bench",
        help=", ".join(BENCHMARKS),
        description="Benchmarks; each writes CSV files and a report under --out (a folder, "
        "checked before any work).  `swarm-ik bench NAME --help` lists a benchmark's options.",
    )
    bsub = b.add_subparsers(dest="bench", required=True, metavar="NAME")
    for name, module in BENCHMARKS.items():
        bp = bsub.add_parser(name, help=MEASURES[name], description=f"Measures {MEASURES[name]}.")
        if not with_options:
            continue
        try:
            importlib.import_module(module).add_arguments(bp)
        except ModuleNotFoundError as exc:  # an optional dependency it imports
            bp.set_defaults(_missing=f"{module} (needs {exc.name})")
    return b


def _out_folder(args: argparse.Namespace) -> Path:
    """The folder the benchmark will write: ``--out``, or its default."""
    out = getattr(args, "out", None)
    if out is not None:
        return Path(out)
    from swarm_ik.bench.common import default_out

    return default_out(args.bench, bool(getattr(args, "quick", False)))


def run(args: argparse.Namespace) -> int:
    """Run the benchmark ``args.bench``; returns its exit code."""
    missing = getattr(args, "_missing", None)
    if missing:
        raise UsageError(f"swarm-ik: error: benchmark module {missing} is not available")
    check_sizes(args.bench, args)  # before the module runs anything
    module = importlib.import_module(BENCHMARKS[args.bench])
    check_output_folder(_out_folder(args), "--out")
    return int(module.run(args))
