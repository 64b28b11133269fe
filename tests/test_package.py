"""The package's public face: every subpackage is reachable from ``import armctl`` alone, the heavy ones load
only when first used, and the old import paths still work for one release, with a DeprecationWarning."""

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
    "name",
    [
        "controllers",
        "errors",
        "models",
        "planning",
        "references",
        "sim",
        "dynamics",
        "model",
        "tuning",
        "scenes",
        "bench",
    ],
)
def test_subpackage_attribute(name: str) -> None:
    assert getattr(armctl, name).__name__ == f"armctl.{name}"
    assert name in dir(armctl)


def test_unknown_attribute_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'tunning'"):
        armctl.tunning  # noqa: B018


def test_tuning_sweep_is_a_deprecated_alias_of_sim_sweep() -> None:
    from armctl.sim import sweep

    with pytest.warns(DeprecationWarning, match=r"armctl\.tuning\.sweep is deprecated.*armctl\.sim\.sweep"):
        alias = armctl.tuning.sweep
    assert alias is sweep
    assert "sweep" not in armctl.tuning.__all__  # one public home
    with pytest.raises(AttributeError, match="no attribute 'sweeps'"):
        armctl.tuning.sweeps  # noqa: B018


def test_old_reference_module_is_a_deprecated_alias() -> None:
    """``armctl.reference`` (now :mod:`armctl.references`) still imports, warns, and gives the same class; run in
    a fresh interpreter, where the module has not been imported yet."""
    code = (
        "import warnings\n"
        "warnings.simplefilter('error', DeprecationWarning)\n"
        "import armctl\n"  # the package itself does not import the old path
        "try:\n"
        "    import armctl.reference\n"
        "except DeprecationWarning as w:\n"
        "    print('warned:', w)\n"
        "warnings.simplefilter('ignore', DeprecationWarning)\n"
        "from armctl.reference import Reference\n"
        "print(Reference is armctl.Reference is armctl.references.Reference)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0].startswith("warned: armctl.reference is deprecated") and "armctl.references" in out[0]
    assert out[1] == "True"


def test_builtin_arms_are_defined_once_and_reached_both_ways() -> None:
    """``armctl.models`` (the built-in arms) and ``armctl.model.library`` (where they are defined) give the same
    functions; ``armctl.model`` (the parts) is another module."""
    from armctl.model import library

    for name in armctl.models.__all__:
        assert getattr(armctl.models, name) is getattr(library, name)
    assert armctl.models.panda.__module__ == "armctl.model.library"
    assert armctl.model.RobotModel is armctl.RobotModel and not hasattr(armctl.model, "panda")
