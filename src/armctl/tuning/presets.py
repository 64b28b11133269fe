"""Tuned controller presets: TOML files in the repository's ``controllers/`` folder, one per scene and method.

A preset records the gains and how they were found::

    scene = "planar_2r"
    method = "computed_torque"
    written_by = "examples/tune_gains.py"
    how = "double pole at ω_n = 20 rad/s; sampled-data gain margin 12.4 at 1 kHz with one period of delay"
    [gains]
    kp = 400.0
    kd = 40.0

Gains are scalars or lists (a diagonal). The folder is ``$ARMCTL_PRESETS`` if set, else ``controllers/`` at the
root of the source checkout armctl runs from.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any

from armctl.errors import ModelLoadError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def presets_dir() -> Path:
    env = os.environ.get("ARMCTL_PRESETS")
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[3] / "controllers"


def preset_path(scene: str, method: str, folder: Path | None = None) -> Path:
    return (folder or presets_dir()) / f"{scene}.{method}.toml"


def load_preset(scene: str, method: str, folder: Path | None = None) -> dict[str, Any]:
    """The preset of ``method`` on ``scene``: a dict with ``gains`` and the tuning record."""
    path = preset_path(scene, method, folder)
    if not path.is_file():
        have = sorted(p.name for p in path.parent.glob("*.toml")) if path.parent.is_dir() else []
        raise ModelLoadError(f"no preset {path.name} in {path.parent} (have: {have}); run the tuning examples "
                             "(examples/tune_gains.py) to write it", value=str(path))
    with path.open("rb") as f:
        data = tomllib.load(f)
    if "gains" not in data:
        raise ModelLoadError(f"preset {path} has no [gains] table", value=str(path))
    return data


def _toml_value(v: Any) -> str:
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if hasattr(v, "tolist"):
        return _toml_value(v.tolist())
    return repr(float(v)) if isinstance(v, float) else str(v)


def write_preset(scene: str, method: str, gains: dict[str, Any], how: str, written_by: str,
                 folder: Path | None = None, **record: Any) -> Path:
    """Write a preset (gains plus the tuning record) and return its path."""
    path = preset_path(scene, method, folder)
    path.parent.mkdir(parents=True, exist_ok=True)
    lines = [f"scene = {_toml_value(scene)}", f"method = {_toml_value(method)}",
             f"written_by = {_toml_value(written_by)}", f"how = {_toml_value(how)}"]
    lines += [f"{k} = {_toml_value(v)}" for k, v in record.items()]
    lines += ["", "[gains]"] + [f"{k} = {_toml_value(v)}" for k, v in gains.items()]
    path.write_text("\n".join(lines) + "\n")
    return path
