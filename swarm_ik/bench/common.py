"""Benchmark plumbing: the CSV schema, a resumable parallel runner, and the statistics.

A benchmark is a list of :class:`RunSpec` (one independent, seeded run each).  :func:`execute`
runs the ones whose :attr:`RunSpec.key` is not yet in the experiment's CSV, over a process pool
(``jobs``) or on Dask workers (``client``, through :func:`swarm_ik.distributed.map_chunks`, in
batches of a few runs per worker), and **appends one row per finished run and flushes it at
once** (on Dask: the rows of each batch as the batch comes back), so an interrupted benchmark
(Ctrl-C, a killed process) loses only the runs in flight; running it again skips the rows
already there.  Each run's best-fitness-per-iteration history goes to a JSON-lines file
beside the CSV (written *before* its CSV row, so every row has its history); plots read these
files, never rerun anything.

CSV schema (:data:`RUN_FIELDS`), one row per run:

==================  ===========================================================================
``key``             unique run key (experiment, case, target, solver, settings, seed)
``experiment``      experiment id, e.g. ``000-table2``
``robot``           robot name; for the benchmark-function experiment the function key (``F1``)
``target_id``       target within the experiment (``printed``, ``pose3``, ``x*`` …)
``solver``          registry name
``seed``            the run's seed
``fitness_name``    ``paper-l1``, ``euler-zyz``, ``se3`` or ``function``
``pop_size``        population size passed to the solver (empty: solver default / none)
``iterations``      iterations passed to the solver (empty: solver default)
``max_evals``       evaluation budget passed (empty: the solver's own schedule ends the run)
``fitness``         best fitness found (the problem's fitness, or the function value)
``position_error``  ‖Δp‖ [m] by Pinocchio's FK (empty for benchmark functions)
``rotation_error``  geodesic rotation error [rad] (empty for benchmark functions)
``n_evals``         evaluations spent
``time_s``          wall-clock seconds of the solve (depends on machine load and ``--jobs``)
``success``         errors within ``tol_pos``/``tol_rot`` and within limits (IK); for functions
                    ``fitness − f_min ≤ 1e-8``
``within_limits``   answer within the joint limits (functions: always within the box)
==================  ===========================================================================

Everything except ``time_s`` is a deterministic function of the run's key: results do not
depend on ``jobs`` or on the order in which runs finish.
"""

from __future__ import annotations

import csv
import functools
import io
import json
import math
import multiprocessing
import os
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swarm_ik.errors import InvalidArgumentError

RUN_FIELDS = (
    "key",
    "experiment",
    "robot",
    "target_id",
    "solver",
    "seed",
    "fitness_name",
    "pop_size",
    "iterations",
    "max_evals",
    "fitness",
    "position_error",
    "rotation_error",
    "n_evals",
    "time_s",
    "success",
    "within_limits",
)
"""Columns of every experiment CSV, in order."""

_INT_FIELDS = frozenset({"seed", "pop_size", "iterations", "max_evals", "n_evals"})
_FLOAT_FIELDS = frozenset({"fitness", "position_error", "rotation_error", "time_s"})
_BOOL_FIELDS = frozenset({"success", "within_limits"})

HISTORY_POINTS = 120
"""Most points kept of a run's history (evenly spaced over the iterations, last included)."""

DASK_BATCH_PER_WORKER = 8
"""Runs per Dask worker submitted at a time by :func:`execute` (rows are written per batch)."""

FUNCTION_SUCCESS_GAP = 1e-8
"""A benchmark-function run counts as a success when ``f − f_min`` is at most this."""


