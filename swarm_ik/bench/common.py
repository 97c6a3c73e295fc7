"""Shared helpers of the benchmarks (each exists once, here).

* robots: :func:`cached_robot` (a per-process cache of :func:`swarm_ik.load_robot`);
* targets: :func:`fk_targets` (FK of joint vectors drawn uniformly within the limits),
  :func:`collision_free_targets` (those of them free of contact);
* files: :func:`read_csv` (rows as strings), :func:`add_out` and :func:`resolve_out` (the
  ``--out`` / ``--quick`` rules), :func:`write_run_info`, :func:`render` (reports from
  template files in ``swarm_ik/bench/templates``);
* the machine: :func:`machine_info`, :func:`cpu_count`, :func:`single_thread`;
* statistics: :func:`summarize`, :func:`timing`, :func:`success_rate`, :func:`judge`;
* C-library plumbing for peers: :func:`quiet_c_output`, :func:`urdf_root_link`;
* the command line: :func:`module_main` (the ``main(argv)`` of ``python -m swarm_ik.bench.NAME``),
  :func:`positive_int` (an option checked before any work; numbers:
  :func:`swarm_ik._validate.positive_float`).
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import functools
import json
import math
import os
import platform
import signal
import string
import sys
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from swarm_ik.bench.sizes import check_sizes
from swarm_ik.errors import InvalidArgumentError, SwarmIKError
from swarm_ik.kernels import counted_sigint, cut_by_ctrl_c

THREAD_VARIABLES = (
    "OMP_NUM_THREADS",
    "MKL_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "NUMBA_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
)
"""Environment variables set to 1 by :func:`single_thread`."""

TEMPLATES = Path(__file__).with_name("templates")
"""Folder of the report templates."""

RUN_INFO = "run.json"
"""File recording what kind of run (full or quick) wrote an output folder."""


# --------------------------------------------------------------------------- command line
class ModuleMain(Protocol):
    """A benchmark module's ``main``: parses ``argv`` (default ``sys.argv[1:]``), runs, and
    returns the exit status."""

    def __call__(self, argv: Sequence[str] | None = None) -> int: ...


def module_main(
    add_arguments: Callable[[argparse.ArgumentParser], None],
    run: Callable[[argparse.Namespace], int],
    name: str,
    description: str | None = None,
) -> ModuleMain:
    """The ``main(argv=None) -> int`` of the benchmark module ``swarm_ik.bench.NAME``, run as
    ``python -m swarm_ik.bench.NAME``: a parser with the module's options, the same as
    ``swarm-ik bench NAME``'s (``add_arguments``), then ``run`` on the parsed options (their
    sizes checked first: :func:`swarm_ik.bench.sizes.check_sizes`); bad input is one line on
    stderr and exit 2."""

    def main(argv: Sequence[str] | None = None) -> int:
        if argv is None:  # (run as a module: this process's own, a Ctrl-C counted so that
            # one a kernel lost is raised again, as in the console script)
            signal.signal(signal.SIGINT, counted_sigint)
        parser = argparse.ArgumentParser(
            prog=f"python -m swarm_ik.bench.{name}", description=description
        )
        add_arguments(parser)
        args = parser.parse_args(argv)
        try:
            check_sizes(name, args)  # sizes above their caps refused, as by `swarm-ik bench`
            return run(args)
        except SwarmIKError as exc:  # bad input: one line and exit 2, as `swarm-ik bench`
            print(f"{parser.prog}: error: {exc}", file=sys.stderr)
            return 2
        except (KeyboardInterrupt, Exception) as exc:  # Ctrl-C: one line and 130, as
            # `swarm-ik bench` (also when it cut a compiled call short: a SystemError)
            if not cut_by_ctrl_c(exc):
                raise
            print(f"{parser.prog}: interrupted", file=sys.stderr)
            return 130

    main.__doc__ = f"``python -m swarm_ik.bench.{name} [options]``."
    return main


def positive_int(value: Any, option: str) -> int:
    """An option's value as an integer of at least 1.

    Raises:
        InvalidArgumentError: ``"{option} must be a positive integer, got {value}"``.
    """
    n = int(value)
    if n < 1:
        raise InvalidArgumentError(f"{option} must be a positive integer, got {value}")
    return n


# --------------------------------------------------------------------------- robots, targets
@functools.lru_cache(maxsize=16)
def cached_robot(name: str) -> Any:
    """``swarm_ik.load_robot(name)``, cached per process."""
    import swarm_ik

    return swarm_ik.load_robot(name)


def check_robots(names: Sequence[str]) -> None:
    """Load each robot of ``names`` (:func:`cached_robot`) before a benchmark writes anything,
    so that a bad name is refused with the loader's message and leaves no folder behind.

    Raises:
        SwarmIKError: the loader's error for the first name it refuses.
    """
    for name in names:
        cached_robot(name)


def fk_targets(robot: Any, n: int, seed: int | Sequence[int]) -> np.ndarray:
    """Reachable targets: FK of ``n`` joint vectors drawn uniformly within the limits.

    Args:
        robot: A :class:`~swarm_ik.RobotModel`.
        n: Number of targets.
        seed: Seed of ``numpy.random.default_rng`` (the first ``k`` targets do not depend
            on ``n``).

    Returns:
        Poses, shape ``(n, 4, 4)`` [m].
    """
    rng = np.random.default_rng(seed)
    q = np.atleast_2d(robot.random_q(rng, max(int(n), 1)))[: int(n)]
    return np.asarray(robot.fk(q), dtype=float).reshape(int(n), 4, 4)


def collision_free_targets(
    robot: Any,
    scene: Any,
    n: int,
    rng: np.random.Generator,
    *,
    batch: int,
    max_draws: int,
    where: str,
    what: str,
    keep: Callable[[np.ndarray], np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Reachable collision-free targets: FK of the first ``n`` joint vectors drawn uniformly
    within the limits, ``batch`` per round, that the exact check finds free of contact (self
    and ``scene``).

    Args:
        robot: A :class:`~swarm_ik.RobotModel`.
        scene: The obstacles (a :class:`~swarm_ik.Scene`).
        n: Number of targets.
        rng: Random generator.
        batch: Joint vectors drawn per round.
        max_draws: Most joint vectors drawn before giving up.
        where: What the error names first (the robot, and the scene).
        what: What the error counts (``"targets"``, ``"joint vectors"``).
        keep: Optional filter of each round's draws, before the contact check: the rows of
            its ``(batch, nq)`` argument worth checking.

    Returns:
        ``(q (n, nq), targets (n, 4, 4))``.

    Raises:
        InvalidArgumentError: fewer than ``n`` found within ``max_draws`` draws (``"{where}:
            only {k} collision-free {what} in {drawn} draws"``).
    """
    rc = robot.collision_model()
    found: list[np.ndarray] = []
    drawn = 0
    while len(found) < n:
        if drawn >= max_draws:
            raise InvalidArgumentError(
                f"{where}: only {len(found)} collision-free {what} in {drawn} draws"
            )
        q = robot.random_q(rng, batch)
        drawn += batch
        if keep is not None:
            q = keep(q)
        for qi in q:
            if not rc.collides(qi, scene):
                found.append(qi)
                if len(found) == n:
                    break
    qs = np.array(found).reshape(n, robot.nq)
    return qs, np.asarray(robot.fk(qs), dtype=float).reshape(n, 4, 4)


