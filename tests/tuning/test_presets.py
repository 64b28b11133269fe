"""Presets: whatever write_preset accepts, load_preset reads back unchanged; a file that is not a preset raises an
ArmctlError naming it."""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from armctl.errors import ArmctlError, InvalidParameterError, ModelLoadError
from armctl.tuning.presets import load_preset, write_preset

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


def test_presets_folder_search_order(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """$ARMCTL_PRESETS, else the source checkout's controllers/, else the installed copy (a non-editable
    install has no checkout); with none, the checkout's path is named in the error."""
    from armctl.tuning import presets

    checkout, installed = tmp_path / "repo" / "controllers", tmp_path / "prefix" / "share" / "armctl" / "controllers"
    user = tmp_path / "home" / ".local" / "share" / "armctl" / "controllers"
    monkeypatch.setattr(presets, "_candidates", lambda: (checkout, installed, user))
    monkeypatch.delenv("ARMCTL_PRESETS", raising=False)
    assert presets.presets_dir() == checkout  # none exists
    with pytest.raises(ModelLoadError, match=r"no preset s\.m\.toml in .*repo.*ARMCTL_PRESETS"):
        load_preset("s", "m")
    write_preset("s", "m", {"kp": 3.0}, "user", "test", user)
    assert presets.presets_dir() == user and load_preset("s", "m")["how"] == "user"
    write_preset("s", "m", {"kp": 2.0}, "installed", "test", installed)
    assert presets.presets_dir() == installed and load_preset("s", "m")["how"] == "installed"
    write_preset("s", "m", {"kp": 1.0}, "checkout", "test", checkout)
    assert presets.presets_dir() == checkout and load_preset("s", "m")["how"] == "checkout"
    monkeypatch.setenv("ARMCTL_PRESETS", str(tmp_path / "mine"))
    assert presets.presets_dir() == tmp_path / "mine"


def test_the_package_ships_every_preset() -> None:
    """pyproject's data-files put controllers/*.toml where presets_dir looks in a non-editable install."""
    import sys

    from armctl.tuning import presets

    tomllib = pytest.importorskip("tomllib") if sys.version_info >= (3, 11) else pytest.importorskip("tomli")
    root = Path(__file__).resolve().parents[2]
    config = tomllib.loads((root / "pyproject.toml").read_text())
    shipped = config["tool"]["setuptools"]["data-files"]["share/armctl/controllers"]
    files = sorted(p for pattern in shipped for p in root.glob(pattern))
    assert files == sorted((root / "controllers").glob("*.toml")) and len(files) >= 17
    assert presets._candidates()[1] == Path(sys.prefix) / "share" / "armctl" / "controllers"
    assert len(presets._candidates()) == 3  # and the user base's (pip install --user)
