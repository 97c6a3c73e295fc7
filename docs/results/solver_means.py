"""Mean fitness over 10 runs per solver on F1-F4 (30 x 200) and on the YuMi target FK(q*).

Run: ``python docs/results/solver_means.py > docs/results/solver_means.md`` (about 10 s on 2
cores).  The paper benchmark (``swarm-ik bench paper``) covers the published set-ups; this
script fills in the solvers it does not run.
"""

from concurrent.futures import ProcessPoolExecutor

import numpy as np

import swarm_ik
from swarm_ik.testfunctions import FUNCTIONS

SOLVERS = [
    "foa",
    "hlfoa",
    "hlfoa-batch",
    "gwo",
    "mgwo",
    "pso",
    "pso-improved",
    "pso-adaptive",
    "cs",
]


def f_run(args):
    s, fk, seed = args
    fn = FUNCTIONS[fk]
    lo, hi = fn.bounds
    r = swarm_ik.minimize(
        fn.function, lo, hi, s, seed=seed, pop_size=30, iterations=200, max_evals=6030
    )
    return s, fk, r.fun


def yumi_run(args):
    s, seed = args
    r = swarm_ik.load_robot("yumi_left")
    q = np.deg2rad([-135.4, -99.5, 13.8, 97.9, -70.8, 188.3, 166.4])
    p = swarm_ik.IKProblem.from_q(r, q, "paper-l1")
    res = swarm_ik.solve(p, s, seed=seed, max_evals=100100, stop_on_success=False)
    return s, res.fitness


if __name__ == "__main__":
    jobs = [(s, fk, seed) for s in SOLVERS for fk in FUNCTIONS for seed in range(10)]
    with ProcessPoolExecutor(2) as ex:
        out = list(ex.map(f_run, jobs, chunksize=8))
        y = list(
            ex.map(
                yumi_run,
                [
                    (s, seed)
                    for s in ["hlfoa-batch", "pso-improved", "pso-adaptive", "cs", "cs-newton"]
                    for seed in range(10)
                ],
            )
        )
    print("# Mean fitness per solver (10 runs)\n")
    print("F1-F4: population 30, 200 iterations (6030 evaluations).\n")
    print("| solver | F1 | F2 | F3 | F4 |")
    print("|---|---|---|---|---|")
    for s in SOLVERS:
        vals = [np.mean([v for (a, b, v) in out if a == s and b == fk]) for fk in FUNCTIONS]
        print(f"| {s} | " + " | ".join(f"{v:.6g}" for v in vals) + " |")
    print("\nYuMi left arm, target FK(q*), fitness paper-l1, 100,100 evaluations, full budget:\n")
    for s in ["hlfoa-batch", "pso-improved", "pso-adaptive", "cs", "cs-newton"]:
        v = [f for (a, f) in y if a == s]
        print(
            f"- {s}: YuMi FK(q*) mean {np.mean(v):.3g}, best {np.min(v):.3g}, worst {np.max(v):.3g}"
        )
