"""A Ctrl-C held until a block ends: standard library only, for the few places where one must
not land half-way (an embedded Dask cluster's start-up, :mod:`swarm_ik.distributed`; an import
that swallows ``KeyboardInterrupt``, :mod:`swarm_ik.spheres`)."""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


def sigint_settable() -> bool:
    """Whether this thread may replace the SIGINT handler: the main thread, and a handler set
    from Python (one set from C cannot be restored)."""
    return (
        threading.current_thread() is threading.main_thread()
        and signal.getsignal(signal.SIGINT) is not None
    )


@contextmanager
def sigint_deferred() -> Iterator[None]:
    """A Ctrl-C during the body is recorded, not raised there, and sent again at its end to
    the handler it was meant for (``KeyboardInterrupt``), once the previous handler is back.
    Where the handler cannot be replaced (:func:`sigint_settable`) the body runs as it is."""
    if not sigint_settable():
        yield
        return
    caught: list[int] = []

    def record(signum: int, frame: Any) -> None:
        caught.append(signum)

    old = signal.getsignal(signal.SIGINT)
    try:  # (the handler replaced inside: an interruption as it is replaced cannot leave it)
        signal.signal(signal.SIGINT, record)
        yield
    finally:
        signal.signal(signal.SIGINT, old)
        if caught:
            signal.raise_signal(signal.SIGINT)
