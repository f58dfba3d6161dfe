"""The ``swarmpath`` command line: one typer app, one module per command.

Adding a command: write ``swarmpath/cli/<name>.py`` that does ``from swarmpath.cli.core import app``
and decorates its function with ``@app.command()``, then add ``<name>`` to ``_COMMANDS`` below
(the order there is the order in ``--help``). Keep heavy imports (zenoh, ompl, fastapi, ...)
inside the command function so that every command starts fast.

Conventions shared by all commands:

* bad input -> raise :class:`swarmpath.cli.core.InputError` (``InputError("--dims", "...")``): it
  prints ``swarmpath <cmd>: error: --dims: ...`` on one line on stderr and exits with code 2; so
  do click's own usage errors (unknown option, not an integer, ...). Never a traceback.
* results go to stdout (tables, or one JSON document with ``--json``); progress and notes go to
  stderr.
"""

from __future__ import annotations

import importlib

from swarmpath.cli.core import InputError, app

__all__ = ["InputError", "app", "main"]

_COMMANDS = (
    "bench", "plan", "reproduce", "audit", "check", "processes", "service", "upload", "results",
    "plugins", "demo", "warmup",
)

for _name in _COMMANDS:
    importlib.import_module(f"swarmpath.cli.{_name}")


def main() -> None:
    """Console-script entry point (``swarmpath = swarmpath.cli:main``)."""
    app(prog_name="swarmpath")
