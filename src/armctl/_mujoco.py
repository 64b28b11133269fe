"""MuJoCo, an optional dependency: imported on first use, with a clear error when it is not installed."""

from __future__ import annotations

from typing import Any

from armctl.errors import OptionalDependencyError

INSTALL = 'pip install "armctl[mujoco]"'


def require_mujoco(feature: str) -> Any:
    """The ``mujoco`` module; :class:`~armctl.errors.OptionalDependencyError` naming ``feature`` and the install
    command if it cannot be imported."""
    try:
        import mujoco
    except ImportError as exc:
        raise OptionalDependencyError(
            f"{feature} needs MuJoCo, which is not installed ({exc}); install it with {INSTALL}",
            value="mujoco",
        ) from exc
    return mujoco
