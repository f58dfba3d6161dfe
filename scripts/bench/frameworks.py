#!/usr/bin/env python3
"""Per-run cost of swarmpath (numpy and numba) beside mealpy, EvoX and evosax, on one budget.

    PYTHONPATH=services .venv/bin/python scripts/bench/frameworks.py \\
        --mealpy-python /tmp/cmp-mealpy/bin/python --evox-python /tmp/cmp-evox/bin/python \\
        --evosax-python /tmp/cmp-evosax/bin/python [--algorithms PSO,GWO,FDO] [--functions F1,F9]

Budget: 30 dims, 30 agents, 500 iterations, ``--runs`` runs (30) for the frameworks that batch
runs (swarmpath: one ``minimize`` call; evosax: ``jit(vmap(scan))``; EvoX: one run at a time,
its workflow is stateful) and ``--mealpy-runs`` (3) for mealpy, which solves one run at a time
in pure Python and costs about 0.5 s per run. The foreign frameworks are not swarmpath
dependencies: each runs in its own throwaway environment, given by its interpreter's path
(commands in docs/benchmarks.md); a framework whose interpreter is not given or cannot import it
is reported as "not installed", an algorithm it does not have as "no such algorithm".

Every framework runs in a subprocess of this script (``--worker NAME``) with one thread
(OMP/MKL/OpenBLAS/numba variables, XLA's Eigen pool off, ``torch.set_num_threads(1)``); the worker
compiles or warms up first (not timed), then reports CPU seconds of its process
(``time.process_time``, every thread) and wall seconds per run, best of ``--repeats`` for the
batched ones, the mean for mealpy and EvoX, plus the median final best fitness and the
evaluations per run, as one JSON line. The driver prints one markdown table with each CPU time's
ratio to swarmpath numba's on the same algorithm and function, and the machine's load average.

The workers write F1 (sphere), F9 (Rastrigin) and F10 (Ackley) in their own array library
(the foreign environments do not have swarmpath); the swarmpath workers use its registry.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from typing import Any

DIM, AGENTS, ITERATIONS = 30, 30, 500
BOUNDS = {"F1": 100.0, "F9": 5.12, "F10": 32.0}
FRAMEWORKS = ("swarmpath-numpy", "swarmpath-numba", "mealpy", "evox", "evosax")
# Which algorithms each foreign framework has, and under which name (read from their sources).
HAS = {
    "mealpy": {"PSO": "PSO.OriginalPSO", "GWO": "GWO.OriginalGWO", "FDO": "FDO.OriginalFDO"},
    "evox": {"PSO": "PSO"},
    "evosax": {"PSO": "PSO"},
}
ONE_THREAD = {
    "OMP_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "NUMBA_NUM_THREADS": "1",
    "XLA_FLAGS": "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1",
}


def note(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def median(values: list[float]) -> float:
    s = sorted(values)
    n = len(s)
    return s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2])


# ------------------------------------------------------------------------------------ workers
def work_swarmpath(backend: str, args: argparse.Namespace) -> dict[str, Any]:
    import numpy as np

    from swarmpath.optimizers import minimize

    rows = []
    for algorithm in args.algorithms:
        for function in args.functions:
            kw = dict(dim=DIM, agents=AGENTS, runs=args.runs, seed=1, backend=backend)
            minimize(algorithm, function, iterations=2, **{**kw, "runs": 1})  # compile / warm up
            cpu = wall = math.inf
            for _ in range(args.repeats):
                c0, w0 = time.process_time(), time.perf_counter()
                res = minimize(algorithm, function, iterations=ITERATIONS, **kw)
                cpu = min(cpu, time.process_time() - c0)
                wall = min(wall, time.perf_counter() - w0)
            rows.append({
                "algorithm": algorithm, "function": function, "runs": args.runs,
                "cpu": cpu / args.runs, "wall": wall / args.runs,
                "best": float(np.median(res.best_fitness)),
                "evaluations": float(np.mean(res.evaluations)),
            })
    version = f"numpy {np.__version__}"
    if backend == "numba":
        import numba

        version += f", numba {numba.__version__}"
    return {"version": version, "rows": rows}


def work_mealpy(args: argparse.Namespace) -> dict[str, Any]:
    import logging
    import warnings

    import mealpy
    import numpy as np

    logging.getLogger("mealpy").setLevel(logging.ERROR)
    objectives = {
        "F1": lambda x: float(np.dot(x, x)),
        "F9": lambda x: float(np.sum(x * x - 10.0 * np.cos(2 * np.pi * x)) + 10.0 * x.size),
        "F10": lambda x: float(
            -20.0 * np.exp(-0.2 * np.sqrt(np.mean(x * x)))
            - np.exp(np.mean(np.cos(2 * np.pi * x))) + 20.0 + np.e
        ),
    }
    rows = []
    for algorithm in args.algorithms:
        if algorithm not in HAS["mealpy"]:
            continue
        module, name = HAS["mealpy"][algorithm].split(".")
        cls = getattr(getattr(mealpy, module), name)
        for function in args.functions:
            count = [0]
            f = objectives[function]

            def objective(x: Any, f: Any = f, count: list[int] = count) -> float:
                count[0] += 1
                return float(f(x))

            b = BOUNDS[function]
            problem = {
                "bounds": mealpy.FloatVar(lb=(-b,) * DIM, ub=(b,) * DIM, name="x"),
                "minmax": "min", "obj_func": objective, "log_to": None,
            }
            cpu, wall, best = [], [], []
            for r in range(args.mealpy_runs):
                model = cls(epoch=ITERATIONS, pop_size=AGENTS)
                c0, w0 = time.process_time(), time.perf_counter()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    agent = model.solve(problem, seed=1 + r)
                cpu.append(time.process_time() - c0)
                wall.append(time.perf_counter() - w0)
                best.append(float(agent.target.fitness))
            rows.append({
                "algorithm": algorithm, "function": function, "runs": args.mealpy_runs,
                "cpu": sum(cpu) / len(cpu), "wall": sum(wall) / len(wall),
                "best": median(best), "evaluations": count[0] / args.mealpy_runs,
            })
    return {"version": f"mealpy {mealpy.__version__}, numpy {np.__version__}", "rows": rows}


def work_evosax(args: argparse.Namespace) -> dict[str, Any]:
    from importlib import metadata

    import jax
    import jax.numpy as jnp
    from evosax.algorithms import PSO

    jax.config.update("jax_enable_x64", True)  # float64, as the other frameworks
    objectives = {
        "F1": lambda x: jnp.sum(x * x, axis=-1),
        "F9": lambda x: jnp.sum(x * x - 10.0 * jnp.cos(2 * jnp.pi * x), axis=-1) + 10.0 * DIM,
        "F10": lambda x: (
            -20.0 * jnp.exp(-0.2 * jnp.sqrt(jnp.mean(x * x, axis=-1)))
            - jnp.exp(jnp.mean(jnp.cos(2 * jnp.pi * x), axis=-1)) + 20.0 + jnp.e
        ),
    }

    def solver(function: str) -> Any:
        strategy = PSO(population_size=AGENTS, solution=jnp.zeros(DIM))
        params = strategy.default_params
        f, b = objectives[function], BOUNDS[function]

        def one_run(key: Any) -> Any:
            key, k_pop, k_init = jax.random.split(key, 3)
            population = jax.random.uniform(k_pop, (AGENTS, DIM), minval=-b, maxval=b)
            state = strategy.init(k_init, population, f(population), params)

            def step(carry: Any, _: Any) -> Any:
                key, state = carry
                key, k_ask, k_tell = jax.random.split(key, 3)
                x, state = strategy.ask(k_ask, state, params)
                state, _ = strategy.tell(k_tell, x, f(x), state, params)
                return (key, state), None

            (_, state), _ = jax.lax.scan(step, (key, state), None, length=ITERATIONS)
            return state.best_fitness

        return jax.jit(jax.vmap(one_run))

    rows = []
    if "PSO" in args.algorithms:
        keys = jax.random.split(jax.random.PRNGKey(1), args.runs)
        for function in args.functions:
            solve = solver(function)
            best = solve(keys).block_until_ready()  # compile
            cpu = wall = math.inf
            for _ in range(args.repeats):
                c0, w0 = time.process_time(), time.perf_counter()
                best = solve(keys).block_until_ready()
                cpu = min(cpu, time.process_time() - c0)
                wall = min(wall, time.perf_counter() - w0)
            rows.append({
                "algorithm": "PSO", "function": function, "runs": args.runs,
                "cpu": cpu / args.runs, "wall": wall / args.runs,
                "best": float(jnp.median(best)), "evaluations": AGENTS * (ITERATIONS + 1),
            })
    version = f"evosax {metadata.version('evosax')}, jax {jax.__version__}"
    return {"version": f"{version} ({jax.devices()[0].platform})", "rows": rows}


def work_evox(args: argparse.Namespace) -> dict[str, Any]:
    from importlib import metadata

    import torch
    from evox.algorithms import PSO
    from evox.core import Problem
    from evox.workflows import StdWorkflow

    torch.set_num_threads(1)
    torch.set_num_interop_threads(1)
    objectives = {
        "F1": lambda x: torch.sum(x * x, dim=-1),
        "F9": lambda x: torch.sum(x * x - 10.0 * torch.cos(2 * math.pi * x), dim=-1) + 10.0 * DIM,
        "F10": lambda x: (
            -20.0 * torch.exp(-0.2 * torch.sqrt(torch.mean(x * x, dim=-1)))
            - torch.exp(torch.mean(torch.cos(2 * math.pi * x), dim=-1)) + 20.0 + math.e
        ),
    }

    class Objective(Problem):
        def __init__(self, f: Any) -> None:
            super().__init__()
            self.f = f

        def evaluate(self, pop: Any) -> Any:
            return self.f(pop)

    def one_run(function: str, seed: int, iterations: int) -> float:
        torch.manual_seed(seed)
        b = BOUNDS[function]
        lb = torch.full((DIM,), -b, dtype=torch.float64)
        algorithm = PSO(pop_size=AGENTS, lb=lb, ub=-lb)
        workflow = StdWorkflow(algorithm, Objective(objectives[function]))
        workflow.init_step()  # evaluates the initial swarm
        for _ in range(iterations):  # each step moves and evaluates the swarm
            workflow.step()
        # a step takes the previous evaluation into its bests before it moves: the last one too
        return float(min(algorithm.global_best_fit, algorithm.fit.min()))

    torch.set_default_dtype(torch.float64)
    rows = []
    if "PSO" in args.algorithms:
        for function in args.functions:
            one_run(function, 0, 3)  # warm up
            cpu, wall, best = [], [], []
            for r in range(args.evox_runs):
                c0, w0 = time.process_time(), time.perf_counter()
                best.append(one_run(function, 1 + r, ITERATIONS))
                cpu.append(time.process_time() - c0)
                wall.append(time.perf_counter() - w0)
            rows.append({
                "algorithm": "PSO", "function": function, "runs": args.evox_runs,
                "cpu": sum(cpu) / len(cpu), "wall": sum(wall) / len(wall),
                "best": median(best), "evaluations": AGENTS * (ITERATIONS + 1),
            })
    version = f"evox {metadata.version('evox')}, torch {torch.__version__} (cpu)"
    return {"version": version, "rows": rows}


def worker(args: argparse.Namespace) -> None:
    name = args.worker
    if name.startswith("swarmpath-"):
        out = work_swarmpath(name.split("-", 1)[1], args)
    else:
        out = {"mealpy": work_mealpy, "evosax": work_evosax, "evox": work_evox}[name](args)
    print(json.dumps(out))


# ------------------------------------------------------------------------------------- driver
def run_worker(name: str, python: str | None, args: argparse.Namespace) -> dict[str, Any]:
    if python is None:
        return {"error": "not installed (no interpreter given)"}
    if not os.path.exists(python):
        return {"error": f"not installed ({python} does not exist)"}
    cmd = [
        python, os.path.abspath(__file__), "--worker", name,
        "--algorithms", ",".join(args.algorithms), "--functions", ",".join(args.functions),
        "--runs", str(args.runs), "--mealpy-runs", str(args.mealpy_runs),
        "--evox-runs", str(args.evox_runs), "--repeats", str(args.repeats),
    ]
    note(f"{name}: {' '.join(cmd)}")
    proc = subprocess.run(cmd, env={**os.environ, **ONE_THREAD}, capture_output=True, text=True)
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["?"])[-1]
        if "ModuleNotFoundError" in last or "ImportError" in last:
            return {"error": f"not installed ({last})"}
        return {"error": f"failed: {last}"}
    return dict(json.loads(proc.stdout.strip().splitlines()[-1]))


def table(results: dict[str, dict[str, Any]], args: argparse.Namespace) -> list[str]:
    lines = [
        f"{DIM} dims, {AGENTS} agents, {ITERATIONS} iterations; CPU and wall ms per run, one "
        "thread per framework; CPU / numba: the framework's CPU ms over swarmpath numba's on "
        "the same algorithm and function.",
        "",
        "| algorithm | function | framework | runs | CPU ms/run | wall ms/run | CPU / numba "
        "| median best | evaluations/run |",
        "| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for algorithm in args.algorithms:
        for function in args.functions:
            rows = {}
            for name, res in results.items():
                for row in res.get("rows", []):
                    if row["algorithm"] == algorithm and row["function"] == function:
                        rows[name] = row
            ref = rows.get("swarmpath-numba")
            for name in FRAMEWORKS:
                head = f"| {algorithm} | {function} | {name}"
                if "error" in results[name]:
                    lines.append(f"{head} | | | | | | {results[name]['error']} |")
                elif name not in rows:
                    lines.append(f"{head} | | | | | | no such algorithm |")
                else:
                    r = rows[name]
                    ratio = f"{r['cpu'] / ref['cpu']:.2f}x" if ref else ""
                    lines.append(
                        f"{head} | {r['runs']} | {r['cpu'] * 1e3:.2f} | {r['wall'] * 1e3:.2f} | "
                        f"{ratio} | {r['best']:.3g} | {r['evaluations']:.0f} |"
                    )
    lines.append("")
    for name in FRAMEWORKS:
        lines.append(f"- {name}: {results[name].get('version', results[name].get('error'))}")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--algorithms", default="PSO,GWO,FDO")
    ap.add_argument("--functions", default="F1,F9,F10")
    ap.add_argument("--runs", type=int, default=30, help="runs of the batching frameworks")
    ap.add_argument("--mealpy-runs", type=int, default=3)
    ap.add_argument("--evox-runs", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=2, help="timed repeats of a batch (best)")
    ap.add_argument("--mealpy-python")
    ap.add_argument("--evox-python")
    ap.add_argument("--evosax-python")
    ap.add_argument("--worker", choices=FRAMEWORKS, help=argparse.SUPPRESS)
    args = ap.parse_args()
    args.algorithms = args.algorithms.split(",")
    args.functions = args.functions.split(",")
    unknown = [f for f in args.functions if f not in BOUNDS]
    if unknown:
        ap.error(f"--functions: {', '.join(unknown)} not written for the foreign frameworks "
                 f"(choose from {', '.join(BOUNDS)})")
    if args.worker:
        worker(args)
        return
    pythons = {
        "swarmpath-numpy": sys.executable, "swarmpath-numba": sys.executable,
        "mealpy": args.mealpy_python, "evox": args.evox_python, "evosax": args.evosax_python,
    }
    load0 = os.getloadavg()
    results = {name: run_worker(name, pythons[name], args) for name in FRAMEWORKS}
    load1 = os.getloadavg()
    print("\n".join(table(results, args)))
    print(f"\nLoad average (1 min) {load0[0]:.2f} at the start, {load1[0]:.2f} at the end, "
          f"on {os.cpu_count()} CPUs.")


if __name__ == "__main__":
    main()