# --------------------------------------------------------------------------- run spec
@dataclass(frozen=True)
class RunSpec:
    """One independent run: everything needed to repeat it bit for bit.

    Attributes:
        experiment: Experiment id (e.g. ``"000-table2"``).
        robot: Robot name (bundled or example-robot-data), or a benchmark-function key of
            :data:`swarm_ik.testfunctions.FUNCTIONS` when ``fitness_name == "function"``.
        target_id: Name of the target within the experiment.
        solver: Solver registry name.
        seed: Seed of the run.
        fitness_name: IK fitness name, or ``"function"`` for a benchmark function.
        target: Target pose as 16 numbers (row-major 4x4, metres); ``None`` for functions.
        pop_size: ``pop_size`` passed to the solver (``None``: not passed).
        iterations: ``iterations`` passed to the solver (``None``: not passed).
        max_evals: Evaluation budget (``None``: the solver's own schedule).
        stop_on_success: Stop at the tolerance (``False``: run the whole budget, as the
            papers do).
        tol_pos: Position tolerance for ``success`` [m].
        tol_rot: Rotation tolerance for ``success`` [rad].
        orth_tol: Orthonormality tolerance of the target (the printed paper-000 target needs
            ``1e-4``).
        keep_history: Whether to store the history for convergence plots.
    """

    experiment: str
    robot: str
    target_id: str
    solver: str
    seed: int
    fitness_name: str
    target: tuple[float, ...] | None = None
    pop_size: int | None = None
    iterations: int | None = None
    max_evals: int | None = None
    stop_on_success: bool = False
    tol_pos: float = 1e-5
    tol_rot: float = 1e-5
    orth_tol: float = 1e-6
    keep_history: bool = True

    @property
    def key(self) -> str:
        """Unique key of the run within an output folder (settings included, so runs made
        with other settings are never mistaken for this one)."""
        parts = [
            self.experiment,
            self.robot,
            self.target_id,
            self.solver,
            self.fitness_name,
            f"pop={_blank(self.pop_size)}",
            f"it={_blank(self.iterations)}",
            f"budget={_blank(self.max_evals)}",
            f"stop={int(self.stop_on_success)}",
            f"seed={self.seed}",
        ]
        return "|".join(parts)

    def solver_params(self) -> dict[str, Any]:
        """Keyword arguments for the solver (only those given)."""
        params: dict[str, Any] = {}
        if self.pop_size is not None:
            params["pop_size"] = self.pop_size
        if self.iterations is not None:
            params["iterations"] = self.iterations
        return params


def _blank(v: Any) -> str:
    return "" if v is None else str(v)


@dataclass(frozen=True)
class RunOutcome:
    """What a worker sends back: the CSV row and the compact history.

    Attributes:
        row: Values by :data:`RUN_FIELDS` name.
        history: Compact history (see :func:`compact_history`), or ``None`` when not kept.
    """

    row: Mapping[str, Any]
    history: Mapping[str, Any] | None


# --------------------------------------------------------------------------- one run
@functools.lru_cache(maxsize=8)
def _robot(name: str) -> Any:
    import swarm_ik

    return swarm_ik.load_robot(name)