# --------------------------------------------------------------------------- files
def read_csv(path: Path) -> list[dict[str, str]]:
    """Rows of a CSV file as dicts of strings (``[]`` when the file does not exist)."""
    path = Path(path)
    if not path.exists():
        return []
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def write_csv(path: Path, fields: Sequence[str], rows: Iterable[Mapping[str, Any]]) -> Path:
    """Write ``rows`` (dicts by ``fields``) to ``path`` with a header; returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(fields), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    return path


def default_out(command: str, quick: bool) -> Path:
    """Default output folder of ``swarm-ik bench COMMAND``: ``./bench-COMMAND`` in the current
    folder (``./bench-COMMAND-quick`` with ``--quick``), never the package's ``docs/``."""
    return Path(f"bench-{command}" + ("-quick" if quick else ""))


def add_out(parser: argparse.ArgumentParser, command: str, **kwargs: Any) -> None:
    """``--out FOLDER`` of ``swarm-ik bench COMMAND``, default ``None`` (:func:`resolve_out`
    then picks :func:`default_out`); ``kwargs`` go to ``add_argument`` (e.g. ``type=Path``)."""
    full, quick = default_out(command, False), default_out(command, True)
    parser.add_argument(
        "--out",
        default=None,
        help=f"output folder (default ./{full}, or ./{quick} with --quick)",
        **kwargs,
    )


