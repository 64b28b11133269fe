"""Presets: whatever write_preset accepts, load_preset reads back unchanged; a file that is not a preset raises an
ArmctlError naming it."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.errors import ArmctlError, InvalidParameterError, ModelLoadError
from armctl.tuning.presets import load_preset, write_preset

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

AWKWARD = [
    "line1\nline2",
    "tab\there",
    "ctrl\x01char",
    "nul\x00",
    "del\x7f",
    "esc\x1b[0m",
    "\r\n",
    "\b\f",
    'say "hi"',
    "'single'",
    '"""',
    "back\\slash",
    "\\u0041 is not A",
    "\\",
    "trailing\\",
    "ω_n = 20 rad/s",
    "🤖",
    "",
    " ",
    "é\u0301",
    "\u2028",
    "\ufeff",
    "#not a comment",
    "a = b",
    "[gains]",
]


@pytest.mark.parametrize("text", AWKWARD)
def test_awkward_strings_round_trip(tmp_path: Path, text: str) -> None:
    write_preset("s", "m", {"kp": 1.0}, how=text, written_by=text, folder=tmp_path, note=text)
    back = load_preset("s", "m", tmp_path)
    assert back["how"] == text and back["written_by"] == text and back["note"] == text


def test_values_round_trip(tmp_path: Path) -> None:
    gains = {
        "kp": np.array([1.5, 2.0, 1e-300, 1.7976931348623157e308]),
        "kd": np.float64(0.1),
        "n": np.int64(3),
        "flag": np.bool_(True),
        "m": np.eye(2),
        "k i": [1, 2.5],
        "a.b": -0.0,
        "": 7,
    }
    write_preset(
        "s",
        "m",
        gains,
        "how",
        "me",
        tmp_path,
        gain_margin=math.inf,
        lost=-math.inf,
        nested={"x": [1, "y"]},
        flags=(True, False),
    )
    back = load_preset("s", "m", tmp_path)
    assert back["gains"] == {
        "kp": [1.5, 2.0, 1e-300, 1.7976931348623157e308],
        "kd": 0.1,
        "n": 3,
        "flag": True,
        "m": [[1.0, 0.0], [0.0, 1.0]],
        "k i": [1, 2.5],
        "a.b": 0.0,
        "": 7,
    }
    assert math.copysign(1.0, back["gains"]["a.b"]) == -1.0
    assert back["gain_margin"] == math.inf and back["lost"] == -math.inf
    assert back["nested"] == {"x": [1, "y"]} and back["flags"] == [True, False]
    write_preset("s", "nan", {"kp": math.nan}, "how", "me", tmp_path)
    assert math.isnan(load_preset("s", "nan", tmp_path)["gains"]["kp"])


NUMBERS = (
    st.lists(st.floats(allow_nan=False), max_size=4)
    | st.integers(-(2**63), 2**63 - 1)
    | st.floats(allow_nan=False)
    | st.booleans()
)


@settings(max_examples=200, deadline=None)
@given(how=st.text(), key=st.text(), value=st.text(), gains=st.dictionaries(st.text(), NUMBERS, max_size=4))
def test_any_string_and_number_round_trips(how: str, key: str, value: str, gains: dict) -> None:  # type: ignore[type-arg]
    # a record key may not repeat a parameter of write_preset
    record = {} if key in {"scene", "method", "gains", "how", "written_by", "folder"} else {key: value}
    with tempfile.TemporaryDirectory() as folder:
        write_preset("scene", "method", gains, how, "hypothesis", Path(folder), **record)
        back = load_preset("scene", "method", Path(folder))
    assert back["how"] == how and back["gains"] == gains
    assert all(back[k] == v for k, v in record.items())


