"""The typer app every command module registers on, and the one-line error convention."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Annotated, Any

import typer
from typer.core import TyperGroup

from swarmpath import __version__

# click's exception classes as this typer uses them (recent typers vendor click as typer._click,
# older ones use click itself): found through the one typer exports.
_CLICK_ERRORS = {c.__name__: c for c in typer.BadParameter.__mro__}
ClickException: type[Exception] = _CLICK_ERRORS["ClickException"]
UsageError: type[Exception] = _CLICK_ERRORS["UsageError"]

EXIT_USAGE = 2


class InputError(ValueError):
    """Bad user input, raised by a command (or the pure functions it calls) naming the option.

    Printed as ``swarmpath <cmd>: error: <field>: <message>`` on one line on stderr; exit code 2.
    """

    def __init__(self, field: str, message: str):
        super().__init__(f"{field}: {message}")
        self.field = field
        self.detail = message


class InputErrors(InputError):
    """Several problems at once (a job spec the coordinator refused, a scenario file): printed as
    one line per problem, each naming its field; exit code 2."""

    def __init__(self, problems: Sequence[tuple[str, str]]):
        self.problems = list(problems)
        super().__init__(*self.problems[0])


class CommandFailed(RuntimeError):
    """A command that could not do its work although the input was fine (coordinator unreachable,
    job still running, unauthorized): ``swarmpath <cmd>: error: <message>`` on stderr, exit 1."""


def resolve_names(spec: str, registered: Sequence[str], option: str, kind: str) -> list[str]:
    """'ICOOT,coot' -> registered names (case-insensitive, duplicates dropped); 'all' = all."""
    if spec.strip().lower() == "all":
        return list(registered)
    by_lower = {name.lower(): name for name in registered}
    out: list[str] = []
    for part in (p.strip() for p in spec.split(",")):
        if not part:
            continue
        name = part if part in registered else by_lower.get(part.lower())
        if name is None:
            from swarmpath.names import did_you_mean

            valid = ", ".join(registered) or "none"
            hint = did_you_mean(part, registered)
            raise InputError(option, f"unknown {kind} {part!r}{hint}; registered: {valid}")
        if name not in out:
            out.append(name)
    if not out:
        raise InputError(option, f"no {kind} given")
    return out


def parse_params_option(
    text: str | None,
    names: Sequence[str],
    names_option: str,
    example: str,
    check: Callable[[str, dict[str, Any]], object],
) -> dict[str, dict[str, Any]]:
    """``--params`` JSON ``{name: {param: value}}`` for names given in ``names_option``.

    ``check(name, values)`` validates one entry (the algorithm's or planner's own
    ``resolve_params``); its ValueError becomes an error naming ``--params``.
    """
    if text is None or not text.strip():
        return {}
    try:
        raw = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError("--params", f"not valid JSON: {exc.msg} (column {exc.colno})") from None
    if not isinstance(raw, dict):
        raise InputError("--params", f"must be a JSON object like {example}")
    by_lower = {n.lower(): n for n in names}
    out: dict[str, dict[str, Any]] = {}
    for key, values in raw.items():
        name = key if key in names else by_lower.get(str(key).lower())
        if name is None:
            raise InputError(
                "--params", f"{key!r} is not one of {names_option} ({', '.join(names)})"
            )
        if not isinstance(values, dict):
            raise InputError("--params", f"{key}: parameters must be a JSON object")
        try:
            check(name, values)
        except ValueError as exc:
            raise InputError("--params", str(exc)) from None
        out[name] = dict(values)
    return out


def plot_dir(path: Path, option: str) -> Path:
    """Create the output directory of ``--plot`` (or ``-o``); InputError naming the option."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(option, f"cannot create {str(path)!r}: {exc.strerror}") from None
    if not path.is_dir():
        raise InputError(option, f"{str(path)!r} is not a directory")
    return path


def error_line(path: str, message: str) -> str:
    one_line = " ".join(message.split())
    return f"{path}: {typer.style('error', fg='red', bold=True)}: {one_line}"


