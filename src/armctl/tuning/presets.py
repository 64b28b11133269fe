"""Tuned controller presets: TOML files in the repository's ``controllers/`` folder, one per scene and method.

A preset records the gains and how they were found::

    scene = "planar_2r"
    method = "computed_torque"
    written_by = "examples/tune_gains.py"
    how = "double pole at ω_n = 20 rad/s; sampled-data gain margin 12.4 at 1 kHz with one period of delay"
    [gains]
    kp = 400.0
    kd = 40.0

Gains are scalars or lists (a diagonal). The folder is ``$ARMCTL_PRESETS`` if set, else the presets shipped
with armctl, the package data folder ``armctl/_presets``, found through :mod:`importlib.resources` wherever armctl
is imported from. In the source repository that folder is a link to the top-level ``controllers/`` (so a source
checkout, an editable install and the tuning examples that rewrite the presets all use those files); a wheel
carries a copy of them.
"""

from __future__ import annotations

import os
import re
import sys
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from armctl.errors import InvalidParameterError, ModelLoadError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def presets_dir() -> Path:
    """Where presets are read and, by default, written.

    Returns
    -------
    Path
        ``$ARMCTL_PRESETS`` if that environment variable is set, else the folder of presets shipped with armctl
        (``armctl/_presets``, resolved: in a source checkout, the repository's ``controllers/``).
    """
    env = os.environ.get("ARMCTL_PRESETS")
    if env:
        return Path(env)
    return Path(str(resources.files("armctl") / "_presets")).resolve()


def preset_path(scene: str, method: str, folder: Path | None = None) -> Path:
    return (folder or presets_dir()) / f"{scene}.{method}.toml"


def load_preset(scene: str, method: str, folder: Path | None = None) -> dict[str, Any]:
    """The preset of ``method`` on ``scene``: a dict with ``gains`` and the tuning record."""
    path = preset_path(scene, method, folder)
    if not path.is_file():
        have = sorted(p.name for p in path.parent.glob("*.toml")) if path.parent.is_dir() else []
        raise ModelLoadError(
            f"no preset {path.name} in {path.parent} (have: {have}); run the tuning examples "
            "(examples/tune_gains.py in the source repository) to write it, or point ARMCTL_PRESETS "
            "at a folder that holds it",
            value=str(path),
        )
    try:
        with path.open("rb") as f:
            data = tomllib.load(f)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise ModelLoadError(
            f"preset {path} is not valid TOML ({e}); fix the file or write it again (examples/tune_gains.py)",
            value=str(path),
        ) from e
    if not isinstance(data.get("gains"), dict):
        raise ModelLoadError(f"preset {path} has no [gains] table", value=str(path))
    return data


#: TOML escapes for the quote, the backslash and the control characters that have a short one (others: \uXXXX)
_SHORT_ESCAPES = {"\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r", '"': '\\"', "\\": "\\\\"}
_NEEDS_ESCAPE = re.compile(r'[\x00-\x1f"\\\x7f]')
_BARE_KEY = re.compile("[A-Za-z0-9_-]+")


def _toml_string(s: str, name: str) -> str:
    """``s`` as a TOML basic string: backslash, quote and the control characters U+0000–U+001F, U+007F escaped."""
    if any("\ud800" <= c <= "\udfff" for c in s):
        raise InvalidParameterError(f"{name} holds a lone surrogate, which TOML (UTF-8) cannot store: {s!r}", value=s)
    return '"' + _NEEDS_ESCAPE.sub(lambda m: _SHORT_ESCAPES.get(m[0], f"\\u{ord(m[0]):04X}"), s) + '"'


def _toml_key(k: Any) -> str:
    if not isinstance(k, str):
        raise InvalidParameterError(f"preset keys must be strings, got {k!r}", value=k)
    return k if _BARE_KEY.fullmatch(k) else _toml_string(k, f"key {k!r}")


def _toml_value(v: Any, name: str) -> str:
    if isinstance(v, str):
        return _toml_string(v, name)
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(int(v))
    if isinstance(v, float):
        return repr(float(v))  # shortest round-trip form; nan, inf and -inf are TOML floats too
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x, name) for x in v) + "]"
    if isinstance(v, Mapping):
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(x, name)}" for k, x in v.items()) + "}"
    if hasattr(v, "tolist") and not isinstance(v, complex):  # NumPy arrays and scalars
        return _toml_value(v.tolist(), name)
    raise InvalidParameterError(
        f"{name} = {v!r}: a preset holds strings, booleans, real numbers, lists and tables, not {type(v).__name__}",
        value=v,
    )


def write_preset(
    scene: str, method: str, gains: dict[str, Any], how: str, written_by: str, folder: Path | None = None, **record: Any
) -> Path:
    """Write a preset (gains plus the tuning record) and return its path."""
    path = preset_path(scene, method, folder)
    fields = {"scene": scene, "method": method, "written_by": written_by, "how": how, **record}
    lines = [f"{_toml_key(k)} = {_toml_value(v, k)}" for k, v in fields.items()]
    lines += ["", "[gains]"] + [f"{_toml_key(k)} = {_toml_value(v, f'gains.{k}')}" for k, v in gains.items()]
    text = "\n".join(lines) + "\n"  # built (and checked) in full before the file is touched
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path