@pytest.mark.parametrize(
    "content",
    [
        b'how = "line1\nline2"\n[gains]\nkp = 1.0\n',
        b"[gains\n",
        b"kp = = 1\n",
        b'how = "\xff\xfe"\n[gains]\n',
        b"gains = 3\n",
        b'scene = "s"\n',
    ],
)
def test_malformed_file_raises_armctl_error_naming_it(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "s.m.toml"
    path.write_bytes(content)
    with pytest.raises(ModelLoadError, match=str(path).replace(".", r"\.")) as info:
        load_preset("s", "m", tmp_path)
    assert isinstance(info.value, ArmctlError) and info.value.value == str(path)


@pytest.mark.parametrize(
    ("gains", "record", "named"),
    [
        ({"kp": None}, {}, "gains.kp"),
        ({"kp": 1 + 2j}, {}, "gains.kp"),
        ({"kp": np.array([1j])}, {}, "gains.kp"),
        ({"kp": 1.0}, {"when": object()}, "when"),
        ({"kp": 1.0}, {"note": "lone \ud800"}, "note"),
        ({1: 1.0}, {}, "1"),
    ],
)
def test_value_toml_cannot_hold_raises_and_leaves_the_file(
    tmp_path: Path,
    gains: dict,
    record: dict,  # type: ignore[type-arg]
    named: str,
) -> None:
    write_preset("s", "m", {"kp": 2.0}, "before", "me", tmp_path)
    with pytest.raises(InvalidParameterError, match=named):
        write_preset("s", "m", gains, "after", "me", tmp_path, **record)
    assert load_preset("s", "m", tmp_path)["how"] == "before"


REPO = Path(__file__).resolve().parents[2]


def _read_toml(path: Path) -> dict[str, Any]:
    with path.open("rb") as f:
        return tomllib.load(f)


def test_presets_folder_is_the_package_data_or_armctl_presets(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """The presets shipped with armctl (in a source checkout: the repository's controllers/, through the link
    armctl/_presets) unless $ARMCTL_PRESETS names another folder; each shipped file loads as it reads."""
    from armctl.tuning.presets import presets_dir

    monkeypatch.delenv("ARMCTL_PRESETS", raising=False)
    assert presets_dir() == (REPO / "controllers").resolve()
    files = sorted((REPO / "controllers").glob("*.toml"))
    assert len(files) >= 17
    for f in files:
        scene, method = f.name.removesuffix(".toml").split(".")
        assert load_preset(scene, method) == _read_toml(f)
    monkeypatch.setenv("ARMCTL_PRESETS", str(tmp_path / "mine"))
    assert presets_dir() == tmp_path / "mine"
    with pytest.raises(ModelLoadError, match=r"no preset s\.m\.toml in .*mine.*ARMCTL_PRESETS"):
        load_preset("s", "m")


# run in a fresh interpreter that sees only the armctl under test: the folder given first on sys.path (a target
# dir holding a wheel's files, or the site dir of an editable install), none of the other armctl checkouts
_PROBE = """
import json, os, site, sys
where = sys.argv[1]
before = set(sys.path)
site.addsitedir(where)  # a target dir; for an editable install, runs its .pth
added = [p for p in sys.path if p not in before]
others = [p for p in sys.path if p not in added and not os.path.isdir(os.path.join(p or ".", "armctl"))]
sys.path[:] = added + others
import armctl
from armctl.tuning.presets import load_preset, presets_dir, write_preset
print(json.dumps({
    "armctl": armctl.__file__,
    "folder": str(presets_dir()),
    "preset": load_preset("planar_2r", "computed_torque"),
    "written": str(write_preset("s", "m", {"kp": 1.0}, "probe", "test")) if len(sys.argv) > 2 else None,
}))
"""


def _probe(where: Path, *write: str) -> dict[str, Any]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "ARMCTL_PRESETS")}
    out = subprocess.run(
        [sys.executable, "-c", _PROBE, str(where), *write], capture_output=True, text=True, env=env, cwd=where
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.splitlines()[-1])  # type: ignore[no-any-return]


def _pip(*args: str) -> None:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    out = subprocess.run([sys.executable, "-m", "pip", "-q", *args], capture_output=True, text=True, env=env)
    assert out.returncode == 0, out.stdout + out.stderr


@pytest.mark.slow
def test_presets_load_from_a_wheel_and_from_an_editable_install(tmp_path: Path) -> None:
    """Built as a user builds it (``pip wheel . --no-deps``) and installed into a target dir, armctl reads the
    presets from its own package data; installed editable (``pip install -e``), from the repository's
    controllers/, where write_preset also writes. Both against the repository's TOML files read here."""
    source = tmp_path / "source"
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info", "build")
    shutil.copytree(REPO / "src", source / "src", symlinks=True, ignore=ignore)
    shutil.copytree(REPO / "controllers", source / "controllers")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(REPO / name, source / name)
    expected = _read_toml(REPO / "controllers" / "planar_2r.computed_torque.toml")

    _pip("wheel", str(source), "-w", str(tmp_path / "dist"), "--no-deps")
    (wheel,) = (tmp_path / "dist").glob("armctl-*.whl")
    with zipfile.ZipFile(wheel) as z:
        shipped = sorted(n.removeprefix("armctl/_presets/") for n in z.namelist() if n.startswith("armctl/_presets/"))
    assert shipped == sorted(p.name for p in (REPO / "controllers").glob("*.toml"))
    _pip("install", "--no-deps", "--target", str(tmp_path / "wheel"), str(wheel))
    got = _probe(tmp_path / "wheel")
    assert Path(got["armctl"]).is_relative_to(tmp_path / "wheel")
    assert Path(got["folder"]) == (tmp_path / "wheel" / "armctl" / "_presets").resolve()
    assert got["preset"] == expected

    _pip("install", "--no-deps", "--target", str(tmp_path / "editable"), "-e", str(source))
    got = _probe(tmp_path / "editable", "write")
    assert Path(got["armctl"]).is_relative_to(source / "src")
    assert Path(got["folder"]) == (source / "controllers").resolve()
    assert got["preset"] == expected
    assert Path(got["written"]) == (source / "controllers" / "s.m.toml").resolve()
    assert _read_toml(source / "controllers" / "s.m.toml")["how"] == "probe"
