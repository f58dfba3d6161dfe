"""A snippet of Python run in a new interpreter, for what only a fresh process shows (which
modules a command or a service's start imports)."""

from __future__ import annotations

import subprocess
import sys


def last_line(code: str, timeout: float = 120.0) -> str:
    """The last line ``code`` printed, run by this venv's python in a new process (it must exit
    0: CalledProcessError otherwise)."""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=timeout, check=True)
    return out.stdout.strip().splitlines()[-1]
