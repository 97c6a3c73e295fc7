"""Scale-out on Dask: run chunks of work in this process, on an embedded local cluster, or on
an existing Dask scheduler.

``scheduler`` (the ``--scheduler`` option of ``swarm-ik batch | reach | bench``) is one of:

* ``None`` or ``"none"``: no Dask; the chunks run one after the other in this process.
* ``"threads"``: no Dask either; the chunks run on a pool of threads of this process, one per
  core (:class:`Threads`).  The compiled kernels of :func:`swarm_ik.solve_batch` release the
  GIL while they run, so its chunks run side by side with nothing to start and nothing
  copied between processes (the Python between two kernel calls, coal's exact check and
  Python goals still take turns).  For batches and reach maps; the benchmarks that time
  Python peers refuse it.
* ``"local"``: an embedded :class:`dask.distributed.LocalCluster` on 127.0.0.1, one
  single-threaded worker *process* per core (any work, whatever holds the GIL).  Needs no
  set-up; it starts in a few seconds.
* an address ``"tcp://host:port"`` (or ``tls://…``): an existing scheduler, e.g. one started
  with ``dask scheduler`` and workers started with ``dask worker tcp://host:port`` on other
  machines (each with swarm_ik installed).
* a ``distributed.Client``: used as is (not closed).

Each chunk is one Dask task with a key of its own call and place (``name-<call>-<index>``), so
a call never meets the tasks of an earlier one (a failed call's tasks are cancelled, and a
retry on the same client gets tasks of its own), and the results come back in the order of
the chunks.  When a worker dies, the scheduler recomputes its unfinished tasks on
the remaining workers (Dask's own fault tolerance); nothing is lost or duplicated.  Whatever
runs in the chunks must not depend on which worker runs it: :func:`swarm_ik.solve_batch`
keys its random streams by target index for that reason.

Dask is an optional dependency: ``pip install "swarm_ik[dask]"`` (``dask[distributed]``).
A script that uses ``"local"`` must guard its entry point with ``if __name__ == "__main__":``
(the worker processes are spawned and import the main module).
"""

from __future__ import annotations

import logging
import multiprocessing
import os
import queue
import re
import signal
import socket
import threading
import uuid
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack, closing, contextmanager
from typing import Any, TypeVar

from swarm_ik._signals import sigint_deferred, sigint_settable
from swarm_ik.errors import InvalidArgumentError

T = TypeVar("T")
R = TypeVar("R")

LOCAL = "local"
"""``scheduler`` value for an embedded LocalCluster."""
IN_PROCESS = "none"
"""``scheduler`` value for no Dask at all (chunks run in this process)."""
THREADS = "threads"
"""``scheduler`` value for a pool of threads in this process (:class:`Threads`; no Dask)."""
SCHEMES = ("tcp://", "tls://", "inproc://")
"""Accepted prefixes of a scheduler address."""


def _import_distributed() -> Any:
    try:
        import distributed
    except ImportError:  # pragma: no cover - depends on the environment
        raise InvalidArgumentError(
            "a Dask scheduler was requested but dask.distributed is not installed; install it "
            'with `pip install "swarm_ik[dask]"` (or `pip install "dask[distributed]"`), '
            "or use --scheduler none"
        ) from None
    return distributed


def available_cores() -> int:
    """Cores this process may run on (affinity mask where available)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - macOS / Windows
        return max(1, os.cpu_count() or 1)


_HOST_PORT = re.compile(r"(tcp|tls)://(\[[^\]]+\]|[^:/\[\]]+):(\d{1,5})/?")
"""A ``tcp://`` or ``tls://`` address: scheme, host (an IPv6 one in brackets), port."""


