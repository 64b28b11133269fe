"""The type checker's exceptions stay few and explained: every ``# type: ignore`` in the library names the error
codes it silences and says why (a comment after it, or on the line above), there are at most 40 of them, and
pyproject.toml turns no module's errors off wholesale (``ignore_errors``)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
SOURCES = sorted((ROOT / "src" / "armctl").rglob("*.py"))
IGNORE = re.compile(r"#\s*type:\s*ignore(?P<codes>\[[^\]]*\])?(?P<rest>.*)$")


def _ignores() -> list[tuple[str, int, str, str]]:
    """(file, line number, the line, the line above) of every ``type: ignore`` comment."""
    out = []
    for path in SOURCES:
        lines = path.read_text(encoding="utf-8").splitlines()
        for i, line in enumerate(lines):
            if IGNORE.search(line):
                out.append((str(path.relative_to(ROOT)), i + 1, line, lines[i - 1] if i else ""))
    return out


def test_the_sources_are_found() -> None:
    assert len(SOURCES) > 100 and any(p.name == "simulate.py" for p in SOURCES)


def test_at_most_40_type_ignores() -> None:
    assert len(_ignores()) <= 40, [f"{f}:{n}" for f, n, _, _ in _ignores()]


@pytest.mark.parametrize(("where", "line", "above"), [(f"{f}:{n}", ln, up) for f, n, ln, up in _ignores()])
def test_each_type_ignore_names_its_codes_and_a_reason(where: str, line: str, above: str) -> None:
    m = IGNORE.search(line)
    assert m is not None and m["codes"], f"{where}: a bare type: ignore silences every error; name the codes"
    reason_after = re.match(r"\s*#\s*\S", m["rest"]) is not None
    reason_above = above.strip().startswith("#") and "type: ignore" not in above
    assert reason_after or reason_above, f"{where}: say why the error is not one (a comment after it or above)"


def test_no_module_has_its_errors_turned_off() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["mypy"]
    assert "ignore_errors" not in config
    assert all("ignore_errors" not in o for o in config.get("overrides", []))
    assert config.get("warn_unused_ignores") is True  # an ignore that no longer silences anything is reported