def load_plugins_option(specs: list[str] | None) -> None:
    """``--plugin`` (every command): load each plugin, and the ``SWARMPATH_PLUGINS`` ones, before
    the command reads any name; add them to this process's ``SWARMPATH_PLUGINS`` so that the
    processes it starts (``-j`` children, ``up``'s workers and their slots) load them too."""
    from swarmpath.plugins import (
        ENV,
        ExtensionClash,
        PluginError,
        export,
        load_plugin,
        load_plugins,
    )

    try:
        load_plugins()
    except (PluginError, ExtensionClash) as exc:
        raise InputError(ENV, str(exc).removeprefix(f"{ENV}: ")) from None
    for spec in specs or ():
        try:
            load_plugin(spec)
        except (PluginError, ExtensionClash) as exc:
            raise InputError("--plugin", str(exc).removeprefix("--plugin: ")) from None
    export(specs or ())


def _plugin_option() -> Any:
    """The ``--plugin`` option as typer builds it (one parameter object, added to every command
    by :class:`_Group`)."""
    probe = typer.Typer()

    @probe.command()
    def _probe(
        plugin: Annotated[
            list[str] | None,
            typer.Option(
                "--plugin", metavar="MODULE_OR_FILE.py", is_eager=True, expose_value=False,
                callback=load_plugins_option,
                help="Load a plugin (a Python file or an importable module) first; repeatable. "
                "Its optimizers, functions and planners are usable by name (docs/extending.md).",
            ),
        ] = None,
    ) -> None:
        return None

    @probe.command()
    def _other() -> None:  # two commands, so that typer builds a group
        return None

    group = typer.main.get_command(probe)
    return next(iter(group.commands.values())).params[0]  # type: ignore[attr-defined]


class _Group(TyperGroup):
    """Typer's group, except that errors in the user's input are one line on stderr (exit 2)
    instead of a rich panel or a traceback, and every command takes ``--plugin``."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        option = _plugin_option()
        for command in self.commands.values():
            if not any(p.name == option.name for p in command.params):
                command.params.append(option)

    def invoke(self, ctx: Any) -> Any:
        from swarmpath.plugins import ExtensionClash, PluginError

        try:
            try:
                return super().invoke(ctx)
            except (ExtensionClash, PluginError) as exc:  # an installed plugin's, on first use
                raise InputError("plugins", str(exc)) from None
        except InputError as exc:
            path = " ".join(p for p in (ctx.command_path, ctx.invoked_subcommand) if p)
            for field, message in getattr(exc, "problems", [(exc.field, exc.detail)]):
                typer.echo(error_line(path, f"{field}: {message}"), err=True)
            raise typer.Exit(EXIT_USAGE) from None
        except CommandFailed as exc:
            path = " ".join(p for p in (ctx.command_path, ctx.invoked_subcommand) if p)
            typer.echo(error_line(path, str(exc)), err=True)
            raise typer.Exit(1) from None

    def main(  # type: ignore[override]
        self,
        args: Sequence[str] | None = None,
        prog_name: str | None = None,
        complete_var: str | None = None,
        standalone_mode: bool = True,
        **extra: Any,
    ) -> Any:
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, False, **extra)
        try:
            # Non-standalone, typer returns the code of typer.Exit (and ctx.exit) instead of
            # calling sys.exit, and lets click's usage errors through to be printed here.
            rv = super().main(args, prog_name, complete_var, False, **extra)
        except ClickException as exc:
            if type(exc).__name__ == "NoArgsIsHelpError":  # bare `swarmpath`: help, as click does
                exc.show()  # type: ignore[attr-defined]
            else:
                ctx = getattr(exc, "ctx", None)
                path = ctx.command_path if ctx is not None else (prog_name or "swarmpath")
                message = exc.format_message()  # type: ignore[attr-defined]
                if isinstance(exc, UsageError):
                    message += f" (see '{path} --help')"
                typer.echo(error_line(path, message), err=True)
            sys.exit(exc.exit_code)  # type: ignore[attr-defined]
        except typer.Abort:
            typer.echo("Aborted!", err=True)
            sys.exit(1)
        sys.exit(rv if isinstance(rv, int) else 0)


app = typer.Typer(
    cls=_Group,
    name="swarmpath",
    help="Swarm optimizers and robot path planners, run as reproducible studies.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_show_locals=False,
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"swarmpath {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_version, is_eager=True, help="Print the version."),
    ] = False,
) -> None:
    """Swarm optimizers and robot path planners, run as reproducible studies."""
