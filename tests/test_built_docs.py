"""The built documentation, as a reader copies from it: no command option turned into a dash by typography, no
constant described by its type's docstring ("Built-in immutable sequence."), no test file cited, and the equations
typeset by the MathJax copy shipped in the build.

It builds the pages without running the gallery into a temporary folder (a few minutes), or reads the build in
``$ARMCTL_BUILT_DOCS`` (CI's full build: ``.ci/run`` sets it after ``sphinx-build``)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: an option or flag whose hyphens typography turned into an en or em dash: " –out", "(—show"
DASHED_OPTION = re.compile(r"(?:^|[\s(\[>\"'])[–—]-?[A-Za-z]")
#: the docstrings of the types of constants, which autodoc shows for a constant without a description
TYPE_DOCS = ("Built-in immutable sequence", "dict() -> new empty dictionary", "int([x]) -> integer")


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> Path:
    given = os.environ.get("ARMCTL_BUILT_DOCS")
    if given:
        return Path(given)
    pytest.importorskip("sphinx_gallery", reason="the docs extra is not installed")
    out = tmp_path_factory.mktemp("html")
    env = {**os.environ, "ARMCTL_DOCS_NO_GALLERY": "1", "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html", str(ROOT / "docs"), str(out)],
        capture_output=True,
        text=True,
        env=env,
        timeout=1200,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    return out


def _pages(built: Path) -> list[Path]:
    pages = [p for p in built.rglob("*.html") if "_static" not in p.parts and "_modules" not in p.parts]
    assert len(pages) > 100
    return pages


def _text(page: Path) -> str:
    """The page's text, tags dropped (a code span's parts become one string)."""
    return re.sub(r"<[^>]+>", "", page.read_text(encoding="utf-8"))


@pytest.mark.slow
def test_commands_copy_as_written(built: Path) -> None:
    dashed = [
        f"{p.relative_to(built)}: {m.group(0)!r}" for p in _pages(built) for m in DASHED_OPTION.finditer(_text(p))
    ]
    assert not dashed, dashed[:10]
    start = (built / "getting_started.html").read_text(encoding="utf-8")
    assert "bench --quick --out bench-out" in _text(built / "getting_started.html") and "--out" in start


@pytest.mark.slow
def test_every_constant_is_described(built: Path) -> None:
    constants = sorted((built / "api" / "generated").glob("*.[A-Z]*[A-Z].html"))
    assert len(constants) >= 9  # BACKENDS, INTEGRATORS, PARAMETER_NAMES, PUMA_QZ, SCENES, …
    for page in _pages(built):
        text = _text(page)
        for doc in TYPE_DOCS:
            assert doc not in text, f"{page.relative_to(built)}: {doc!r}"


@pytest.mark.slow
def test_no_test_file_is_cited(built: Path) -> None:
    cited = [str(p.relative_to(built)) for p in _pages(built) if re.search(r"tests/\w+/test_\w+\.py", _text(p))]
    assert not cited, cited


@pytest.mark.slow
def test_equations_are_typeset_by_the_shipped_mathjax(built: Path) -> None:
    page = (built / "guide" / "dynamics.html").read_text(encoding="utf-8")
    assert 'class="math' in page
    scripts = re.findall(r"<script[^>]+src=\"([^\"]*mathjax[^\"]*)\"", page)
    assert scripts and all(not s.startswith(("http:", "https:", "//")) for s in scripts), scripts
    assert (built / "guide" / scripts[0]).resolve().is_file()
