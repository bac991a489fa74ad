import subprocess
import sys

import pytest

from sandbox.cli import build_parser, main


def _commands():
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    return sorted(sub.choices)


def test_expected_commands_exist():
    assert {"demo", "bench"} <= set(_commands())


@pytest.mark.parametrize("command", _commands())
def test_every_subcommand_has_help(command, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main([command, "--help"])
    assert exit_info.value.code == 0
    assert "usage:" in capsys.readouterr().out


def test_no_command_prints_help(capsys):
    assert main([]) == 2
    assert "COMMAND" in capsys.readouterr().out


def test_bad_input_is_a_clear_error(capsys):
    assert main(["bench", "--repeats", "0"]) == 2
    assert "expected a positive integer" in capsys.readouterr().err


def test_module_entry_point_runs():
    out = subprocess.run([sys.executable, "-m", "sandbox", "--version"], capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip()