def check_scheduler(scheduler: Any, *, threads: bool = True) -> Any:
    """Validate a ``scheduler`` value; returns it (``None`` for "in this process, one chunk
    after the other").

    Args:
        scheduler: See the module docstring.
        threads: Whether ``"threads"`` is a choice (not for the benchmarks that time Python
            peers: threads of one process would take turns on the GIL inside their timings).

    Raises:
        InvalidArgumentError: not ``None``, ``"none"``, ``"threads"``, ``"local"``, an address
            with one of :data:`SCHEMES`, or a ``distributed.Client``; the message lists the
            choices.
    """
    if scheduler is None or scheduler == IN_PROCESS:
        return None
    if isinstance(scheduler, str):
        if scheduler == LOCAL:
            return scheduler
        if scheduler == THREADS:
            if not threads:
                raise InvalidArgumentError(
                    "scheduler 'threads' is for batches and reach maps (its threads would take "
                    "turns on Python's lock inside the timings here); valid choices: 'none', "
                    "'local' or a Dask scheduler address tcp://host:port"
                )
            return scheduler
        m = _HOST_PORT.fullmatch(scheduler)
        if scheduler.startswith(("tcp://", "tls://")) and (m is None or int(m.group(3)) > 65535):
            raise InvalidArgumentError(
                f"scheduler address {scheduler!r} needs a host and a port (1 to 65535), e.g. "
                "tcp://127.0.0.1:8786"
            )
        if scheduler.startswith(SCHEMES):
            return scheduler
        raise InvalidArgumentError(
            f"unknown scheduler {scheduler!r}; valid choices: 'none' (in this process), "
            + ("'threads' (a thread per core in this process), " if threads else "")
            + "'local' (embedded LocalCluster), or an address starting with "
            + ", ".join(SCHEMES)
            + " (e.g. tcp://127.0.0.1:8786)"
        )
    if isinstance(scheduler, Threads) and threads:  # (what connect("threads") yields)
        return scheduler
    if hasattr(scheduler, "submit") and hasattr(scheduler, "gather"):
        return scheduler
    raise InvalidArgumentError(
        "scheduler must be None, 'none', "
        + ("'threads', " if threads else "")
        + f"'local', an address or a distributed.Client; got {type(scheduler).__name__}"
    )


@contextmanager
def connect(
    scheduler: Any = None,
    *,
    n_workers: int | None = None,
    timeout: float = 30.0,
) -> Iterator[Any]:
    """A Dask client for ``scheduler`` (``None`` when no Dask is wanted), closed on exit.

    Args:
        scheduler: See the module docstring.
        n_workers: Worker processes of an embedded LocalCluster, or threads of
            ``"threads"`` (default: the cores).
        timeout: Seconds to wait for a remote scheduler.

    Yields:
        ``None`` (in-process), :class:`Threads` (``"threads"``), or a
        ``distributed.Client``.  A Client passed in is yielded and left open; clusters and
        clients created here are closed at exit.
    """
    scheduler = check_scheduler(scheduler)
    if scheduler is None:
        yield None
        return
    if isinstance(scheduler, str) and scheduler == THREADS:
        yield Threads(n_workers or available_cores())
        return
    if not isinstance(scheduler, str):  # (a Client, or a Threads: used as they are)
        yield scheduler
        return
    distributed = _import_distributed()
    if scheduler == LOCAL:
        cluster = None
        try:
            with sigint_blocked_for_workers():  # (a Ctrl-C reaches this process alone)
                cluster = distributed.LocalCluster(
                    n_workers=n_workers or available_cores(),
                    threads_per_worker=1,
                    processes=True,
                    host="127.0.0.1",
                    # (no dashboard: Dask's scheduler still serves HTTP, on 8787 unless told
                    # otherwise, and warned where that port was taken; a free local port)
                    dashboard_address="127.0.0.1:0",
                    scheduler_kwargs={"dashboard": False},
                    # (what the worker processes print: an ERROR record too, e.g. a heartbeat cut
                    # by the scheduler closing on Ctrl-C, 30 lines; a task's error reaches the
                    # client)
                    silence_logs=logging.CRITICAL,
                )
        except KeyboardInterrupt:  # (raised once the cluster is up: closed, then passed on)
            if cluster is not None:
                cluster.close()
            raise
        except RuntimeError as exc:  # (a worker that failed to start)
            raise InvalidArgumentError(
                f"scheduler='local' could not start its worker processes ({exc}); " + _MAIN_GUARD
            ) from None
        try:
            client = distributed.Client(cluster)
            _EMBEDDED[id(client)] = set(client.run(os.getpid).values())
            try:
                yield client
            except KeyboardInterrupt:
                abandon(client)
                raise
            finally:
                _EMBEDDED.pop(id(client), None)
                client.close()
        finally:
            cluster.close()
        return
    _probe(scheduler, timeout)
    try:
        client = distributed.Client(scheduler, timeout=timeout)
    except OSError as exc:
        raise InvalidArgumentError(
            f"could not reach the Dask scheduler at {scheduler!r} ({exc})"
        ) from None
    except (MemoryError, ValueError, TypeError) as exc:  # (a server whose greeting Dask misread:
        # a length of 3 EiB, say)
        raise InvalidArgumentError(
            f"{scheduler!r} answered, but not as a Dask scheduler ({type(exc).__name__})"
        ) from None
    try:
        yield client
    finally:
        client.close()


