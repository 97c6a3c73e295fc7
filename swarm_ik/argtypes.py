"""Types of command-line options shared by the ``swarm-ik`` sub-commands and the benchmarks
(``argparse`` ``type=`` functions: a bad value is one line and exit 2, before anything runs).

Standard library only: the parsers are built without loading numpy or numba.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

SEED_LIMIT = 2**63
"""Seeds are integers in ``[0, SEED_LIMIT)`` (as :func:`swarm_ik._validate.check_seed`)."""


def seed(text: str) -> int:
    """A ``--seed``: an integer in ``[0, 2**63)``."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer seed, got {text!r}") from None
    if not 0 <= value < SEED_LIMIT:
        raise argparse.ArgumentTypeError(f"a seed must be in [0, 2**63), got {text}")
    return value


def count(lowest: int = 1, highest: int | None = None) -> Callable[[str], int]:
    """The type of an option that counts something: an integer ``>= lowest`` (and
    ``<= highest`` when given)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if value < lowest:
            raise argparse.ArgumentTypeError(f"must be an integer from {lowest}, got {text}")
        if highest is not None and value > highest:
            raise argparse.ArgumentTypeError(
                f"must be an integer from {lowest} to {highest}, got {text}"
            )
        return value

    parse.__name__ = f"count_from_{lowest}"
    return parse


def positive_number(text: str) -> float:
    """A finite number ``> 0`` (a tolerance, a budget in ms)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(value) and value > 0.0):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text}")
    return value


def add_seed(parser: argparse.ArgumentParser, help: str, default: int = 0) -> None:
    """``--seed`` (:func:`seed`) on ``parser``, described by ``help``."""
    parser.add_argument("--seed", type=seed, default=default, help=f"{help} (default {default})")