def resolve_out(out: str | os.PathLike[str] | None, command: str, quick: bool) -> Path:
    """The output folder of a benchmark invocation, checked against what is already there.

    ``--quick`` never overwrites a full run: a folder whose :data:`RUN_INFO` says it holds a
    full run is refused for a quick one (and a quick folder for a full run, so that a full
    report never mixes in quick rows).

    Args:
        out: ``--out`` as given (``None``: :func:`default_out`).
        command: Benchmark name (``ik``, ``paper``, ``throughput``).
        quick: Whether this is a ``--quick`` run.

    Returns:
        The folder (not created).

    Raises:
        InvalidArgumentError: the path is a file, or the folder holds another command's run
            or the other kind (quick or full) of this command's.
    """
    path = default_out(command, quick) if out is None else Path(out)
    if path.exists() and not path.is_dir():
        raise InvalidArgumentError(f"--out {str(path)!r} is a file; give a folder")
    info = path / RUN_INFO
    if info.exists():
        try:
            prev = json.loads(info.read_text())
        except json.JSONDecodeError:
            prev = {}
        was = prev.get("command")
        if isinstance(was, str) and was != command:  # (its summary and plan replaced by
            # another command's: a `bench goals` run into a `bench ik` folder, silently)
            raise InvalidArgumentError(
                f"--out {str(path)!r} holds a run of `bench {was}`; `bench {command}` may not "
                "write there: choose another --out"
            )
        was_quick = bool(prev.get("quick", False))
        if was_quick != quick:
            kind, other = ("quick", "full") if quick else ("full", "quick")
            raise InvalidArgumentError(
                f"--out {str(path)!r} holds a {other} run of `bench {prev.get('command', '?')}`;"
                f" a {kind} run may not write there: choose another --out"
            )
    return path


def require_results(out: Path, files: Sequence[Path], command: str, quick: bool = False) -> None:
    """For ``--report-only``: refuse a folder where none of the CSV ``files`` holds a row (a
    report of nothing, written over an empty folder, would look like a run).

    Args:
        out: The output folder.
        files: The CSV files a report is built from.
        command: The benchmark (``swarm-ik bench COMMAND`` makes the results).
        quick: Whether this is a ``--quick`` invocation (the command named says so too).

    Raises:
        InvalidArgumentError: naming the folder and the command that makes the results.
    """
    for path in files:
        if path.is_file():
            with path.open() as fh:
                if fh.readline() and fh.readline().strip():  # (a header and one row)
                    return
    raise InvalidArgumentError(
        f"--report-only: no results to report in {str(out)!r} (no rows in "
        f"{', '.join(f.name for f in files)}); run `swarm-ik bench {command}"
        f"{' --quick' if quick else ''} --out {out}` first"
    )


def write_run_info(out: Path, command: str, quick: bool, **extra: Any) -> Path:
    """Record in ``out/run.json`` which benchmark wrote the folder and whether ``--quick``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    p = out / RUN_INFO
    rec = {"command": command, "quick": bool(quick), **extra}
    p.write_text(json.dumps(rec, indent=1, sort_keys=True) + "\n")
    return p


def write_report(path: Path, text: str) -> int:
    """Write a benchmark's Markdown report to ``path``, print it, and return exit code 0."""
    Path(path).write_text(text)
    print(text)
    return 0


def load_line() -> str:
    """The machine's cores and load averages, for a report's machine line."""
    la = os.getloadavg()
    return f"{cpu_count()} cores, load average {la[0]:.1f} / {la[1]:.1f} / {la[2]:.1f} at the end"


def render(template: str, **values: Any) -> str:
    """A report from a template file of :data:`TEMPLATES` (``string.Template`` syntax,
    ``$name`` / ``${name}``); every placeholder must be given.

    Raises:
        InvalidArgumentError: a placeholder has no value.
    """
    text = (TEMPLATES / template).read_text()
    try:
        return string.Template(text).substitute({k: str(v) for k, v in values.items()})
    except KeyError as exc:
        raise InvalidArgumentError(f"template {template}: no value for {exc}") from None