def run_one(spec: RunSpec) -> RunOutcome:
    """Run one spec (in a worker process or inline).

    Args:
        spec: The run.

    Returns:
        Its CSV row and compact history.
    """
    import swarm_ik

    if spec.fitness_name == "function":
        from swarm_ik.testfunctions import get_function

        fn = get_function(spec.robot)
        lo, hi = fn.bounds
        res = swarm_ik.minimize(
            fn.function,
            lo,
            hi,
            spec.solver,
            seed=spec.seed,
            max_evals=spec.max_evals,
            **spec.solver_params(),
        )
        fit, hist, n_evals, t = float(res.fun), res.history, res.n_evals, res.time_s
        pos = rot = math.nan
        success = fit - fn.f_min <= FUNCTION_SUCCESS_GAP
        within = bool(np.all(res.x >= lo) and np.all(res.x <= hi))
    else:
        if spec.target is None:
            raise InvalidArgumentError(f"run {spec.key!r}: an IK run needs a target")
        robot = _robot(spec.robot)
        target = np.asarray(spec.target, dtype=float).reshape(4, 4)
        problem = swarm_ik.IKProblem(robot, target, spec.fitness_name, orth_tol=spec.orth_tol)
        r = swarm_ik.solve(
            problem,
            spec.solver,
            seed=spec.seed,
            max_evals=spec.max_evals,
            tol_pos=spec.tol_pos,
            tol_rot=spec.tol_rot,
            stop_on_success=spec.stop_on_success,
            **spec.solver_params(),
        )
        fit, hist, n_evals, t = r.fitness, r.history, r.n_evals, r.time_s
        pos, rot, success, within = r.position_error, r.rotation_error, r.success, r.within_limits
    row = {
        "key": spec.key,
        "experiment": spec.experiment,
        "robot": spec.robot,
        "target_id": spec.target_id,
        "solver": spec.solver,
        "seed": spec.seed,
        "fitness_name": spec.fitness_name,
        "pop_size": spec.pop_size,
        "iterations": spec.iterations,
        "max_evals": spec.max_evals,
        "fitness": float(fit),
        "position_error": float(pos),
        "rotation_error": float(rot),
        "n_evals": int(n_evals),
        "time_s": float(t),
        "success": bool(success),
        "within_limits": bool(within),
    }
    history = compact_history(hist, int(n_evals)) if spec.keep_history else None
    return RunOutcome(row, history)


def warm_up() -> None:
    """Compile the numba kernels once (FK, the ``swarm`` polish) so that no run's ``time_s``
    includes compilation; called once per worker process.  Failures are ignored (the runs
    then simply pay the compilation themselves)."""
    try:
        import swarm_ik

        robot = _robot("yumi_left")
        problem = swarm_ik.IKProblem.from_q(robot, robot.mid_q())
        for solver in ("swarm", "dls"):
            if solver in swarm_ik.solvers.names():
                swarm_ik.solve(problem, solver, seed=0, max_evals=50)
    except Exception:  # noqa: BLE001 - warming up is an optimisation only
        pass


def compact_history(
    history: Sequence[float] | np.ndarray, n_evals: int, max_points: int = HISTORY_POINTS
) -> dict[str, Any]:
    """A run's best-fitness history, thinned for storage.

    Args:
        history: Best fitness after each iteration, shape ``(iterations,)``.
        n_evals: Evaluations the run spent (to place iterations on an evaluation axis).
        max_points: Most points kept (evenly spaced iterations, the last one always kept).

    Returns:
        ``{"n_iter": L, "n_evals": N, "it": [iteration indices], "f": [values]}``; values
        rounded to 5 significant digits, non-finite ones as ``None``.
    """
    h = np.asarray(history, dtype=float)
    n = int(h.shape[0])
    idx: list[int] = (
        np.unique(np.round(np.linspace(0, n - 1, min(n, max_points))).astype(int)).tolist()
        if n
        else []
    )
    vals = [float(f"{h[i]:.5g}") if np.isfinite(h[i]) else None for i in idx]
    return {"n_iter": n, "n_evals": int(n_evals), "it": [int(i) for i in idx], "f": vals}


# --------------------------------------------------------------------------- files
def csv_path(out: Path, experiment: str) -> Path:
    """The CSV file of an experiment in folder ``out``."""
    return Path(out) / f"{experiment}.csv"


def history_path(out: Path, experiment: str) -> Path:
    """The JSON-lines history file of an experiment in folder ``out``."""
    return Path(out) / f"{experiment}.history.jsonl"


def _repair_tail(path: Path) -> None:
    """Drop a partial last line (a run killed while writing) so appends start on a fresh line."""
    if not path.exists() or path.stat().st_size == 0:
        return
    with open(path, "rb+") as fh:
        data = fh.read()
        if data.endswith(b"\n"):
            return
        cut = data.rfind(b"\n") + 1
        fh.seek(cut)
        fh.truncate()


def _format(name: str, v: Any) -> str:
    if v is None:
        return ""
    if name in _BOOL_FIELDS:
        return "true" if v else "false"
    if name in _FLOAT_FIELDS:
        return "" if math.isnan(v) else repr(float(v))
    return str(v)


