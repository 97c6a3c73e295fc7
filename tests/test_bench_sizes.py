"""``swarm-ik bench NAME``: every size and count option is capped (``swarm_ik.bench.sizes``'s
``MAX_*``) and a value above its cap is refused with exit 2 and one line naming the option,
the value and the cap, before a robot is loaded or the benchmark runs; values up to the cap
still reach the benchmark."""

from __future__ import annotations

import argparse
import importlib
import re
from pathlib import Path

import pytest
from conftest import never

from swarm_ik.bench import sizes
from swarm_ik.cli import bench

CASES = [
    (name, option, lowest, cap, cap_name)
    for name, options in sizes.SIZE_OPTIONS.items()
    if name in bench.BENCHMARKS  # (``path`` runs as ``python -m swarm_ik.bench.path`` only)
    for option, lowest, cap, cap_name in options
]
"""Every capped option of ``swarm-ik bench``: ``(benchmark, option, lowest, cap, cap's name)``."""

IDS = [f"{name} {option}" for name, option, *_ in CASES]


def _module(name: str):
    """The benchmark module of ``name`` (skipped where an optional dependency is missing)."""
    module = bench.BENCHMARKS.get(name, f"swarm_ik.bench.{name}")
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as exc:  # pragma: no cover - every module imports here
        pytest.skip(f"{module} needs {exc.name}")


