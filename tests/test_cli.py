"""The command line's basic calls: ``armctl --version`` and a bare ``armctl`` (the subcommands' own checks are in
test_scene_cli_result_checks.py and tests/bench)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _project_version() -> str:
    """The version pyproject.toml declares: the package's metadata, read without importing armctl."""
    if sys.version_info >= (3, 11):
        import tomllib
    else:  # pragma: no cover
        import tomli as tomllib

    return str(tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"])


def _armctl(*args: str) -> subprocess.CompletedProcess[str]:
    """``python -m armctl.cli ARGS`` in a fresh process, with this checkout's source first on the path."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])}
    return subprocess.run(
        [sys.executable, "-m", "armctl.cli", *args], capture_output=True, text=True, env=env, timeout=120, check=False
    )


def test_version_prints_the_projects_version_and_exits_0() -> None:
    proc = _armctl("--version")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"armctl {_project_version()}"


def test_the_package_version_is_the_projects() -> None:
    import armctl

    assert armctl.__version__ == _project_version()


def test_bare_armctl_prints_help_and_exits_0() -> None:
    proc = _armctl()
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("usage: armctl")
    for command in ("bench", "demo", "--version"):
        assert command in proc.stdout
    assert "required" not in proc.stdout + proc.stderr


def test_main_without_arguments_returns_0(capsys: pytest.CaptureFixture[str]) -> None:
    from armctl.cli import main

    assert main([]) == 0
    assert "usage: armctl" in capsys.readouterr().out


def test_an_unknown_command_is_a_usage_error(capsys: pytest.CaptureFixture[str]) -> None:
    from armctl.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["frobnicate"])
    assert exc.value.code == 2
    assert "invalid choice: 'frobnicate'" in capsys.readouterr().err
