"""The one runner of every benchmark: resumable, parallel, CSV rows appended as runs finish.

A benchmark is a list of *tasks*: frozen, picklable objects with a ``key`` (unique within the
output folder; settings included, so runs made with other settings are never mistaken for
it) and an ``experiment`` (the CSV file ``<out>/<experiment>.csv`` its rows go to).  A
*worker* turns one task into an :class:`Outcome`: one or more rows (a task may solve one
target with several solvers, interleaved) and an optional history record.

:func:`execute` runs the tasks whose key is not yet in their experiment's CSV, inline
(``jobs=1``), over a pool of ``jobs`` spawned processes, or on Dask workers (``client``,
through :func:`swarm_ik.distributed.map_chunks`, a few tasks per worker at a time), and
**appends the rows of each finished task and flushes them at once**, so an interrupted
benchmark (Ctrl-C, a killed process) loses only the tasks in flight; running it again skips
what is there.  Rows of one task are written together, histories before rows (a row never
lacks its history).  Progress bars go to a terminal only (never into a log file).
"""

from __future__ import annotations

import csv
import functools
import io
import json
import math
import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol, TypeVar

from swarm_ik.errors import InvalidArgumentError

DASK_BATCH_PER_WORKER = 8
"""Tasks per Dask worker submitted at a time by :func:`execute` (rows written per batch)."""


class Task(Protocol):
    """What :func:`execute` needs of a task."""

    @property
    def key(self) -> str: ...  # pragma: no cover - protocol

    @property
    def experiment(self) -> str: ...  # pragma: no cover - protocol


@dataclass(frozen=True)
class Schema:
    """Columns of an experiment CSV and how to write / read them.

    Attributes:
        fields: Column names, in order; the first must be ``key``.
        ints: Integer columns (empty cell: ``None``).
        floats: Float columns (empty cell: NaN; written with ``repr``, exact round trip).
        bools: Boolean columns (``true`` / ``false``).
    """

    fields: tuple[str, ...]
    ints: frozenset[str] = field(default_factory=frozenset)
    floats: frozenset[str] = field(default_factory=frozenset)
    bools: frozenset[str] = field(default_factory=frozenset)

    def __post_init__(self) -> None:
        if not self.fields or self.fields[0] != "key":
            raise InvalidArgumentError(f"a schema's first column must be 'key', got {self.fields}")

    def format(self, name: str, v: Any) -> str:
        """The CSV cell of value ``v`` in column ``name``."""
        if v is None:
            return ""
        if name in self.bools:
            return "true" if v else "false"
        if name in self.floats:
            return "" if math.isnan(v) else repr(float(v))
        return str(v)

    def parse(self, name: str, text: str) -> Any:
        """The typed value of CSV cell ``text`` in column ``name``."""
        if name in self.ints:
            return None if text == "" else int(text)
        if name in self.floats:
            return math.nan if text == "" else float(text)
        if name in self.bools:
            if text not in ("true", "false"):
                raise InvalidArgumentError(f"column {name!r}: expected true/false, got {text!r}")
            return text == "true"
        return text


@dataclass(frozen=True)
class Outcome:
    """What a worker sends back for one task.

    Attributes:
        rows: Rows of the task, values by column name (every row carries its own ``key``,
            unique in the CSV; the task's key is the first row's, or the one given).
        history: A JSON-able record stored in ``<experiment>.history.jsonl`` under the task's
            key, or ``None``.
        task_key: The task's key when it is not the first row's key (multi-row tasks).
    """

    rows: Sequence[Mapping[str, Any]]
    history: Mapping[str, Any] | None = None
    task_key: str | None = None

    @property
    def key(self) -> str:
        """The task's key (resume unit)."""
        return self.task_key if self.task_key is not None else str(self.rows[0]["key"])


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
        fh.seek(data.rfind(b"\n") + 1)
        fh.truncate()


