"""The paper benchmark: CSV schema, resume after interruption, statistics, verdicts, report."""

from __future__ import annotations

import argparse
import csv
import importlib
import math
import pickle
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from conftest import never

import swarm_ik
from swarm_ik import cli
from swarm_ik.bench import common, paper, plans, published, runner, solve_runs
from swarm_ik.bench.common import judge, summarize
from swarm_ik.bench.plans import RunSpec
from swarm_ik.bench.report import Comparison, Headline, render_comparison
from swarm_ik.bench.solve_runs import RUN_FIELDS
from swarm_ik.cli import BENCHMARKS
from swarm_ik.errors import InvalidArgumentError, UnknownNameError


def execute(specs, out, **kw):
    """The runner with the optimiser-run worker and schema (as ``bench paper`` calls it)."""
    worker = kw.pop("worker", solve_runs.run_one)
    kw.setdefault("initializer", None)
    return runner.execute(specs, out, worker, solve_runs.SCHEMA, **kw)


def read_rows(path):
    return runner.read_rows(path, solve_runs.SCHEMA)


def tiny_specs(n: int = 5, experiment: str = "t-func") -> list[RunSpec]:
    """``n`` GWO runs on Hartmann-3 with 6 wolves and 8 iterations (milliseconds each)."""
    return [
        RunSpec(experiment, "F4", "min", "gwo", seed, "function", None, 6, 8) for seed in range(n)
    ]


def ik_spec(get_robot, solver: str = "dls", seed: int = 0) -> RunSpec:
    robot = get_robot("yumi_left")
    target = robot.fk(np.array([0.3, -0.8, 0.4, 0.6, -0.5, 1.2, 0.7]))
    return RunSpec(
        "t-ik",
        "yumi_left",
        "pose0",
        solver,
        seed,
        "se3",
        tuple(float(v) for v in target.ravel()),
        iterations=60,
        max_evals=60,
    )


def comparable(rows: list[dict]) -> dict[str, tuple]:
    """Rows by key without the wall-clock time (the only non-deterministic column)."""
    return {r["key"]: tuple(r[f] for f in RUN_FIELDS if f != "time_s") for r in rows}


# --------------------------------------------------------------------------- CSV schema
def test_csv_schema_one_typed_row_per_run(tmp_path: Path) -> None:
    specs = tiny_specs(4)
    summary = execute(specs, tmp_path, jobs=1, progress=False)
    assert (summary.total, summary.new, summary.skipped, summary.interrupted) == (4, 4, 0, False)
    path = runner.csv_path(tmp_path, "t-func")
    with open(path, newline="") as fh:
        raw = list(csv.reader(fh))
    assert tuple(raw[0]) == RUN_FIELDS
    assert len(raw) == 1 + 4
    rows = read_rows(path)
    assert sorted(r["key"] for r in rows) == sorted(s.key for s in specs)
    f4 = swarm_ik.testfunctions.FUNCTIONS["F4"]
    for r in rows:
        assert isinstance(r["seed"], int) and isinstance(r["n_evals"], int)
        assert isinstance(r["success"], bool) and r["within_limits"] is True
        assert r["pop_size"] == 6 and r["iterations"] == 8 and r["max_evals"] is None
        assert r["n_evals"] == 6 * 8
        assert math.isnan(r["position_error"]) and math.isnan(r["rotation_error"])
        assert r["fitness"] >= f4.f_min - 1e-5
        assert r["success"] == (r["fitness"] - f4.f_min <= solve_runs.FUNCTION_SUCCESS_GAP)
    hist = runner.read_histories(runner.history_path(tmp_path, "t-func"))
    assert set(hist) == {s.key for s in specs}
    for r in rows:
        h = hist[r["key"]]
        assert h["n_iter"] == 8 and h["n_evals"] == 48
        f = np.array(h["f"], dtype=float)
        assert np.all(np.diff(f) <= 0)  # best-so-far never increases
        assert f[-1] == pytest.approx(r["fitness"], rel=1e-4)