@contextmanager
def sigint_blocked_for_workers() -> Iterator[None]:
    """Start worker processes deaf to SIGINT without losing a Ctrl-C meant for this process.

    While the body runs (an embedded cluster's start-up) SIGINT is *blocked* in this thread;
    the threads it starts meanwhile and the processes they start (fork, spawn or forkserver:
    the mask survives fork and exec) inherit the mask, so a Ctrl-C sent to the process group
    later stays pending in the workers for good (no traceback from each) and reaches this
    process only.  A Ctrl-C during the body is recorded (held pending by the mask, or caught
    by a handler where a thread that does not block SIGINT takes it) and raised again at its
    end, with the cluster in hand (the caller's exit closes it): not lost (the SIG_IGN used
    before dropped it, and the whole batch then ran), not raised half-way through the
    start-up.  The mask and the handler are restored at once.

    multiprocessing's resource tracker is started first: the thread that starts it unblocks
    SIGINT (bpo-33613), and would then start the workers with SIGINT unblocked.  Where masks
    are not available (Windows) SIGINT is ignored during the body instead, as it was.
    """
    if not sigint_settable():
        yield
        return
    if not hasattr(signal, "pthread_sigmask"):  # pragma: no cover - Windows
        old = signal.getsignal(signal.SIGINT)
        try:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            yield
        finally:
            signal.signal(signal.SIGINT, old)
        return
    with sigint_deferred():  # (raised again once the mask is off and the handler back)
        from multiprocessing import resource_tracker

        resource_tracker.ensure_running()
        old_mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            yield
        finally:  # (a Ctrl-C held pending is recorded by sigint_deferred's handler here)
            signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)


_MAIN_GUARD = (
    "the workers of scheduler='local' are new Python processes that import the calling "
    "script again, so a script must make the call under "
    '`if __name__ == "__main__":` (the usual cause)'
)
"""Why an embedded cluster's workers fail in a script without Python's main guard."""

_EMBEDDED: dict[int, set[int]] = {}
"""The worker processes' ids of each embedded cluster's client :func:`connect` made (by
``id(client)``), for :func:`abandon`."""


def abandon(client: Any) -> None:
    """Kill at once the worker processes of an embedded cluster that :func:`connect` made for
    ``client`` (after a Ctrl-C: their running chunks are dropped).  A graceful close waits for
    the running tasks (a compiled chunk cannot be interrupted) and then kills them after
    4 s; killed first, the cluster closes within a second.  Nothing is done for other
    clients, and only this process's own children are touched."""
    pids = _EMBEDDED.get(id(client), set())
    for child in multiprocessing.active_children():
        if child.pid in pids:
            child.kill()


def n_workers(client: Any) -> int:
    """Workers behind ``client`` (1 for ``None``, in-process; the threads of :class:`Threads`)."""
    if client is None:
        return 1
    if isinstance(client, Threads):
        return client.n
    return max(1, len(client.scheduler_info().get("workers", {})))


