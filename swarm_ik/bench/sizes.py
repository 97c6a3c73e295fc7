"""Caps of the benchmarks' size and count options (``swarm-ik bench NAME`` and ``python -m
swarm_ik.bench.NAME``): a value above its cap is refused with one line naming the option, its
value and the cap, before a robot is loaded or anything is computed."""

from __future__ import annotations

import argparse

from swarm_ik.errors import InvalidArgumentError

MAX_TARGETS = 100_000
"""Most targets a benchmark draws per robot, experiment or scene (``--n`` of ``ik``, ``goals``,
``collision`` and ``wholebody``, ``--n-targets`` of ``many``; ``--batch-n``, ``--ablation-n``
and ``--diagnose`` of ``collision``; ``--chunk`` of ``wholebody``): 100 times ``bench ik``'s
default (1000), 200 times ``goals``' and ``wholebody``'s (500).  Every target keeps a row per
peer (about 1 kB each) in memory until the CSV is written, and a task of ``bench ik`` is made
up front per target, robot and budget: this bounds them to a few GB, and the run to hours
(at the default budgets), where 10**12 exhausted the memory."""

MAX_BATCH = 1_000_000
"""Most targets of one ``bench throughput`` size (``--sizes``, and ``--loop-max``, the largest
size also timed as Python loops): 10 times its largest default size (100,000).  One
``solve_batch`` call holds its targets and answers (a few hundred bytes per target), the loops
one :class:`~swarm_ik.Result` per target: at most about a GB, where 10**11 exhausted the
memory."""

MAX_MANY_N = 256
"""Largest ``n`` of ``bench many`` (``--n``, solutions asked of ``solve_many`` per target;
default 16): the size of the reference pool (``solve_many(n=256)``) that the spread of the
panda's solutions is measured against, so a larger ``n`` measures nothing more; a redundant
arm pools ``4 · n`` solutions per target, and 10**9 ran on without end."""

MAX_RUNS = 500
"""Most runs per case and solver of ``bench paper --runs``: 10 times the papers' largest
(50).  Each unit of ``--runs`` makes 820 runs of the full configuration, their specifications
listed up front (about 0.65 MB per unit): at most about 0.3 GB, where 10**11 grew the memory
without end before the first run."""

MAX_REPEAT = 100
"""Most timed repeats of each ``bench throughput`` measurement (``--repeat``, default 3; the
fastest is kept, the results being identical run to run): bounds the run time, not memory."""

MAX_BOXES = 10_000
"""Most random boxes of a ``bench throughput --boxes K`` scene: far beyond the scenes of the
tests and docs (45 to 200 boxes); the boxes are drawn one by one into a list, so 10**12 of them
would exhaust the memory."""

MAX_JOBS = 256
"""Most worker processes of ``bench paper`` and ``bench ik`` (``--jobs``): more than the CPUs
of the largest single machines; each is a spawned interpreter with its own compiled kernels
(about 100 MB or more), and the pool starts up to one per queued run."""

_CAPPED = {
    "MAX_TARGETS": (
        "ik --n", "goals --n", "many --n-targets", "collision --n", "collision --batch-n",
        "collision --diagnose", "collision --ablation-n", "wholebody --n", "wholebody --chunk",
        "path --n",
    ),
    "MAX_WAYPOINTS": ("path --waypoints",),
    "MAX_BATCH": ("throughput --sizes", "throughput --loop-max"),
    "MAX_MANY_N": ("many --n",),
    "MAX_RUNS": ("paper --runs",),
    "MAX_REPEAT": ("throughput --repeat",),
    "MAX_BOXES": ("throughput --boxes",),
    "MAX_JOBS": ("paper --jobs", "ik --jobs"),
}  # fmt: skip
"""Each cap's name -> the ``"benchmark --option"`` it bounds."""

_ZERO_ALLOWED = ("throughput --loop-max", "collision --diagnose")
"""The capped options whose lowest value is 0 (the others': 1)."""

MAX_WAYPOINTS = 10_000
"""Most waypoints per path of ``python -m swarm_ik.bench.path`` (``--waypoints``, default
40): each path is planned whole, its candidate graph growing with the waypoints."""

SIZE_OPTIONS: dict[str, tuple[tuple[str, int, int, str], ...]] = {
    bench: tuple(
        (option, 0 if f"{bench} {option}" in _ZERO_ALLOWED else 1, globals()[cap], cap)
        for cap, where in _CAPPED.items()
        for b, option in (w.split() for w in where)
        if b == bench
    )
    for bench in ("paper", "ik", "throughput", "goals", "many", "collision", "wholebody", "path")
}
"""Benchmark name -> its size and count options: ``(option, lowest, cap, cap's name)``; each
option holds an integer, a list of them (``--sizes``, ``--boxes``) or None (not given)."""


def check_sizes(name: str, args: argparse.Namespace) -> None:
    """Refuse a size or count option of the benchmark ``name`` above its cap
    (:data:`SIZE_OPTIONS`), before any work.

    Args:
        name: The benchmark (a key of :data:`BENCHMARKS`).
        args: Its parsed options.

    Raises:
        InvalidArgumentError: ``"--n must be a count from 1 to 100000
            (swarm_ik.bench.sizes.MAX_TARGETS), got 1000000000000"``: the first value out of
            range.
    """
    for option, lowest, cap, cap_name in SIZE_OPTIONS.get(name, ()):
        value = getattr(args, option[2:].replace("-", "_"), None)
        values = value if isinstance(value, (list, tuple)) else [] if value is None else [value]
        for v in values:
            if not lowest <= int(v) <= cap:
                raise InvalidArgumentError(
                    f"{option} must be a count from {lowest} to {cap} "
                    f"(swarm_ik.bench.sizes.{cap_name}), got {v}"
                )