def test_ik_row_errors_are_pinocchio_checked(tmp_path: Path, get_robot) -> None:
    spec = ik_spec(get_robot)
    outcome = solve_runs.run_one(spec)
    row = outcome.rows[0]
    assert set(row) == set(RUN_FIELDS)
    robot = get_robot("yumi_left")
    problem = swarm_ik.IKProblem(robot, np.array(spec.target).reshape(4, 4))
    res = swarm_ik.solve(problem, "dls", seed=0, iterations=60, max_evals=60, stop_on_success=False)
    assert row["fitness"] == res.fitness
    assert row["position_error"] == res.position_error
    assert row["success"] == (
        row["position_error"] <= 1e-5 and row["rotation_error"] <= 1e-5 and row["within_limits"]
    )
    assert row["n_evals"] <= 60
    assert outcome.history is not None and outcome.history["n_iter"] == len(res.history)


def test_keys_distinguish_settings() -> None:
    a = RunSpec("e", "F1", "min", "gwo", 0, "function", None, 30, 200)
    assert a.key != RunSpec("e", "F1", "min", "gwo", 0, "function", None, 30, 100).key
    assert a.key != RunSpec("e", "F1", "min", "gwo", 1, "function", None, 30, 200).key
    assert a.key != RunSpec("e", "F1", "min", "mgwo", 0, "function", None, 30, 200).key
    with pytest.raises(InvalidArgumentError, match="duplicate"):
        execute([a, a], Path("/nonexistent"), progress=False)


def test_compact_history_keeps_last_point_and_bounds_size() -> None:
    h = np.geomspace(1.0, 1e-12, 1000)
    c = solve_runs.compact_history(h, 100_000, max_points=50)
    assert len(c["it"]) == len(c["f"]) <= 50
    assert c["it"][0] == 0 and c["it"][-1] == 999
    assert c["f"][-1] == pytest.approx(1e-12, rel=1e-4)
    assert solve_runs.compact_history([np.inf, 1.0], 2)["f"] == [None, 1.0]


# --------------------------------------------------------------------------- resume
class _Interrupt:
    """A worker that raises KeyboardInterrupt on its ``k``-th call (a Ctrl-C mid-run)."""

    def __init__(self, k: int) -> None:
        self.k, self.calls = k, 0

    def __call__(self, spec: RunSpec) -> runner.Outcome:
        self.calls += 1
        if self.calls == self.k:
            raise KeyboardInterrupt
        return solve_runs.run_one(spec)


def test_resume_after_keyboard_interrupt(tmp_path: Path) -> None:
    specs = tiny_specs(6)
    first = execute(specs, tmp_path / "a", jobs=1, progress=False, worker=_Interrupt(4))
    assert first.interrupted and first.new == 3
    assert len(read_rows(runner.csv_path(tmp_path / "a", "t-func"))) == 3
    calls: list[str] = []

    def counting(spec: RunSpec) -> runner.Outcome:
        calls.append(spec.key)
        return solve_runs.run_one(spec)

    second = execute(specs, tmp_path / "a", jobs=1, progress=False, worker=counting)
    assert (second.skipped, second.new, second.interrupted) == (3, 3, False)
    assert calls == [s.key for s in specs[3:]]  # finished runs are not redone
    resumed = read_rows(runner.csv_path(tmp_path / "a", "t-func"))
    execute(specs, tmp_path / "b", jobs=1, progress=False)
    straight = read_rows(runner.csv_path(tmp_path / "b", "t-func"))
    assert comparable(resumed) == comparable(straight)
    assert len(runner.read_histories(runner.history_path(tmp_path / "a", "t-func"))) == 6