def read_rows(path: Path, schema: Schema) -> list[dict[str, Any]]:
    """Rows of an experiment CSV, typed by ``schema``.

    A partial last line (from a killed run) is ignored; when a key appears twice the last
    row wins.

    Raises:
        InvalidArgumentError: the header is not ``schema.fields``.
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
    if tuple(header) != schema.fields:
        raise InvalidArgumentError(
            f"{path}: unexpected CSV header {header}; expected {list(schema.fields)}"
        )
    by_key: dict[str, dict[str, Any]] = {}
    for rec in reader:
        if len(rec) != len(schema.fields):
            continue
        row = {n: schema.parse(n, v) for n, v in zip(schema.fields, rec, strict=True)}
        by_key[row["key"]] = row
    return list(by_key.values())


def read_histories(path: Path) -> dict[str, dict[str, Any]]:
    """History records by task key from a JSON-lines file (partial or broken lines skipped)."""
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


def _done_path(out: Path, experiment: str) -> Path:
    return Path(out) / f"{experiment}.done"


class _Writer:
    """Appends the rows (and history) of finished tasks to an experiment's files."""

    def __init__(self, out: Path, experiment: str, schema: Schema, multi_row: bool) -> None:
        self.schema = schema
        csv_file = csv_path(out, experiment)
        csv_file.parent.mkdir(parents=True, exist_ok=True)
        self._hist_file = history_path(out, experiment)
        self._done_file = _done_path(out, experiment) if multi_row else None
        for p in (csv_file, self._hist_file, self._done_file):
            if p is not None:
                _repair_tail(p)
        new = not csv_file.exists() or csv_file.stat().st_size == 0
        self._csv = open(csv_file, "a", newline="")  # noqa: SIM115 - closed in close()
        self._hist: Any = None
        self._done: Any = None
        self._w = csv.writer(self._csv, lineterminator="\n")
        if new:
            self._w.writerow(schema.fields)
            self._csv.flush()

    def write(self, o: Outcome) -> None:
        if o.history is not None:
            if self._hist is None:
                self._hist = open(self._hist_file, "a")  # noqa: SIM115
            rec = {"key": o.key, **o.history}
            self._hist.write(json.dumps(rec, separators=(",", ":")) + "\n")
            self._hist.flush()
        for row in o.rows:
            self._w.writerow([self.schema.format(n, row[n]) for n in self.schema.fields])
        self._csv.flush()
        if self._done_file is not None:  # a multi-row task is done once all its rows are in
            if self._done is None:
                self._done = open(self._done_file, "a")  # noqa: SIM115
            self._done.write(o.key + "\n")
            self._done.flush()

    def close(self) -> None:
        for fh in (self._csv, self._hist, self._done):
            if fh is not None:
                fh.close()


# --------------------------------------------------------------------------- runner
@dataclass(frozen=True)
class Summary:
    """What :func:`execute` did.

    Attributes:
        total: Tasks asked for.
        skipped: Tasks already done (resumed past).
        new: Tasks finished and written now.
        interrupted: True when a KeyboardInterrupt stopped it (the finished rows are saved).
        wall_s: Wall-clock seconds of this call.
    """

    total: int
    skipped: int
    new: int
    interrupted: bool
    wall_s: float


def done_keys(out: Path, experiment: str, schema: Schema, multi_row: bool) -> set[str]:
    """Keys of the tasks of ``experiment`` already done under ``out``."""
    if not multi_row:
        return {r["key"] for r in read_rows(csv_path(out, experiment), schema)}
    p = _done_path(out, experiment)
    if not p.exists():
        return set()
    text = p.read_text()
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]
    return set(text.splitlines())


T = TypeVar("T", bound=Task)


def pending(
    tasks: Iterable[T], out: Path, schema: Schema, multi_row: bool = False
) -> tuple[list[T], int]:
    """The tasks not yet done under ``out``, and how many were done."""
    tasks = list(tasks)
    done: dict[str, set[str]] = {}
    todo = []
    for t in tasks:
        if t.experiment not in done:
            done[t.experiment] = done_keys(out, t.experiment, schema, multi_row)
        if t.key not in done[t.experiment]:
            todo.append(t)
    return todo, len(tasks) - len(todo)