def _bench_parsers() -> dict[str, argparse.ArgumentParser]:
    """The parsers of ``swarm-ik bench NAME``, with their options, by benchmark name."""
    parser = argparse.ArgumentParser(prog="swarm-ik")
    b = bench.add_parser(parser.add_subparsers(dest="command"))
    sub = next(a for a in b._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def test_the_caps_are_generous_and_bounded() -> None:
    """The caps exceed every default (and the papers' settings) and stay finite."""
    from swarm_ik.bench import plans

    assert sizes.MAX_TARGETS >= 100 * 1000  # bench ik's default N
    assert sizes.MAX_BATCH >= 10 * max(plans.THROUGHPUT_SIZES)
    assert sizes.MAX_MANY_N >= 16
    assert sizes.MAX_RUNS >= 10 * plans.FULL.runs_003
    assert sizes.MAX_REPEAT >= 3 and sizes.MAX_BOXES >= 200 and sizes.MAX_JOBS >= 64
    for _, _, _, cap, cap_name in CASES:
        assert getattr(sizes, cap_name) == cap < 10**9


def test_every_count_option_of_every_benchmark_is_capped() -> None:
    """Each option of type ``argtypes.count`` of each ``bench`` sub-command is in
    ``SIZE_OPTIONS``, with the same lowest value (an option added later without a cap fails)."""
    capped = {(name, option): lowest for name, option, lowest, *_ in CASES}
    found = {}
    for name, parser in _bench_parsers().items():
        for action in parser._actions:
            kind = getattr(action.type, "__name__", "")
            if kind.startswith("count_from_"):
                found[(name, action.option_strings[0])] = int(kind.rsplit("_", 1)[1])
    assert found == capped


@pytest.mark.parametrize(("name", "option", "lowest", "cap", "cap_name"), CASES, ids=IDS)
def test_a_size_above_its_cap_is_refused_before_any_work(
    name: str, option: str, lowest: int, cap: int, cap_name: str, refused, monkeypatch, tmp_path
) -> None:
    """``swarm-ik bench NAME OPTION 10**12`` (the reviewer's values exhausted the memory or ran
    on without end): exit 2, one line naming the option, the value and the cap; the benchmark
    not run, no robot loaded, no folder made."""
    module = _module(name)
    monkeypatch.setattr(module, "run", never)
    out = tmp_path / "out"
    huge = str(10**12)
    line = refused("bench", name, option, huge, "--out", str(out))
    assert f"{option} must be a count from {lowest} to {cap}" in line
    assert f"swarm_ik.bench.sizes.{cap_name}" in line and line.endswith(f"got {huge}")
    line = refused("bench", name, option, str(cap + 1), "--out", str(out))
    assert line.endswith(f"got {cap + 1}")
    assert not out.exists()


@pytest.mark.parametrize(("name", "option", "lowest", "cap", "cap_name"), CASES, ids=IDS)
def test_sizes_up_to_the_cap_reach_the_benchmark(
    name: str, option: str, lowest: int, cap: int, cap_name: str, monkeypatch, tmp_path
) -> None:
    """The smallest value, a small one and the cap itself pass the check: the benchmark's
    ``run`` is called with them (replaced here, so that nothing is computed)."""
    from swarm_ik.cli import main

    module = _module(name)
    seen: list[argparse.Namespace] = []
    monkeypatch.setattr(module, "run", lambda args: seen.append(args) or 0)
    dest = option[2:].replace("-", "_")
    for value in (lowest, 2, cap):
        assert main(["bench", name, option, str(value), "--out", str(tmp_path / "out")]) == 0
        got = getattr(seen[-1], dest)
        assert (got if isinstance(got, int) else got[0]) == value


def test_a_list_of_sizes_is_refused_at_its_first_value_above_the_cap(refused, tmp_path) -> None:
    """``bench throughput --sizes 100 CAP+1``: the value above the cap is the one named."""
    line = refused(
        "bench", "throughput", "--sizes", "100", str(sizes.MAX_BATCH + 1), "--out", str(tmp_path)
    )
    assert line.endswith(f"got {sizes.MAX_BATCH + 1}") and "--sizes" in line


@pytest.mark.parametrize(
    ("name", "argv"),
    [
        ("goals", ["--n", str(10**12)]),
        ("throughput", ["--sizes", str(10**11)]),
        ("ik", ["--n", str(10**12)]),
        ("paper", ["--runs", str(10**11)]),
        ("many", ["--n", str(10**9), "--n-targets", "1"]),
        ("path", ["--n", str(10**12)]),
        ("path", ["--waypoints", str(10**9)]),
    ],
)
def test_python_m_bench_module_refuses_the_same(name: str, argv: list[str], tmp_path) -> None:
    """``python -m swarm_ik.bench.NAME`` checks the same caps before its ``run``: one line on
    stderr and exit 2 (the refusal raised through ``main``: a traceback and exit 1)."""
    import subprocess
    import sys

    _module(name)
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", f"swarm_ik.bench.{name}", *argv, "--out", str(out)],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and re.search(r"must be a count from \d+ to \d+ ", lines[0]), lines
    assert not out.exists()


def test_bench_ik_help_lists_the_default_peers_with_commas() -> None:
    """``swarm-ik bench ik --help``: the default peers separated by commas (they ran together
    as "among swarm ik-solver dls ...")."""
    from swarm_ik.bench import plans

    text = " ".join(_bench_parsers()["ik"].format_help().split())
    assert "among " + ", ".join(plans.IK_PEERS) + ";" in text.replace("- ", "-")


def test_a_quick_bench_run_still_works(tmp_path: Path, capsys) -> None:
    """A small ``bench many`` size through the whole command (the check passes small values
    on to real work): ``--n 2 --n-targets 1`` on one arm."""
    pytest.importorskip("eaik")
    from swarm_ik.cli import main

    out = tmp_path / "many"
    argv = ["bench", "many", "--n", "2", "--n-targets", "1", "--arms", "ur5", "--out", str(out)]
    assert main(argv) == 0, capsys.readouterr().err
    assert (out / "many.csv").exists()


def test_a_ctrl_c_in_python_m_bench_path_is_one_line(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """``python -m swarm_ik.bench.path`` printed a 25-line traceback on Ctrl-C; it is one
    line and exit 130, as ``swarm-ik bench``."""
    import signal
    import subprocess
    import sys
    import time

    proc = subprocess.Popen(
        [sys.executable, "-m", "swarm_ik.bench.path", "--n", "50", "--out", str(tmp_path / "p")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    time.sleep(4.0)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and err.strip().endswith(
        "python -m swarm_ik.bench.path: interrupted"
    )