def test_resume_after_killed_process(tmp_path: Path) -> None:
    specs = tiny_specs(5)
    (tmp_path / "specs.pkl").write_bytes(pickle.dumps(specs))
    script = tmp_path / "killed.py"
    script.write_text(
        textwrap.dedent(f"""
        import os, pickle, signal
        from swarm_ik.bench import runner, solve_runs

        specs = pickle.loads(open({str(tmp_path / "specs.pkl")!r}, "rb").read())
        calls = [0]

        def worker(spec):
            calls[0] += 1
            if calls[0] == 3:
                os.kill(os.getpid(), signal.SIGKILL)
            return solve_runs.run_one(spec)

        runner.execute(specs, {str(tmp_path / "out")!r}, worker, solve_runs.SCHEMA, jobs=1,
                       progress=False)
    """)
    )
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, timeout=120)
    assert proc.returncode == -9, proc.stderr.decode()
    path = runner.csv_path(tmp_path / "out", "t-func")
    before = read_rows(path)
    assert len(before) == 2
    with open(path, "a") as fh:  # and a row torn in the middle of its write
        fh.write("t-func|F4|torn,t-func,F4")
    assert len(read_rows(path)) == 2
    summary = execute(specs, tmp_path / "out", jobs=1, progress=False)
    assert (summary.skipped, summary.new) == (2, 3)
    after = read_rows(path)
    assert sorted(r["key"] for r in after) == sorted(s.key for s in specs)
    assert "torn" not in path.read_text()
    assert {k: v for k, v in comparable(after).items() if k in comparable(before)} == comparable(
        before
    )


def test_results_do_not_depend_on_jobs(tmp_path: Path) -> None:
    specs = tiny_specs(4)
    execute(specs, tmp_path / "one", jobs=1, progress=False)
    s2 = execute(specs, tmp_path / "two", jobs=2, progress=False, initializer=None)
    assert s2.new == 4
    one = read_rows(runner.csv_path(tmp_path / "one", "t-func"))
    two = read_rows(runner.csv_path(tmp_path / "two", "t-func"))
    assert comparable(one) == comparable(two)


# --------------------------------------------------------------------------- statistics
def test_summarize_uses_population_std() -> None:
    st = summarize([4.0, 1.0, 3.0, 2.0])
    assert (st.n, st.best, st.worst, st.mean, st.median) == (4, 1.0, 4.0, 2.5, 2.5)
    assert st.var == pytest.approx(1.25)  # ddof = 0; ddof = 1 would give 5/3
    assert st.std == pytest.approx(math.sqrt(1.25))
    assert st.get("worst") == 4.0
    with pytest.raises(InvalidArgumentError, match="valid"):
        st.get("max")
    with pytest.raises(InvalidArgumentError):
        summarize([])
    assert common.success_rate([True, False, True, True]) == 0.75
    assert math.isnan(common.success_rate([]))


def test_verdict_rule() -> None:
    assert judge(5.3, 5.27).label == "reproduced"
    assert judge(0.05, 0.43).label == "same order"  # factor 8.6: not reproduced
    assert judge(0.0618, 0.0122).text == "same order (ratio 5.07)"
    assert judge(0.3, 0.43).label == "reproduced"  # within a factor 2
    assert judge(0.04, 0.43).label == "better"
    worse = judge(2.2, 0.0122, why_worse="unreachable")
    assert worse.label == "worse" and "unreachable" in worse.text and worse.reason == "unreachable"
    assert "cause not identified" in judge(1.0, 1e-3).text
    # both at machine precision: equal under the IK floor, very different without it
    assert judge(7.6e-16, 4.04e-16, floor=1e-12).label == "reproduced"
    assert judge(1e-10, 4.04e-16, floor=1e-12).label == "worse"
    # negative minimum (Hartmann-3): distances to f_min, at the printed resolution
    fmin = published.HARTMANN3_MIN
    assert judge(-3.86244, -3.8628, f_min=fmin, floor=5e-5).label == "same order"  # ×6.8
    assert judge(-3.86278, -3.8628, f_min=fmin, floor=5e-5).label == "reproduced"
    assert judge(-3.8609, -3.8628, f_min=fmin, floor=5e-5).label == "worse"
    assert judge(-3.8628, -3.8609, f_min=fmin, floor=5e-5).label == "better"


def _rows(solver: str, values: list[float], **extra) -> list[dict]:
    return [
        {
            "key": f"{solver}{i}",
            "solver": solver,
            "fitness": v,
            "success": False,
            "position_error": 1.0,
            **extra,
        }
        for i, v in enumerate(values)
    ]