def _parse(name: str, text: str) -> Any:
    if name in _INT_FIELDS:
        return None if text == "" else int(text)
    if name in _FLOAT_FIELDS:
        return math.nan if text == "" else float(text)
    if name in _BOOL_FIELDS:
        if text not in ("true", "false"):
            raise InvalidArgumentError(f"column {name!r}: expected true/false, got {text!r}")
        return text == "true"
    return text


def read_rows(path: Path) -> list[dict[str, Any]]:
    """Rows of an experiment CSV, typed (ints, floats, bools; empty → ``None``/NaN).

    A partial last line (from a killed run) is ignored.  When a key appears twice, the last
    row wins.

    Raises:
        InvalidArgumentError: the header is not :data:`RUN_FIELDS`.
    """
    path = Path(path)
    if not path.exists():
        return []
    text = path.read_text()
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]
    reader = csv.reader(io.StringIO(text))
    header = next(reader, None)
    if header is None:
        return []
    if tuple(header) != RUN_FIELDS:
        raise InvalidArgumentError(
            f"{path}: unexpected CSV header {header}; expected {list(RUN_FIELDS)}"
        )
    by_key: dict[str, dict[str, Any]] = {}
    for rec in reader:
        if len(rec) != len(RUN_FIELDS):
            continue
        row = {name: _parse(name, v) for name, v in zip(RUN_FIELDS, rec, strict=True)}
        by_key[row["key"]] = row
    return list(by_key.values())


def read_histories(path: Path) -> dict[str, dict[str, Any]]:
    """Histories by run key from a JSON-lines file (partial or broken lines skipped)."""
    path = Path(path)
    out: dict[str, dict[str, Any]] = {}
    if not path.exists():
        return out
    for line in path.read_text().splitlines():
        try:
            rec = json.loads(line)
        except json.JSONDecodeError:
            continue
        if isinstance(rec, dict) and "key" in rec:
            out[rec["key"]] = rec
    return out


class _Writer:
    """Appends rows (and histories) to an experiment's files, flushing each at once."""

    def __init__(self, csv_file: Path, hist_file: Path) -> None:
        csv_file.parent.mkdir(parents=True, exist_ok=True)
        _repair_tail(csv_file)
        _repair_tail(hist_file)
        new = not csv_file.exists() or csv_file.stat().st_size == 0
        self._csv = open(csv_file, "a", newline="")  # noqa: SIM115 - closed in close()
        self._hist_file = hist_file
        self._hist: Any = None  # opened at the first history (none for some experiments)
        self._w = csv.writer(self._csv, lineterminator="\n")
        if new:
            self._w.writerow(RUN_FIELDS)
            self._csv.flush()

    def write(self, outcome: RunOutcome) -> None:
        if outcome.history is not None:  # history first: a row never lacks its history
            if self._hist is None:
                self._hist = open(self._hist_file, "a")  # noqa: SIM115
            rec = {"key": outcome.row["key"], **outcome.history}
            self._hist.write(json.dumps(rec, separators=(",", ":")) + "\n")
            self._hist.flush()
        self._w.writerow([_format(n, outcome.row[n]) for n in RUN_FIELDS])
        self._csv.flush()

    def close(self) -> None:
        self._csv.close()
        if self._hist is not None:
            self._hist.close()


# --------------------------------------------------------------------------- runner
@dataclass(frozen=True)
class ExecSummary:
    """What :func:`execute` did.

    Attributes:
        total: Runs asked for.
        skipped: Runs already in the CSV (resumed past).
        new: Runs finished and written now.
        interrupted: True when a KeyboardInterrupt stopped it (the finished rows are saved).
        wall_s: Wall-clock seconds of this call.
    """

    total: int
    skipped: int
    new: int
    interrupted: bool
    wall_s: float


