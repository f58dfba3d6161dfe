#!/usr/bin/env python3
"""evosax's PSO per run on F1 (30 dims, 30 particles, 500 iterations): the Table 2 budget.

Runs in its own throwaway environment (evosax and JAX are not swarmpath dependencies):

    python3 -m venv /tmp/evo && /tmp/evo/bin/pip install evosax
    /tmp/evo/bin/python scripts/bench/evosax_pso.py [--runs 30] [--repeats 3]

The runs are one jitted program: ``jax.lax.scan`` over the iterations inside ``jax.vmap`` over the
runs' keys (evosax's ask/tell, F1 written in jax.numpy). Compilation is done first and not
timed; CPU seconds of the process (all XLA threads) / runs are reported, best of ``--repeats``.

Variant differences from swarmpath's PSO (docs/algorithms.md, PSO): evosax 0.3 draws r1, r2 once
per particle (not per component: 30x fewer uniforms), keeps the inertia constant (0.75; swarmpath
0.9 -> 0.2) with c1 = 1.5, c2 = 2 (swarmpath 2, 2), has no velocity clamp and no box handling
(the initial population is drawn in the box here; swarmpath's particles outside are not
evaluated). The work per iteration is otherwise the same: a velocity and position update and one
evaluation per particle.
"""

from __future__ import annotations

import argparse
import os
import time

import jax
import jax.numpy as jnp
from evosax.algorithms import PSO

DIM, AGENTS, ITERATIONS, BOUND = 30, 30, 500, 100.0


def make(runs: int):  # type: ignore[no-untyped-def]
    strategy = PSO(population_size=AGENTS, solution=jnp.zeros(DIM))
    params = strategy.default_params

    def one_run(key):  # type: ignore[no-untyped-def]
        key, k_pop, k_init = jax.random.split(key, 3)
        population = jax.random.uniform(k_pop, (AGENTS, DIM), minval=-BOUND, maxval=BOUND)
        fitness = jnp.sum(population * population, axis=1)
        state = strategy.init(k_init, population, fitness, params)

        def step(carry, _):  # type: ignore[no-untyped-def]
            key, state = carry
            key, k_ask, k_tell = jax.random.split(key, 3)
            x, state = strategy.ask(k_ask, state, params)
            f = jnp.sum(x * x, axis=1)
            state, _ = strategy.tell(k_tell, x, f, state, params)
            return (key, state), state.best_fitness

        _, curve = jax.lax.scan(step, (key, state), None, length=ITERATIONS)
        return curve[-1]

    return jax.jit(jax.vmap(one_run))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=30)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    solve = make(args.runs)
    keys = jax.random.split(jax.random.PRNGKey(1), args.runs)
    best = solve(keys).block_until_ready()  # compile
    cpu = wall = float("inf")
    for _ in range(args.repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        best = solve(keys).block_until_ready()
        cpu = min(cpu, time.process_time() - c0)
        wall = min(wall, time.perf_counter() - w0)
    print(f"evosax PSO, F1 {DIM} dims, {AGENTS} particles, {ITERATIONS} iterations, "
          f"{args.runs} runs: {cpu / args.runs * 1e3:.2f} CPU ms per run, "
          f"{wall / args.runs * 1e3:.2f} wall ms per run; best fitness median "
          f"{float(jnp.median(best)):.3g} (jax {jax.__version__}, {jax.devices()[0].platform}, "
          f"load average {os.getloadavg()[0]:.2f})")


if __name__ == "__main__":
    main()
