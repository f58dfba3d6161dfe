"""Re-export of :mod:`swarmpath.parallel` (where the process pool lives: outside the ``cli``
package, so that its children import neither typer nor the commands)."""

from swarmpath.parallel import MAX_JOBS, PROGRESS_SECONDS, run_tasks, usable_cpus

__all__ = ["MAX_JOBS", "PROGRESS_SECONDS", "run_tasks", "usable_cpus"]