def pending(specs: Iterable[RunSpec], out: Path) -> tuple[list[RunSpec], int]:
    """The specs whose key is not yet in their experiment's CSV, and how many were done."""
    specs = list(specs)
    done: dict[str, set[str]] = {}
    todo = []
    for s in specs:
        if s.experiment not in done:
            done[s.experiment] = {r["key"] for r in read_rows(csv_path(out, s.experiment))}
        if s.key not in done[s.experiment]:
            todo.append(s)
    return todo, len(specs) - len(todo)


def execute(
    specs: Sequence[RunSpec],
    out: Path,
    *,
    jobs: int = 1,
    progress: bool = True,
    desc: str = "runs",
    worker: Callable[[RunSpec], RunOutcome] = run_one,
    initializer: Callable[[], None] | None = warm_up,
    client: Any = None,
    batch_per_worker: int = DASK_BATCH_PER_WORKER,
) -> ExecSummary:
    """Run the specs not yet in the CSV files under ``out``, appending rows as they finish.

    Args:
        specs: The runs (any experiments; each goes to its experiment's CSV).
        out: Output folder.
        jobs: Worker processes (1: run inline in this process); ignored with ``client``.
        progress: Show a ``tqdm`` progress bar.
        desc: Label of the progress bar.
        worker: The function running one spec (must be picklable when ``jobs > 1`` or with
            ``client``).
        initializer: Called once in each worker process (inline: once before the first run;
            Dask: once per worker process, before its first run) when there are IK runs to
            do; ``None``: nothing.
        client: A ``distributed.Client``: run on its workers instead of the process pool, in
            batches of ``batch_per_worker`` runs per worker (one Dask task per run), the rows
            of a batch written when it completes.  ``None``: the process pool / inline.
        batch_per_worker: Runs per worker in one Dask batch (more: less idle time at the end
            of each batch; fewer: less lost on an interruption).

    Returns:
        A summary; on KeyboardInterrupt the rows finished so far are saved and
        ``interrupted`` is True (rerun to resume).

    Raises:
        InvalidArgumentError: ``jobs < 1``, ``batch_per_worker < 1`` or two specs share a key.
    """
    if jobs < 1:
        raise InvalidArgumentError(f"jobs must be >= 1, got {jobs}")
    if batch_per_worker < 1:
        raise InvalidArgumentError(f"batch_per_worker must be >= 1, got {batch_per_worker}")
    keys = [s.key for s in specs]
    if len(set(keys)) != len(keys):
        dup = sorted({k for k in keys if keys.count(k) > 1})[:3]
        raise InvalidArgumentError(f"duplicate run keys: {dup}")
    t0 = time.perf_counter()
    out = Path(out)
    todo, skipped = pending(specs, out)
    writers: dict[str, _Writer] = {}
    written = [0]

    def write(o: RunOutcome) -> None:
        exp = str(o.row["experiment"])
        if exp not in writers:
            writers[exp] = _Writer(csv_path(out, exp), history_path(out, exp))
        writers[exp].write(o)
        written[0] += 1
        bar.update(1)

    bar = _progress(len(specs), skipped, desc, progress)
    interrupted = False
    try:
        if not any(s.fitness_name != "function" for s in todo):
            initializer = None  # benchmark functions use no compiled kernel
        if client is not None:
            if todo:
                _execute_dask(todo, client, worker, write, initializer, batch_per_worker)
        elif jobs == 1 or len(todo) <= 1:
            if todo and initializer is not None:
                initializer()
            for s in todo:
                write(worker(s))
        else:
            _execute_pool(todo, jobs, worker, write, initializer)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        bar.close()
        for w in writers.values():
            w.close()
    return ExecSummary(len(specs), skipped, written[0], interrupted, time.perf_counter() - t0)


