"""``swarmpath plugins``: every optimizer, function, suite and planner, where it comes from and
the digest of its code (built-ins included: a plugin is listed exactly like them)."""

from __future__ import annotations

import json
import sys
from typing import Annotated, Any

import typer

from swarmpath.cli.core import InputError, app


def _params(defaults: dict[str, Any], choices: dict[str, list[str]]) -> str:
    parts = []
    for key, value in defaults.items():
        allowed = choices.get(key)
        parts.append(f"{key}={value}" + (f" ({'|'.join(allowed)})" if allowed else ""))
    return ", ".join(parts)


@app.command()
def plugins(
    kind: Annotated[
        str | None,
        typer.Option("--kind", "-k", help="Only this kind: optimizer, function, suite, planner."),
    ] = None,
    only_plugins: Annotated[
        bool, typer.Option("--only-plugins", help="Leave the built-ins out.")
    ] = False,
    as_json: Annotated[
        bool, typer.Option("--json", help="One JSON document: every row in full.")
    ] = False,
) -> None:
    """List every extension: kind, name, source (built-in, distribution and version, or file),
    the sha256 digest of its code, and its parameters' defaults and choices. Installed plugins
    come from entry points (groups swarmpath.optimizers, swarmpath.functions,
    swarmpath.planners); quick ones from --plugin or SWARMPATH_PLUGINS (docs/extending.md)."""
    from swarmpath.plugins.catalog import KINDS, extensions, problems

    if kind is not None and kind not in KINDS:
        raise InputError("--kind", f"must be one of {', '.join(KINDS)}, got {kind!r}")
    rows = extensions((kind,) if kind else KINDS, builtin=False if only_plugins else None)
    broken = problems()
    if as_json:
        doc = {"extensions": [r.to_dict() for r in rows], "problems": broken}
        sys.stdout.write(json.dumps(doc) + "\n")
        return
    width = max([len(r.name) for r in rows] + [4])
    origin = max([len(r.origin) for r in rows] + [6])
    typer.echo(f"{'kind':<9} {'name':<{width}} {'source':<{origin}} {'digest':<12} parameters")
    for r in rows:
        typer.echo(f"{r.kind:<9} {r.name:<{width}} {r.origin:<{origin}} {r.short_digest:<12} "
                   f"{_params(r.defaults, r.choices)}".rstrip())
    for p in broken:
        typer.echo(f"left out: {p['group']} entry point {p['name']!r} of {p['origin']}: "
                   f"{p['message']}", err=True)
