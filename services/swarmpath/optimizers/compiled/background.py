"""The background compile that backend "auto" starts for the pieces a cold cache lacks
(:func:`swarmpath.optimizers.compiled.ready.request`).

``python -m swarmpath.optimizers.compiled.background kind:name ...``: at the lowest CPU priority
(nice 19 and, on Linux, ``SCHED_IDLE``: it takes only CPU time nothing else wants), it makes the
pieces ready as the install's warm-up does (:func:`.warm.warm`, ``cold_only``: a piece marked
since, by any process, is skipped) and marks each one. It takes none of the pieces' locks: a
worker slot warming at the same time would otherwise wait for a piece this process compiles
at idle priority (at worst, one piece is compiled by both). It inherits the tree's background
lock from the process that started it (an open file, locked): held until it exits, so that one
such process runs at a time.
"""

from __future__ import annotations

import argparse
import os
import sys


def _lower_priority() -> None:
    try:
        os.nice(19)
    except OSError:
        pass
    idle = getattr(os, "SCHED_IDLE", None)
    if idle is not None:
        try:
            os.sched_setscheduler(0, idle, os.sched_param(0))
        except OSError:
            pass


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="swarmpath-background-compile")
    parser.add_argument("pieces", nargs="+", help="kind:name, as compiled.warm.pieces lists them")
    args = parser.parse_args(argv)
    _lower_priority()
    wanted = [tuple(p.split(":", 1)) for p in args.pieces]
    from swarmpath.optimizers.compiled.warm import warm

    done = warm([name for kind, name in wanted if kind == "algorithm"],
                [name for kind, name in wanted if kind == "function"],
                maps=("map", "clearance") in wanted, cold_only=True)
    print(f"compiled {len(done)} of {len(wanted)} pieces in {sum(w.seconds for w in done):.1f} s "
          "of CPU", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