def test_report_puts_published_numbers_beside_ours() -> None:
    table = published.P000_TABLE2
    rows = (
        _rows("foa", [5.2, 5.3, 5.4])
        + _rows("hlfoa", [1e-15, 2e-15, 3e-16])
        + _rows("dls", [1e-16])
    )
    hl = Headline()
    md = render_comparison(
        Comparison("t", lambda r: True, ("foa", "hlfoa", "dls"), table, floor=1e-12),
        rows,
        hl,
        "exp",
    )
    head = next(line for line in md.splitlines() if line.startswith("| algorithm"))
    cols = [c.strip() for c in head.strip("|").split("|")]
    assert cols.index("mean (paper)") == cols.index("mean (ours)") + 1
    foa = next(line for line in md.splitlines() if line.startswith("| FOA"))
    assert "| 5.3 | 5.27 |" in foa and "reproduced" in foa  # mean 5.3 beside the paper's 5.27
    assert "reproduced" in next(line for line in md.splitlines() if line.startswith("| HLFOA"))
    assert "no published number" in next(line for line in md.splitlines() if "`dls`" in line)
    sfoa = next(line for line in md.splitlines() if line.startswith("| SFOA"))
    assert "published only" in sfoa and "6.94" in sfoa  # (the paper's 6.93508)
    assert [r[2] for r in hl.rows] == ["FOA", "HLFOA"]


def test_unattainable_published_value_is_worse_with_reason() -> None:
    rows = _rows("gwo", [2.2, 2.3])
    comp = Comparison(
        "t",
        lambda r: True,
        ("gwo",),
        published.P003_TABLE4,
        stats=("mean", "best"),
        attainable=2.1,
        why_worse=lambda s, st: "unreachable within the stated limits",
    )
    line = next(x for x in render_comparison(comp, rows).splitlines() if "`gwo`" in x)
    assert "worse" in line and "unreachable" in line  # ratio 5.2 alone would say reproduced


# --------------------------------------------------------------------------- experiments
def test_paper_targets(get_robot) -> None:
    robot = get_robot("yumi_left")
    printed = plans.printed_target()
    problem = swarm_ik.IKProblem(robot, printed, "paper-l1", orth_tol=1e-4)
    assert np.array_equal(problem.target, printed)  # kept as printed, not projected
    q = np.asarray(paper.Q_EXACT)
    assert robot.within_limits(q)
    assert np.allclose(np.rad2deg(q), published.P000_Q_PRINTED_DEG, atol=0.1)
    floor, q_floor = paper.printed_floor()
    assert 1e-5 < floor < 1.6e-5  # the rounding floor of the printed pose
    assert robot.within_limits(np.asarray(q_floor))
    assert float(problem.fitness(q[None])[0]) < 1.6e-5
    exact = swarm_ik.IKProblem(robot, plans.exact_target(), "paper-l1")
    assert float(exact.fitness(q[None])[0]) < 1e-14
    x = np.asarray(published.P003_X_STAR)
    for name in ("loading_manipulator", "loading_manipulator_long"):
        assert not get_robot(name).within_limits(x)  # x* violates the limits of both


def test_configs_and_specs() -> None:
    full, quick = paper.FULL, paper.QUICK
    assert (full.pop_000, full.iterations_000, full.runs_000) == (100, 1000, 10)
    assert (full.pop_003, full.iterations_003, full.runs_003) == (30, 200, 50)
    specs = paper.specs_000_table2(quick)
    assert len({s.key for s in specs}) == len(specs)
    assert {s.target_id for s in specs} == {"printed", "exact"}
    assert all(not s.stop_on_success for s in specs)
    full_keys = {s.key for s in paper.specs_000_table2(full)}
    assert not full_keys & {s.key for s in specs}  # quick rows never pass for full ones
    budget = paper.specs_budget(quick)
    for s in budget:
        assert s.stop_on_success and s.max_evals in quick.budgets
        if s.solver == "dls":
            assert s.iterations == s.max_evals
    assert paper.QUICK.with_runs(2).runs_003 == 2
    with pytest.raises(InvalidArgumentError):
        paper.QUICK.with_runs(0)


