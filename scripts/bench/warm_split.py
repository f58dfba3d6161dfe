"""The install's warm-up in one process and in two (``swarmpath warmup --if-cold --no-suites
-j N``), side by side on empty numba caches: the CPU seconds of each process. On a quiet machine
with two cores the wall time of ``-j 2`` is about the larger of its two processes' CPU.

    PYTHONPATH=services .venv/bin/python scripts/bench/warm_split.py --jobs 2,1 --pairs 1

Each measurement runs in a child process whose ``NUMBA_CACHE_DIR`` is a new empty directory
(numba reads it at import), in the order given, ``--pairs`` times.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time


def child(jobs: int) -> None:
    from swarmpath.optimizers.compiled.objectives import compiled_names
    from swarmpath.optimizers.compiled.registry import kernel_names
    from swarmpath.optimizers.compiled.warm import warm_in_processes

    names = [n for n in compiled_names() if ":" not in n]  # --no-suites
    started = time.time()
    done = warm_in_processes(kernel_names(), names, jobs=jobs, maps=True, cold_only=True)
    me = resource.getrusage(resource.RUSAGE_SELF)
    others = resource.getrusage(resource.RUSAGE_CHILDREN)
    print(json.dumps({"jobs": jobs, "pieces": len(done), "wall": time.time() - started,
                      "cpu_this": me.ru_utime + me.ru_stime,
                      "cpu_others": others.ru_utime + others.ru_stime}))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--jobs", default="2,1", help="comma-separated process counts")
    parser.add_argument("--pairs", type=int, default=1)
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child)
        return
    print("jobs  pieces  wall s  CPU s (this process + the others)  load")
    for _ in range(args.pairs):
        for jobs in (int(j) for j in args.jobs.split(",")):
            with tempfile.TemporaryDirectory(prefix="warm-split-") as cache:
                env = {**os.environ, "NUMBA_CACHE_DIR": cache}
                out = subprocess.run([sys.executable, __file__, "--child", str(jobs)], env=env,
                                     capture_output=True, text=True, check=True)
            r = json.loads(out.stdout.splitlines()[-1])
            print(f"{r['jobs']:4}  {r['pieces']:6}  {r['wall']:6.1f}  {r['cpu_this']:.1f} + "
                  f"{r['cpu_others']:.1f}  {os.getloadavg()[0]:.1f}", flush=True)


if __name__ == "__main__":
    main()
