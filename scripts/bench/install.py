"""The test extras' install into a new venv, by pip and by uv, side by side: what
``scripts/_venv.sh`` does on a fresh clone before anything else (wall and CPU seconds).

    python3 scripts/bench/install.py --pairs 2

Each pair creates two new venvs in a temporary directory, in turn (the first tool alternates):
``pip install -e .[test]`` (pip's default: bytecode compiled at install) and ``pip install uv``
followed by ``uv pip install -e .[test]`` (no bytecode at install: written at first import,
scripts/_venv.sh unsets PYTHONDONTWRITEBYTECODE). Both read their own download caches, warm
after the first pair (on a fresh machine both download every wheel once). The venv's creation is
timed apart: it is the same for both. Prints one markdown row per install and whether both
installed the same distributions (``pip freeze``, uv itself left out).
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def timed(cmd: list[str]) -> tuple[float, float]:
    """Run ``cmd`` (check it), return its wall and CPU seconds (its process tree, reaped)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def freeze(python: Path) -> list[str]:
    out = subprocess.run([str(python), "-m", "pip", "freeze"], check=True, text=True,
                         capture_output=True).stdout
    return sorted(line for line in out.splitlines()
                  if not line.startswith(("uv ", "uv==", "uv @", "swarmpath", "-e ")))


def install(tool: str, venv: Path) -> tuple[float, float, float]:
    """A new venv at ``venv`` and the test extras installed by ``tool``: (venv s, wall, CPU)."""
    venv_wall, _ = timed([sys.executable, "-m", "venv", str(venv)])
    python = venv / "bin" / "python"
    spec = f"{REPO}[test]"
    if tool == "pip":
        wall, cpu = timed([str(python), "-m", "pip", "install", "--quiet", "-e", spec])
    else:
        w1, c1 = timed([str(python), "-m", "pip", "install", "--quiet", "uv"])
        w2, c2 = timed([str(venv / "bin" / "uv"), "pip", "install", "--quiet",
                        "--python", str(python), "-e", spec])
        wall, cpu = w1 + w2, c1 + c2
    return venv_wall, wall, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pairs", type=int, default=2)
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    print("| pair | tool | venv s | install wall s | install CPU s |")
    print("| ---: | --- | ---: | ---: | ---: |")
    same = []
    for pair in range(1, args.pairs + 1):
        with tempfile.TemporaryDirectory(prefix="swarmpath-install-") as tmp:
            frozen = {}
            for tool in ("pip", "uv") if pair % 2 else ("uv", "pip"):  # alternating
                venv = Path(tmp) / tool
                v, wall, cpu = install(tool, venv)
                frozen[tool] = freeze(venv / "bin" / "python")
                print(f"| {pair} | {tool} | {v:.1f} | {wall:.1f} | {cpu:.1f} |", flush=True)
            same.append(frozen["pip"] == frozen["uv"])
    print(f"\nload average after: {os.getloadavg()[0]:.2f}; the same distributions and versions "
          f"in every pair: {all(same)}")


if __name__ == "__main__":
    main()