def _execute_pool(
    todo: Sequence[RunSpec],
    jobs: int,
    worker: Callable[[RunSpec], RunOutcome],
    write: Callable[[RunOutcome], None],
    initializer: Callable[[], None] | None,
) -> None:
    """Run ``todo`` over ``jobs`` spawned processes; writes each outcome as it arrives.

    At most ``2·jobs`` runs are queued at a time, so an interruption cancels the rest at once;
    runs that finish while shutting down after an interruption are still written.
    """
    ctx = multiprocessing.get_context("spawn")  # no fork: safe with numba/BLAS threads
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=initializer)
    futures: dict[Future[RunOutcome], RunSpec] = {}
    queue = iter(todo)
    try:
        for s in queue:
            futures[pool.submit(worker, s)] = s
            if len(futures) >= 2 * jobs:
                break
        while futures:
            done, _ = wait(futures, return_when=FIRST_COMPLETED)
            for fut in done:
                futures.pop(fut)
                write(fut.result())
                nxt = next(queue, None)
                if nxt is not None:
                    futures[pool.submit(worker, nxt)] = nxt
    except KeyboardInterrupt:
        pool.shutdown(wait=True, cancel_futures=True)
        for fut in futures:  # keep what finished meanwhile
            if fut.done() and not fut.cancelled() and fut.exception() is None:
                write(fut.result())
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


_INITIALIZED: set[Any] = set()
"""Initializers already called in this (Dask worker) process."""


def _initialized_run(
    worker: Callable[[RunSpec], RunOutcome], initializer: Callable[[], None] | None, spec: RunSpec
) -> RunOutcome:
    """``worker(spec)`` after calling ``initializer`` once in this process (Dask tasks)."""
    if initializer is not None and initializer not in _INITIALIZED:
        initializer()
        _INITIALIZED.add(initializer)
    return worker(spec)


def _execute_dask(
    todo: Sequence[RunSpec],
    client: Any,
    worker: Callable[[RunSpec], RunOutcome],
    write: Callable[[RunOutcome], None],
    initializer: Callable[[], None] | None,
    batch_per_worker: int,
) -> None:
    """Run ``todo`` on the Dask workers behind ``client`` with
    :func:`swarm_ik.distributed.map_chunks`, ``batch_per_worker × workers`` runs at a time (one
    task per run); writes each batch's outcomes (in spec order) as the batch completes, so an
    interruption loses at most the batch in flight (its tasks are cancelled)."""
    from swarm_ik import distributed

    func = functools.partial(_initialized_run, worker, initializer)
    size = batch_per_worker * distributed.n_workers(client)
    for start in range(0, len(todo), size):
        batch = list(todo[start : start + size])
        for outcome in distributed.map_chunks(func, batch, client=client, name="swarm-ik-bench"):
            write(outcome)


class _NoBar:
    def update(self, n: int) -> None:
        pass

    def close(self) -> None:
        pass


def _progress(total: int, initial: int, desc: str, enabled: bool) -> Any:
    if not enabled:
        return _NoBar()
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover - tqdm is a dependency
        return _NoBar()
    return tqdm(total=total, initial=initial, desc=desc, unit="run", dynamic_ncols=True)


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


@dataclass(frozen=True)
class Verdict:
    """Our value against a published one.

    Attributes:
        label: ``"reproduced"``, ``"better"`` or ``"worse"``.
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
    1/factor`` → *better*, ``a/b > factor`` → *worse*, otherwise *reproduced* (same order of
    magnitude).  ``floor`` is the level below which values are not distinguished: numerical
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
    return Verdict("reproduced", ratio, f"reproduced (ratio {ratio:.2g})")


def group_rows(
    rows: Iterable[Mapping[str, Any]], *keys: str
) -> dict[tuple[Any, ...], list[Mapping[str, Any]]]:
    """Rows grouped by the values of ``keys`` (insertion order kept)."""
    groups: dict[tuple[Any, ...], list[Mapping[str, Any]]] = {}
    for r in rows:
        groups.setdefault(tuple(r[k] for k in keys), []).append(r)
    return groups


def cpu_count() -> int:
    """CPUs available to this process."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1