def test_cli_runs_an_experiment_and_writes_report(tmp_path: Path) -> None:
    from swarm_ik.cli import main

    argv = [
        "bench",
        "paper",
        "--quick",
        "--experiments",
        "003-table3",
        "--runs",
        "1",
        "--jobs",
        "1",
        "--out",
        str(tmp_path),
        "--no-progress",
    ]
    assert main(argv) == 0
    rows = read_rows(runner.csv_path(tmp_path, "003-table3"))
    assert len(rows) == 4 * 2  # F1..F4 x {gwo, mgwo}
    report = (tmp_path / "report.md").read_text()
    assert "QUICK run" in report and "Table 3" in report and "| GWO (`gwo`)" in report
    pytest.importorskip("matplotlib")
    assert (tmp_path / "convergence_003-table3.png").stat().st_size > 10_000
    assert (tmp_path / "box_003-table3.png").stat().st_size > 10_000
    assert main(argv) == 0  # rerun: resumes, nothing new
    assert len(read_rows(runner.csv_path(tmp_path, "003-table3"))) == 8


@pytest.mark.parametrize("experiment", ["000-table2", "000-table4"])
def test_the_quick_run_of_each_ik_experiment_of_the_printed_target_ends(
    experiment: str, tmp_path: Path
) -> None:
    """[HLFOA]'s experiments solve its printed (rounded) target: the pin check before the
    search refused it, and ``bench paper --quick`` exited 2."""
    from swarm_ik.cli import main

    argv = ["bench", "paper", "--quick", "--experiments", experiment, "--runs", "1", "--jobs",
            "1", "--out", str(tmp_path), "--no-progress"]  # fmt: skip
    assert main(argv) == 0
    assert read_rows(runner.csv_path(tmp_path, experiment))


def test_unknown_experiment_lists_valid_ones(tmp_path: Path) -> None:
    import argparse

    parser = argparse.ArgumentParser()
    paper.add_arguments(parser)
    args = parser.parse_args(["--experiments", "table9", "--out", str(tmp_path)])
    with pytest.raises(UnknownNameError, match="000-table2"):
        paper.run(args)


# --------------------------------------------------------------------------- plots
def test_resample_is_a_step_function_of_the_stored_points() -> None:
    from swarm_ik.bench import plots

    x, f = plots.run_curve({"n_iter": 4, "n_evals": 40, "it": [0, 1, 3], "f": [3.0, None, 1.0]})
    assert x.tolist() == [10.0, 20.0, 40.0] and np.isnan(f[1])
    out = plots.resample(
        [(np.array([1.0, 2.0, 3.0]), np.array([3.0, 2.0, 1.0]))],
        np.array([0.5, 1.0, 2.5, 3.0, 4.0]),
    )
    assert np.isnan(out[0, 0]) and out[0, 1:].tolist() == [3.0, 2.0, 1.0, 1.0]


def test_missing_matplotlib_is_reported_by_name(monkeypatch, tmp_path: Path) -> None:
    from swarm_ik.bench import plots

    monkeypatch.setitem(sys.modules, "matplotlib.figure", None)  # import fails
    with pytest.raises(plots.PlotExtraMissingError, match=r"swarm_ik\[plot\]"):
        plots.boxes(tmp_path / "x.png", _rows("gwo", [1.0]), [("p", lambda r: True, 0.0)], ["gwo"])


# --------------------------------------------------------------------------- --scheduler (Dask)
@pytest.fixture(scope="module")
def dask_client():
    """An embedded LocalCluster of two worker processes, shared by the Dask tests below."""
    pytest.importorskip("distributed")
    from swarm_ik import distributed

    with distributed.connect("local", n_workers=2) as client:
        yield client


def test_execute_on_dask_equals_the_inline_run_and_resumes(
    tmp_path: Path, get_robot, dask_client
) -> None:
    specs = tiny_specs(5) + [
        ik_spec(get_robot, s, seed) for s in ("dls", "swarm") for seed in (0, 1)
    ]
    execute(specs, tmp_path / "ref", jobs=1, progress=False)
    # batches of 2 runs (1 per worker); the 8th run fails on its worker: the 3 batches before
    # it are on disk, the batch holding it is lost, nothing after it ran
    bad = RunSpec("t-func", "F4", "min", "no-such-solver", 0, "function", None, 6, 8)
    with pytest.raises(UnknownNameError, match="no-such-solver"):
        execute(
            specs[:7] + [bad] + specs[7:],
            tmp_path / "dask",
            progress=False,
            client=dask_client,
            batch_per_worker=1,
        )
    done = {
        r["key"]
        for e in ("t-func", "t-ik")
        for r in read_rows(runner.csv_path(tmp_path / "dask", e))
    }
    assert done == {s.key for s in specs[:6]}
    summary = execute(
        specs, tmp_path / "dask", progress=False, client=dask_client, batch_per_worker=2
    )
    assert (summary.skipped, summary.new, summary.interrupted) == (6, 3, False)
    for e in ("t-func", "t-ik"):
        ref = read_rows(runner.csv_path(tmp_path / "ref", e))
        got = read_rows(runner.csv_path(tmp_path / "dask", e))
        assert comparable(got) == comparable(ref)
        hist_ref = runner.read_histories(runner.history_path(tmp_path / "ref", e))
        assert runner.read_histories(runner.history_path(tmp_path / "dask", e)) == hist_ref