# --------------------------------------------------------------------------- machine
def cpu_count() -> int:
    """CPUs available to this process."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:  # pragma: no cover - not Linux
        pass
    return platform.processor() or platform.machine()


def package_version(name: str) -> str:
    """Installed version of distribution ``name``, or ``"not installed"``."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(name)
    except PackageNotFoundError:
        return "not installed"


def machine_info(packages: Sequence[str] = ()) -> dict[str, str]:
    """CPU, cores, Python and the versions of numpy, numba, Pinocchio, swarm_ik and
    ``packages`` (distribution names), for reports."""
    info = {
        "CPU": _cpu_name(),
        "cores": str(cpu_count()),
        "Python": platform.python_version(),
        "platform": platform.platform(),
    }
    for dist in ("numpy", "numba", "pin", "swarm_ik", *packages):
        info[dist] = package_version(dist)
    return info


def single_thread() -> None:
    """Ask every numeric library for one thread (OpenMP, MKL, OpenBLAS, numba) in this process
    and in the processes it starts: the environment variables of :data:`THREAD_VARIABLES`,
    and ``threadpoolctl`` for the libraries already loaded when it is installed."""
    for var in THREAD_VARIABLES:
        os.environ[var] = "1"
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:
        return
    threadpool_limits(1)


@contextlib.contextmanager
def quiet_c_output() -> Iterator[None]:
    """Silence C-level stdout and stderr (e.g. KDL's URDF parser warning about inertias)."""
    fds = []
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
            fds.append(stream.fileno())
        except (AttributeError, OSError, ValueError):
            continue
    saved = [os.dup(fd) for fd in fds]
    with open(os.devnull, "w") as devnull:
        for fd in fds:
            os.dup2(devnull.fileno(), fd)
        try:
            yield
        finally:
            for fd, keep in zip(fds, saved, strict=True):
                os.dup2(keep, fd)
                os.close(keep)


def urdf_root_link(path: Path) -> str:
    """Name of the root link of a URDF file (the link that is no joint's child)."""
    root = ET.parse(path).getroot()
    links = [link.get("name") for link in root.findall("link")]
    children = {j.find("child").get("link") for j in root.findall("joint")}  # type: ignore[union-attr]
    roots = [name for name in links if name not in children]
    return str(roots[0])


def urdf_link_of_frame(path: Path, frame: str) -> str:
    """The URDF link a Pinocchio frame name stands for: the link itself, or the child link of
    the (fixed) joint of that name."""
    root = ET.parse(path).getroot()
    if any(link.get("name") == frame for link in root.findall("link")):
        return frame
    for j in root.findall("joint"):
        if j.get("name") == frame:
            return str(j.find("child").get("link"))  # type: ignore[union-attr]
    raise InvalidArgumentError(f"{path}: no link or joint named {frame!r}")


# --------------------------------------------------------------------------- statistics
@dataclass(frozen=True)
class Stats:
    """Summary of a sample of final values (fitness, errors, …).

    ``std`` and ``var`` are the **population** statistics (``ddof = 0``): the papers do not
    say which they use.

    Attributes:
        n: Sample size.
        best: Minimum.
        mean: Mean.
        worst: Maximum.
        std: Standard deviation, ``ddof = 0``.
        var: Variance, ``ddof = 0``.
        median: Median.
    """

    n: int
    best: float
    mean: float
    worst: float
    std: float
    var: float
    median: float

    def get(self, name: str) -> float:
        """A statistic by name (``best``, ``mean``, ``worst``, ``std``, ``var``, ``median``)."""
        if name not in ("best", "mean", "worst", "std", "var", "median"):
            raise InvalidArgumentError(
                f"unknown statistic {name!r}; valid: best, mean, median, std, var, worst"
            )
        return float(getattr(self, name))


def summarize(values: Iterable[float]) -> Stats:
    """Best / mean / worst / std (ddof 0) / variance / median of a sample.

    Raises:
        InvalidArgumentError: the sample is empty.
    """
    v = np.asarray(list(values), dtype=float)
    if v.size == 0:
        raise InvalidArgumentError("cannot summarize an empty sample")
    return Stats(
        n=int(v.size),
        best=float(v.min()),
        mean=float(v.mean()),
        worst=float(v.max()),
        std=float(v.std(ddof=0)),
        var=float(v.var(ddof=0)),
        median=float(np.median(v)),
    )


