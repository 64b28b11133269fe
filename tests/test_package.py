"""The package's public face: every subpackage of the documented layout is reachable from ``import armctl`` alone, and
the heavy ones load only when first used."""

from __future__ import annotations

import subprocess
import sys

import pytest

import armctl


def test_import_is_light_and_every_subpackage_is_reachable() -> None:
    code = (
        "import sys, armctl\n"
        "heavy = ('control', 'matplotlib', 'casadi', 'armctl.tuning', 'armctl.scenes', 'armctl.bench')\n"
        "print(sorted(m for m in heavy if m in sys.modules))\n"
        "print(armctl.tuning.linearize.__name__, armctl.scenes.__name__, armctl.bench.__name__)\n"
        "print('armctl.tuning' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0] == "[]"  # nothing heavy at import
    assert out[1] == "linearize armctl.scenes armctl.bench"  # reachable as attributes, without an import
    assert out[2] == "True"  # loaded on first use


@pytest.mark.parametrize(
    "name", ["controllers", "errors", "models", "planning", "sim", "dynamics", "model", "tuning", "scenes", "bench"]
)
def test_subpackage_attribute(name: str) -> None:
    assert getattr(armctl, name).__name__ == f"armctl.{name}"
    assert name in dir(armctl)


def test_unknown_attribute_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'tunning'"):
        armctl.tunning  # noqa: B018


def test_sweep_is_where_the_design_puts_it_too() -> None:
    from armctl.sim import sweep

    assert armctl.tuning.sweep is sweep  # the documented layout: tuning/ (python-control, sweeps)
