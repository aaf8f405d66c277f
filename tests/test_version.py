"""`rocketdrl-ma --version` and ``rocketdrl_ma.__version__`` are the installed distribution's version (the wheel's
is checked against pyproject.toml in test_packaging)."""
from importlib.metadata import version

import pytest

import rocketdrl_ma
from rocketdrl_ma.cli import main


def test_the_command_line_prints_the_installed_version(capsys):
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    assert capsys.readouterr().out == f"rocketdrl-ma {version('rocketdrl-ma')}\n"
    assert rocketdrl_ma.__version__ == version("rocketdrl-ma")