def success_rate(flags: Iterable[bool]) -> float:
    """Fraction of True values (NaN for an empty sample)."""
    f = [bool(x) for x in flags]
    return float(np.mean(f)) if f else math.nan


VERDICT_FACTOR = 10.0
"""Ratio beyond which ours counts as better / worse than the published value (one order of
magnitude, in the distance to the known minimum)."""

REPRODUCED_FACTOR = 2.0
"""Ratio within which ours counts as *reproduced*; between it and :data:`VERDICT_FACTOR` the
verdict is *same order* (of magnitude), with the ratio: a mean 5× the paper's is not called
reproduced."""


@dataclass(frozen=True)
class Verdict:
    """Our value against a published one.

    Attributes:
        label: ``"reproduced"``, ``"same order"``, ``"better"`` or ``"worse"``.
        ratio: ``max(ours − f_min, floor) / max(published − f_min, floor)``.
        text: One line for the report (with the reason when worse).
        reason: The reason given when worse (``None`` otherwise).
    """

    label: str
    ratio: float
    text: str
    reason: str | None = None


def judge(
    ours: float,
    published: float,
    *,
    f_min: float = 0.0,
    floor: float = 0.0,
    why_worse: str | None = None,
    factor: float = VERDICT_FACTOR,
) -> Verdict:
    """Compare our statistic with the published one, in distance to the known minimum.

    Rule: ``a = max(ours − f_min, floor)``, ``b = max(published − f_min, floor)``; ``a/b <
    1/factor`` → *better*, ``a/b > factor`` → *worse*, within :data:`REPRODUCED_FACTOR`
    either way → *reproduced*, otherwise *same order* (of magnitude, the ratio given).
    ``floor`` is the level below which values are not distinguished: numerical
    exactness for IK fitness, or the resolution of a published number printed with few
    decimals.  A ``floor`` of 0 uses the smallest positive double.

    Args:
        ours: Our value.
        published: The paper's value.
        f_min: Known minimum of the quantity (0 for IK fitness).
        floor: Values closer to ``f_min`` than this are treated as equal to it.
        why_worse: The reason shown when the verdict is *worse* (``None``: "cause not
            identified").
        factor: Ratio threshold (default one order of magnitude).

    Returns:
        The verdict.
    """
    fl = max(floor, np.finfo(float).tiny)
    a = max(ours - f_min, fl)
    b = max(published - f_min, fl)
    ratio = a / b
    if ratio < 1.0 / factor:
        return Verdict("better", ratio, f"better (×{1 / ratio:.2g} closer to the optimum)")
    if ratio > factor:
        reason = why_worse or "cause not identified"
        return Verdict("worse", ratio, f"worse (×{ratio:.2g}): {reason}", reason)
    if 1.0 / REPRODUCED_FACTOR <= ratio <= REPRODUCED_FACTOR:
        return Verdict("reproduced", ratio, f"reproduced (ratio {ratio:.3g})")
    return Verdict("same order", ratio, f"same order (ratio {ratio:.3g})")


def group_rows(
    rows: Iterable[Mapping[str, Any]], *keys: str
) -> dict[tuple[Any, ...], list[Mapping[str, Any]]]:
    """Rows grouped by the values of ``keys`` (insertion order kept)."""
    groups: dict[tuple[Any, ...], list[Mapping[str, Any]]] = {}
    for r in rows:
        groups.setdefault(tuple(r[k] for k in keys), []).append(r)
    return groups


@dataclass(frozen=True)
class Timing:
    """Order statistics of a sample of times [s].

    Attributes:
        n: Sample size.
        median: Median.
        p95: 95th percentile.
        p99: 99th percentile.
        max: Maximum.
    """

    n: int
    median: float
    p95: float
    p99: float
    max: float


def timing(values: Iterable[float]) -> Timing:
    """Median, p95, p99 and max of a sample (NaN everywhere for an empty one)."""
    v = np.asarray([x for x in values if np.isfinite(x)], dtype=float)
    if v.size == 0:
        return Timing(0, math.nan, math.nan, math.nan, math.nan)
    p50, p95, p99 = np.percentile(v, [50, 95, 99])
    return Timing(int(v.size), float(p50), float(p95), float(p99), float(v.max()))