def execute(
    tasks: Sequence[Task],
    out: Path,
    worker: Callable[[Any], Outcome],
    schema: Schema,
    *,
    jobs: int = 1,
    client: Any = None,
    initializer: Callable[[], None] | None = None,
    multi_row: bool = False,
    progress: bool | None = None,
    desc: str = "runs",
    batch_per_worker: int = DASK_BATCH_PER_WORKER,
) -> Summary:
    """Run the tasks not yet done under ``out``, appending their rows as they finish.

    Args:
        tasks: The tasks (any experiments; each task's rows go to its experiment's CSV).
        out: Output folder.
        worker: ``task -> Outcome`` (picklable when ``jobs > 1`` or with ``client``).
        schema: Columns of the CSV files.
        jobs: Worker processes (1: inline in this process); ignored with ``client``.
        client: A ``distributed.Client``: run on its workers, ``batch_per_worker`` tasks per
            worker at a time; ``None``: the process pool / inline.
        initializer: Called once per worker process (inline: once before the first task).
        multi_row: Tasks produce several rows each: completion is recorded per task in
            ``<experiment>.done`` (so a task killed half-written is rerun; its rows are
            rewritten and the last copy of each row key wins on reading).
        progress: Show a progress bar; ``None`` (default): only when stderr is a terminal.
        desc: Label of the progress bar.
        batch_per_worker: Tasks per worker in one Dask batch.

    Returns:
        A summary; on KeyboardInterrupt the finished tasks are saved and ``interrupted`` is
        True (run again to resume).

    Raises:
        InvalidArgumentError: ``jobs < 1``, ``batch_per_worker < 1`` or two tasks share a key.
    """
    if jobs < 1:
        raise InvalidArgumentError(f"jobs must be >= 1, got {jobs}")
    if batch_per_worker < 1:
        raise InvalidArgumentError(f"batch_per_worker must be >= 1, got {batch_per_worker}")
    keys = [t.key for t in tasks]
    if len(set(keys)) != len(keys):
        dup = sorted({k for k in keys if keys.count(k) > 1})[:3]
        raise InvalidArgumentError(f"duplicate run keys: {dup}")
    t0 = time.perf_counter()
    out = Path(out)
    todo, skipped = pending(tasks, out, schema, multi_row)
    writers: dict[str, _Writer] = {}
    exp_of = {t.key: t.experiment for t in todo}
    written = [0]
    bar = _progress(len(tasks), skipped, desc, progress)

    def write(o: Outcome) -> None:
        exp = exp_of.get(o.key) or str(o.rows[0]["experiment"])
        if exp not in writers:
            writers[exp] = _Writer(out, exp, schema, multi_row)
        writers[exp].write(o)
        written[0] += 1
        bar.update(1)

    interrupted = False
    try:
        if client is not None:
            if todo:
                _execute_dask(todo, client, worker, write, initializer, batch_per_worker)
        elif jobs == 1 or len(todo) <= 1:
            if todo and initializer is not None:
                initializer()
            for t in todo:
                write(worker(t))
        else:
            _execute_pool(todo, jobs, worker, write, initializer)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        bar.close()
        for w in writers.values():
            w.close()
    return Summary(len(tasks), skipped, written[0], interrupted, time.perf_counter() - t0)


def _execute_pool(
    todo: Sequence[Task],
    jobs: int,
    worker: Callable[[Any], Outcome],
    write: Callable[[Outcome], None],
    initializer: Callable[[], None] | None,
) -> None:
    """Run ``todo`` over ``jobs`` spawned processes, at most ``2·jobs`` queued at a time (an
    interruption writes what has finished, cancels the queue and stops the workers at once:
    the runs they held are lost, to be run again on resume)."""
    ctx = multiprocessing.get_context("spawn")  # no fork: safe with numba/BLAS threads
    init = None if initializer is None else functools.partial(_quiet_initializer, initializer)
    others = set(multiprocessing.active_children())  # (children that are not the pool's)
    pool = ProcessPoolExecutor(max_workers=jobs, mp_context=ctx, initializer=init)
    futures: dict[Future[Outcome], Task] = {}
    queue = iter(todo)
    try:
        for t in queue:
            futures[pool.submit(worker, t)] = t
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
        for fut in futures:
            if fut.done() and not fut.cancelled() and fut.exception() is None:
                write(fut.result())
        pool.shutdown(wait=False, cancel_futures=True)
        for proc in set(multiprocessing.active_children()) - others:  # the pool's workers:
            proc.terminate()  # stopped now, not after their runs (Ctrl-C within a second)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _quiet_initializer(initializer: Callable[[], None]) -> None:
    """A pool worker's ``initializer``, ended without a traceback by the Ctrl-C that a
    terminal sends to the whole process group (the parent reports the interruption)."""
    try:
        initializer()
    except KeyboardInterrupt:
        os._exit(130)


_INITIALIZED: set[Any] = set()
"""Initializers already called in this (Dask worker) process."""


def _initialized_run(
    worker: Callable[[Any], Outcome], initializer: Callable[[], None] | None, task: Any
) -> Outcome:
    """``worker(task)`` after calling ``initializer`` once in this process (Dask tasks)."""
    if initializer is not None and initializer not in _INITIALIZED:
        initializer()
        _INITIALIZED.add(initializer)
    return worker(task)


def _execute_dask(
    todo: Sequence[Task],
    client: Any,
    worker: Callable[[Any], Outcome],
    write: Callable[[Outcome], None],
    initializer: Callable[[], None] | None,
    batch_per_worker: int,
) -> None:
    """Run ``todo`` on the Dask workers behind ``client``, ``batch_per_worker × workers`` tasks
    at a time (one Dask task each); each batch's outcomes are written as it completes."""
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


def _progress(total: int, initial: int, desc: str, enabled: bool | None) -> Any:
    if enabled is None:
        enabled = sys.stderr.isatty()
    if not enabled:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc=desc, unit="task", dynamic_ncols=True)