class Threads:
    """The pool of ``scheduler="threads"``: chunks on up to ``n`` threads of this process.

    The kernels of a batch release the GIL (numba's ``nogil``) while they run, so chunks run
    side by side on the cores; the Python between kernel calls takes turns.  The threads are
    daemons kept for the process's later calls (what a thread makes once, such as its list of
    goal kernels, is made once): after a Ctrl-C (or a chunk's error) no chunk starts, and a
    chunk already running ends in the background without keeping the process alive (a
    compiled chunk cannot be stopped from outside; a batch's chunks take a fraction of a
    second each, a time limit bounds them).

    Attributes:
        n: Threads (at least 1).
    """

    WAIT_S = 0.1
    """Seconds between two looks of the calling thread at the chunks (where a Ctrl-C raises)."""

    def __init__(self, n: int) -> None:
        self.n = max(1, int(n))

    def map(
        self,
        func: Callable[[T], R],
        items: Sequence[T],
        done: Callable[[int], Any] | None = None,
    ) -> list[R]:
        """``[func(item) for item in items]``, the items taken in order by up to :attr:`n`
        threads; ``done(i)`` is called in the calling thread as item ``i`` finishes.  The
        first error of a chunk is raised here (no chunk starts after it)."""
        results: list[Any] = [None] * len(items)
        todo: queue.SimpleQueue[int] = queue.SimpleQueue()
        for i in range(len(items)):
            todo.put(i)
        finished: queue.SimpleQueue[tuple[int, BaseException | None]] = queue.SimpleQueue()
        stop = threading.Event()

        def runner() -> None:  # (one of this call's n: takes items until none is left)
            while not stop.is_set():
                try:
                    i = todo.get_nowait()
                except queue.Empty:
                    return
                try:
                    results[i] = func(items[i])
                except BaseException as exc:  # (passed to the calling thread)
                    stop.set()
                    finished.put((i, exc))
                    return
                finished.put((i, None))

        try:
            with sigint_deferred():  # (a Ctrl-C here is raised once every runner started, and
                # the finally below stops them: none lost, none left running the batch)
                for _ in range(min(self.n, len(items))):
                    _POOL.run(runner)
            for _ in range(len(items)):
                while True:
                    try:
                        i, exc = finished.get(timeout=self.WAIT_S)
                        break
                    except queue.Empty:
                        continue
                if exc is not None:
                    raise exc
                if done is not None:
                    done(i)
        finally:
            stop.set()
        return results

    def __repr__(self) -> str:
        return f"Threads(n={self.n})"


class _Pool:
    """The process's daemon threads behind :class:`Threads`: a job waits for an idle thread,
    and a new thread starts when none is idle."""

    def __init__(self) -> None:
        self._jobs: queue.SimpleQueue[Callable[[], None]] = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._idle = 0
        self._started = 0

    def run(self, job: Callable[[], None]) -> None:
        """Run ``job`` on a thread of the pool (an idle one, else a new one)."""
        with self._lock:
            start = self._idle == 0
            if start:
                self._started += 1
            else:
                self._idle -= 1
            name = f"swarm-ik-{self._started}"
        self._jobs.put(job)
        if start:
            try:
                threading.Thread(target=self._serve, name=name, daemon=True).start()
            except BaseException:  # (no thread: the job waits for one that frees itself)
                with self._lock:
                    self._started -= 1
                raise

    def _serve(self) -> None:
        while True:
            job = self._jobs.get()
            try:
                job()
            finally:
                with self._lock:
                    self._idle += 1


_POOL = _Pool()


class _NoBar:
    """Stand-in for a disabled progress bar (tqdm is not imported unless one is shown)."""

    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass


def progress_bar(enabled: bool, total: int, desc: str | None, unit: str) -> Any:
    """A tqdm bar of ``total`` ``unit``s (or one that does nothing when not ``enabled``), for
    :func:`map_chunks` and callers that send chunks in waves (``solve_batch``)."""
    if not enabled:
        return _NoBar()
    from tqdm.auto import tqdm

    return tqdm(total=total, desc=desc, disable=not enabled, unit=unit, dynamic_ncols=True)


def on_every_worker(client: Any, func: Callable[[T], R], item: T, name: str = "swarm-ik") -> None:
    """``func(item)`` once on each worker behind ``client``, waited for:
    what the workers load the first time (the kernels from numba's cache, a scene's sphere
    model) loaded before a caller's clock starts; nothing for ``None`` or :class:`Threads`
    (this process: the caller's own loading)."""
    if client is None or isinstance(client, Threads):
        return
    call = uuid.uuid4().hex[:16]
    workers = list(client.scheduler_info().get("workers", {}))
    futures = [
        client.submit(func, item, key=f"{name}-warm-{call}-{i}", workers=[w], pure=False)
        for i, w in enumerate(workers)
    ]
    try:
        client.gather(futures)
    except BaseException:
        client.cancel(futures)
        raise