def test_bench_paper_scheduler_option(tmp_path: Path, dask_client) -> None:
    import argparse

    parser = argparse.ArgumentParser()
    paper.add_arguments(parser)
    base = ["--quick", "--experiments", "003-table3", "--runs", "2", "--no-progress", "--no-plots"]
    assert parser.parse_args(base).scheduler == "none"  # default: the process pool
    with pytest.raises(InvalidArgumentError, match="'local'.*tcp://"):
        paper.config_from_args(parser.parse_args([*base, "--scheduler", "127.0.0.1:8786"]))
    assert paper.run(parser.parse_args([*base, "--jobs", "1", "--out", str(tmp_path / "a")])) == 0
    args = parser.parse_args([*base, "--out", str(tmp_path / "b")])
    args.scheduler = dask_client  # what --scheduler local / tcp://… connects to
    assert paper.run(args) == 0
    a = read_rows(runner.csv_path(tmp_path / "a", "003-table3"))
    b = read_rows(runner.csv_path(tmp_path / "b", "003-table3"))
    assert len(a) == 4 * 2 * 2 and comparable(a) == comparable(b)
    assert "2 Dask workers" in (tmp_path / "b" / "report.md").read_text()


# --------------------------------------------------------------------------- report prose
def _fake_rows(specs: list[RunSpec], rng: np.random.Generator) -> list[dict]:
    """One CSV-like row per spec with a random fitness (the report only reads these)."""
    return [
        {
            "key": s.key,
            "experiment": s.experiment,
            "robot": s.robot,
            "target_id": s.target_id,
            "solver": s.solver,
            "seed": s.seed,
            "fitness_name": s.fitness_name,
            "pop_size": s.pop_size,
            "iterations": s.iterations,
            "max_evals": s.max_evals,
            "fitness": float(rng.uniform(1e-3, 1.0)),
            "position_error": float(rng.uniform(1e-4, 1e-2)),
            "rotation_error": 0.0,
            "success": bool(rng.random() < 0.5),
            "within_limits": True,
            "time_s": 0.01,
            "n_evals": 10,
        }
        for s in specs
    ]


def test_every_report_section_renders_from_the_template(tmp_path: Path) -> None:
    """Each experiment's prose comes from ``templates/paper.md`` with its numbers filled in
    from the configuration and the rows: no placeholder left, the set-up sizes present."""
    from swarm_ik.bench import report

    cfg = plans.QUICK.with_runs(1)
    rng = np.random.default_rng(0)
    used: set[str] = set()
    real = report.render_block

    def spy(template: str, block: str, **kw):
        used.add(block)
        return real(template, block, **kw)

    paper.render_block = spy  # type: ignore[assignment]
    try:
        for exp in paper.EXPERIMENTS.values():
            rows = _fake_rows(exp.specs(cfg), rng)
            if exp.id == "000-table2":  # printed-pose rows at the rounding floor: the only
                for r in rows:  # rows that get its reason (block why-printed)
                    if r["target_id"] == "printed":
                        r["fitness"] = plans.printed_floor()[0]
            text = exp.section(cfg, rows, Headline(), tmp_path)
            assert "$" not in text, exp.id
            assert text.strip()
    finally:
        paper.render_block = real  # type: ignore[assignment]
    assert used == set(report.template_blocks("paper.md")) - {"report", "quick"}
    setup = report.render_block(
        "paper.md",
        "setup-003-table3",
        pop=cfg.pop_003,
        iterations=cfg.iterations_003,
        runs=cfg.runs_003,
        paper_pop=30,
        paper_iterations=200,
        paper_runs=50,
        hartmann_min=-3.86,
        f4_resolution="5e-05",
        mgwo_settings="m = 3",
    )
    assert f"{cfg.pop_003} wolves, {cfg.iterations_003} iterations" in setup
    with pytest.raises(InvalidArgumentError, match="no value for 'pop'"):
        report.render_block("paper.md", "setup-003-table3")
    with pytest.raises(InvalidArgumentError, match="its blocks: report"):
        report.render_block("paper.md", "nope")


