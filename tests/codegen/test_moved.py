"""The old import paths of the code-generation modules still work for one release, and say where they moved."""

from __future__ import annotations

import importlib
import sys

import pytest


@pytest.mark.parametrize(
    ("old", "new", "name"),
    [
        ("armctl.dynamics.codegen", "armctl.codegen.library", "cached"),
        ("armctl.dynamics.codegen", "armctl.codegen.toolchain", "compiler"),
        ("armctl.dynamics.library_cache", "armctl.codegen.library_cache", "clean_stale"),
    ],
)
def test_the_old_path_warns_and_gives_the_same_objects(old: str, new: str, name: str) -> None:
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=f"{old} moved to {new.rsplit('.', 1)[0]}"):
        module = importlib.import_module(old)
    assert getattr(module, name) is getattr(importlib.import_module(new), name)


def test_compiled_dynamics_is_a_deprecated_name_of_the_pinocchio_backend() -> None:
    import armctl
    from armctl.dynamics.pinocchio_backend import PinocchioDynamics

    with pytest.warns(DeprecationWarning, match="CompiledDynamics is deprecated"):
        from armctl.dynamics.compiled import CompiledDynamics
    assert CompiledDynamics is PinocchioDynamics
    assert isinstance(armctl.Dynamics(armctl.models.pendulum()), CompiledDynamics)
