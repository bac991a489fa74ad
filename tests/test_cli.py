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


def test_commands_run_with_one_blas_thread_unless_the_user_chose(monkeypatch):
    from threadpoolctl import threadpool_info

    from sandbox.cli import THREAD_VARIABLES, _blas_threads

    def blas_threads():
        return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}

    for name in THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    with _blas_threads():
        assert blas_threads() == {1}
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    before = blas_threads()
    with _blas_threads():
        assert blas_threads() == before