def test_report_template_holds_no_measured_numbers() -> None:
    """Numbers with three or more significant digits (a measurement, a published value, a
    robot limit) come from the CSV, the configuration or the data modules, never the text."""
    import re

    text = (common.TEMPLATES / "paper.md").read_text()
    text = re.sub(r"`00[03]-[^`]*`|<!-- block [\w-]+ -->", "", text)  # ids, block names
    assert not re.findall(r"\d\.\d{2,}|\d{3,}", text)
    report = paper.build_report(plans.QUICK, Path("/nonexistent-bench-folder"))
    assert "QUICK run" in report and "not run yet" in report and "$" not in report
    assert f"a/b > {common.VERDICT_FACTOR:g}" in report


def test_bench_outputs_and_sizes_are_checked_before_work(tmp_path, capsys) -> None:
    """Issue 16 item 11: a file as --out and --sizes 0 exit 2 with one line."""
    from swarm_ik.cli import main

    afile = tmp_path / "afile"
    afile.write_text("")
    assert main(["bench", "ik", "--quick", "--out", str(afile)]) == 2
    assert "is a file" in capsys.readouterr().err
    assert main(["bench", "throughput", "--sizes", "0", "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err.strip()
    assert "argument --sizes: must be an integer from 1" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("name", sorted(BENCHMARKS))
def test_every_benchmark_runs_as_a_module_with_the_commands_options(name: str, capsys) -> None:
    module = importlib.import_module(cli.BENCHMARKS[name])
    with pytest.raises(SystemExit) as done:
        module.main(["--help"])  # python -m swarm_ik.bench.NAME --help
    assert done.value.code == 0
    as_module = capsys.readouterr().out
    assert as_module.startswith(f"usage: python -m {cli.BENCHMARKS[name]} ")
    with pytest.raises(SystemExit):
        cli.main(["bench", name, "--help"])
    as_command = capsys.readouterr().out
    options = set(re.findall(r"(?<![\w-])--[a-z][\w-]*", as_command))
    assert options and options == set(re.findall(r"(?<![\w-])--[a-z][\w-]*", as_module))


@pytest.mark.parametrize("name", sorted(BENCHMARKS))
def test_the_help_of_out_names_the_folder_written_with_and_without_quick(name: str) -> None:
    """``--out``'s help gives the default folder the command uses (``cli.bench._out_folder``,
    the same as common.resolve_out), and, where ``--quick`` changes it, the quick one too
    (``bench goals`` and ``bench collision`` named the full run's folder only)."""
    from swarm_ik.cli.bench import _out_folder

    parser = argparse.ArgumentParser()
    importlib.import_module(cli.BENCHMARKS[name]).add_arguments(parser)
    actions = {o: a for a in parser._actions for o in a.option_strings}
    text = str(actions["--out"].help)
    full = _out_folder(argparse.Namespace(bench=name, out=None, quick=False))
    assert f"./{full}" in text
    if "--quick" in actions:
        quick = _out_folder(argparse.Namespace(bench=name, out=None, quick=True))
        assert quick != full and f"./{quick} with --quick" in text
    else:
        assert "--quick" not in text


def test_throughput_report_gives_the_collision_free_rows_as_a_ratio_of_the_plain_batch():
    from swarm_ik.bench.throughput import box_ratios

    rows = [
        {"robot": "panda", "n": "100", "method": m, "poses_per_s": str(v)}
        for m, v in (
            ("batch-1proc", 900.0), ("boxes40-plain", 1000.0), ("boxes40-avoid-1proc", 250.0),
            ("boxes40-avoid-threads", 300.0), ("boxes40-avoid-dask", 400.0),
            ("boxes10-plain", 800.0), ("boxes10-avoid-1proc", 400.0),
        )
    ]  # fmt: skip
    text = box_ratios(rows)
    assert "| panda | 40 | 100 | 0.25 | 0.30 | 0.40 |" in text
    assert "| panda | 10 | 100 | 0.50 | – | – |" in text  # (no threads or Dask row)
    assert box_ratios(rows[:1]) == ""


@pytest.mark.parametrize("command", ["ik", "paper"])
def test_report_only_without_results_is_refused_and_writes_nothing(
    command: str, tmp_path, capsys
) -> None:
    """``--report-only`` over a folder with no results: exit 2, one line naming the folder
    and the command that makes them, and no report (it said it wrote files it had not)."""
    from swarm_ik.cli import main

    out = tmp_path / "empty"
    assert main(["bench", command, "--report-only", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "no results to report" in err
    assert f"swarm-ik bench {command} --out" in err
    assert not out.exists()


@pytest.mark.parametrize(
    "argv", [["throughput", "--robots", "nosuch"], ["many", "--arms", "nosuch"]]
)
def test_a_bad_robot_name_leaves_no_folder(argv: list[str], tmp_path, capsys) -> None:
    """A refused robot is refused before the output folder is made (a run.json left there
    changed the next run in that folder)."""
    from swarm_ik.cli import main

    out = tmp_path / "out"
    assert main(["bench", *argv, "--out", str(out)]) == 2
    assert "unknown robot 'nosuch'" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.parametrize("arm", ["panda", "yumi_left"])
def test_bench_many_refuses_an_arm_eaik_cannot_solve_before_making_the_folder(
    arm: str, tmp_path, monkeypatch, capsys
) -> None:
    """``bench many --arms`` with a 7-joint arm: exit 2, one line naming the arm and why, no
    folder and no work (the folder was made and the machine timed before the refusal)."""
    pytest.importorskip("eaik")
    from swarm_ik.bench import many
    from swarm_ik.cli import main

    monkeypatch.setattr(many, "machine_speed", never)
    out = tmp_path / "out"
    assert main(["bench", "many", "--arms", "ur5", arm, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"--arms {arm}: " in err[0] and "7 joints" in err[0]
    assert not out.exists()
    assert many.main(["--arms", arm, "--out", str(out)]) == 2  # python -m swarm_ik.bench.many
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"--arms {arm}: " in err[0]
    assert not out.exists()


def test_bench_many_checks_its_out_folder_as_the_other_benchmarks(
    tmp_path, monkeypatch, capsys
) -> None:
    """``bench many``'s --out goes through common.resolve_out, as every other benchmark's: a
    file, or a folder holding a quick run, is refused before any work, also when run as
    ``python -m swarm_ik.bench.many``."""
    from swarm_ik.bench import many

    monkeypatch.setattr(many, "machine_speed", never)
    afile = tmp_path / "afile"
    afile.write_text("")
    assert many.main(["--out", str(afile)]) == 2  # (one line, as `swarm-ik bench many`)
    assert "is a file; give a folder" in capsys.readouterr().err
    quick = tmp_path / "quick"
    common.write_run_info(quick, "many", True)
    assert many.main(["--out", str(quick)]) == 2
    assert "holds a quick run" in capsys.readouterr().err
    assert sorted(p.name for p in quick.iterdir()) == [common.RUN_INFO]
    assert "default ./bench-many)" in _help(many.main)  # (it has no --quick)


def _help(module_main) -> str:
    """What ``module_main(["--help"])`` prints."""
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), pytest.raises(SystemExit):
        module_main(["--help"])
    return buf.getvalue()


def test_unknown_names_are_listed_once() -> None:
    """A name both bundled and in example-robot-data (panda) is listed once."""
    with pytest.raises(swarm_ik.UnknownNameError) as err:
        swarm_ik.load_robot("nosuch")
    names = str(err.value).split("valid robots: ")[1].split(", ")
    assert "panda" in names and len(names) == len(set(names))