def map_chunks(
    func: Callable[[T], R],
    items: Sequence[T],
    *,
    client: Any = None,
    scheduler: Any = None,
    name: str = "swarm-ik",
    progress: bool = False,
    desc: str | None = None,
    sizes: Sequence[int] | None = None,
    unit: str = "item",
) -> list[R]:
    """``[func(item) for item in items]``, on Dask workers when a client or scheduler is given.

    Helper for anything that splits work into independent chunks (batched IK, reachability
    maps, benchmark sweeps).  ``func`` and the items must be picklable and ``func`` must be
    importable on the workers (a module-level function or a ``functools.partial`` of one).

    Args:
        func: Function of one item.
        items: The chunks.
        client: A ``distributed.Client`` to use (takes precedence over ``scheduler``).
        scheduler: Otherwise a scheduler spec (see the module docstring); a cluster or
            connection made for it is closed before returning.
        name: Prefix of the Dask task keys.
        progress: Show a progress bar (tqdm).
        desc: Label of the progress bar.
        sizes: Weight of each item in the progress bar (e.g. targets per chunk); default 1.
        unit: Unit of the progress bar (e.g. ``"pose"``).

    Returns:
        ``func(item)`` for each item, in the order of ``items`` (each exactly once).
    """
    if sizes is not None and len(sizes) != len(items):
        raise InvalidArgumentError(
            f"sizes must have one entry per item ({len(items)}), got {len(sizes)}"
        )
    weights = list(sizes) if sizes is not None else [1] * len(items)
    with ExitStack() as stack:
        if client is None and check_scheduler(scheduler) is not None:
            client = stack.enter_context(connect(scheduler))
        bar = stack.enter_context(closing(progress_bar(progress, int(sum(weights)), desc, unit)))
        if client is None:
            out = []
            for item, w in zip(items, weights, strict=True):
                out.append(func(item))
                bar.update(w)
            return out
        if isinstance(client, Threads):
            return client.map(func, items, lambda i: bar.update(weights[i]))
        distributed = _import_distributed()
        # keys of this call alone: a key of an earlier call that failed may still name its
        # cancelled task on this client, which would answer for the new one
        call = uuid.uuid4().hex[:16]
        futures = [
            client.submit(func, item, key=f"{name}-{call}-{i}") for i, item in enumerate(items)
        ]
        position = {f.key: i for i, f in enumerate(futures)}
        try:
            for f in distributed.as_completed(futures):
                bar.update(weights[position[f.key]])
            return list(client.gather(futures))
        except BaseException:
            client.cancel(futures)
            raise


def _probe(scheduler: str, timeout: float) -> None:
    """Refuse at once a ``tcp://host:port`` scheduler that refuses the connection (Dask's
    client retries until its ``timeout``, 30 s, before saying so), or that sends nothing
    within :data:`PROBE_S` of it (a Dask scheduler greets a new connection at once; another
    server, a dashboard's HTTP port say, waits for a request, and Dask's client waited for
    its greeting forever, whatever the time limit)."""
    m = _HOST_PORT.fullmatch(scheduler)
    if m is None or m.group(1) != "tcp":
        return
    wait = min(timeout, PROBE_S)
    try:
        conn = socket.create_connection((m.group(2).strip("[]"), int(m.group(3))), timeout=wait)
    except (OSError, UnicodeError) as exc:  # (refused, timed out, no such host, a bad name)
        raise InvalidArgumentError(
            f"could not reach the Dask scheduler at {scheduler!r} "
            f"({getattr(exc, 'strerror', None) or exc})"
        ) from None
    with conn:
        conn.settimeout(wait)
        try:
            greeting = conn.recv(8)
        except TimeoutError:
            raise InvalidArgumentError(
                f"{scheduler!r} accepted the connection but sent nothing in {wait:g} s: not a "
                "Dask scheduler's address (a dashboard's HTTP port?)"
            ) from None
        except OSError as exc:
            greeting, why = b"", exc.strerror or str(exc)
        else:
            why = "it closed the connection at once"
    if not greeting:
        raise InvalidArgumentError(
            f"{scheduler!r} is no Dask scheduler's address ({why} without a greeting)"
        )


PROBE_S = 5.0
"""Seconds :func:`connect` waits for a remote scheduler's greeting before refusing it."""
