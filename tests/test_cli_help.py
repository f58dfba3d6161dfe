"""`swarmpath CMD --help` shows every option's whole help text and its default (rich markup in
help text must not eat anything, e.g. ``[default: CPU count]``)."""

import re

import pytest
import typer
from typer.testing import CliRunner

from swarmpath.cli import app

runner = CliRunner()
GROUP = typer.main.get_command(app)
COMMANDS = sorted(GROUP.commands)  # type: ignore[attr-defined]


def squeeze(text: str) -> str:
    """The text without box drawing and whitespace (help columns wrap differently)."""
    return re.sub(r"[\s│╭╮╰╯─]+", "", text)


@pytest.mark.parametrize("name", COMMANDS)
def test_help_shows_every_option_text_and_default(name):
    result = runner.invoke(app, [name, "--help"], env={"COLUMNS": "120", "TERMINAL_WIDTH": "120"})
    assert result.exit_code == 0, result.output
    shown = squeeze(result.output)
    command = GROUP.commands[name]  # type: ignore[attr-defined]
    assert squeeze(command.help or "") in shown, (name, command.help)
    checked = 0
    for param in command.params:
        if getattr(param, "hidden", False) or not getattr(param, "help", None):
            continue
        assert squeeze(param.help) in shown, (name, param.name, param.help)
        if isinstance(param.show_default, str):
            assert squeeze(f"[default: ({param.show_default})]") in shown, (name, param.name)
        elif param.default not in (None, False) and not param.is_flag and param.name != "help":
            assert squeeze(f"[default: {param.default}]") in shown, (name, param.name)
        checked += 1
    assert checked or not command.params


def test_defaults_that_are_not_values_are_spelled_out():
    shown = squeeze(runner.invoke(app, ["up", "--help"], env={"COLUMNS": "120"}).output)
    assert squeeze("[default: (CPU count)]") in shown and "[default:0]" not in shown
    shown = squeeze(runner.invoke(app, ["submit", "--help"], env={"COLUMNS": "120"}).output)
    assert squeeze("http://127.0.0.1:8000") in shown
