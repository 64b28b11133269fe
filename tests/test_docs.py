"""The documentation's sources cover the product: every public name has an API entry, every guide page is in the
guide, the README names the build command. (The build itself, with warnings as errors, runs in CI: .ci/run.)"""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
BUILD = "sphinx-build -W -b html docs docs/_build/html"
#: the public modules whose ``__all__`` the API reference must cover
PUBLIC = (
    "armctl",
    "armctl.models",
    "armctl.model",
    "armctl.codegen",
    "armctl.dynamics",
    "armctl.dynamics.identification",
    "armctl.references",
    "armctl.controllers",
    "armctl.controllers.osc",
    "armctl.planning",
    "armctl.sim",
    "armctl.tuning",
    "armctl.scenes",
    "armctl.bench.suite",
)


def api_entries() -> list[tuple[str, str]]:
    """(module, name) of every autosummary entry of the API pages, with the module its ``currentmodule`` sets."""
    out = []
    for page in sorted((DOCS / "api").glob("*.rst")):
        module = None
        in_summary = False
        for line in page.read_text().splitlines():
            if m := re.match(r"\.\. currentmodule:: (\S+)", line):
                module = m.group(1)
            elif line.startswith(".. autosummary::"):
                in_summary = True
            elif in_summary and (m := re.match(r"   ([A-Za-z_][\w.]*)$", line)):
                assert module is not None, page
                out.append((module, m.group(1)))
            elif in_summary and line and not line.startswith("   "):
                in_summary = False
    return out


def documented() -> dict[int, str]:
    """id(object) → the name it is documented under, for every API entry (which must import)."""
    out = {}
    for module, name in api_entries():
        obj = getattr(importlib.import_module(module), name)
        out[id(obj)] = f"{module}.{name}"
    return out


def test_every_api_entry_imports_and_is_listed_once() -> None:
    entries = api_entries()
    assert len(entries) > 150
    names = [f"{m}.{n}" for m, n in entries]
    assert len(set(names)) == len(names)
    objects = documented()  # raises if an entry does not import
    assert len(objects) == len(entries), "an object is documented under two names (duplicate descriptions)"


@pytest.mark.parametrize("module", PUBLIC)
def test_every_public_name_has_an_api_entry(module: str) -> None:
    mod = importlib.import_module(module)
    objects = documented()
    missing = []
    public = getattr(mod, "__all__", None) or [  # no __all__: the classes and functions defined there
        n for n in dir(mod) if not n.startswith("_") and getattr(getattr(mod, n), "__module__", None) == module
    ]
    for name in public:
        obj = getattr(mod, name)
        if isinstance(obj, type(mod)):  # a subpackage: it has its own page
            continue
        if id(obj) not in objects:
            missing.append(name)
    assert not missing, f"{module}: no API entry for {missing}"


@pytest.mark.parametrize(
    "obj",
    [
        "armctl.Dynamics",
        "armctl.simulate",
        "armctl.controllers.OperationalSpaceQP",
        "armctl.planning.time_optimal",
        "armctl.dynamics.identification.identify",
        "armctl.tuning.presets.load_preset",
        "armctl.dynamics.kernel.Kernel",
    ],
)
def test_the_main_names_have_a_page(obj: str) -> None:
    module, name = obj.rsplit(".", 1)
    assert id(getattr(importlib.import_module(module), name)) in documented()


def test_every_guide_page_is_in_the_guide() -> None:
    index = (DOCS / "guide" / "index.rst").read_text()
    listed = set(re.findall(r"^   (\w+)$", index, re.M))
    pages = {p.stem for p in (DOCS / "guide").glob("*.rst")} - {"index"}
    assert pages == listed
    for topic in (
        "modelling",
        "dynamics",
        "controllers",
        "osc",
        "planning",
        "simulation",
        "identification",
        "tuning",
        "benchmark",
        "speed",
    ):
        assert topic in pages


def test_every_example_has_a_gallery_title() -> None:
    for script in sorted((ROOT / "examples").glob("*.py")):
        lines = script.read_text().split('"""', 2)[1].strip().splitlines()
        assert len(lines) > 2 and set(lines[1]) == {"="} and len(lines[1]) == len(lines[0]), script.name


def test_nothing_is_fetched_when_the_docs_are_viewed() -> None:
    conf = (DOCS / "conf.py").read_text()
    extensions = re.search(r"^extensions = \[(.*?)\]", conf, re.S | re.M).group(1)
    assert "intersphinx" not in extensions  # its inventories are fetched at build time
    # MathJax from a CDN unless its copy is shipped with the pages
    assert [e for e in re.findall(r'"([^"]+)"', extensions) if "mathjax" in e] == ["sphinx-mathjax-offline"]
    assert re.search(r'html_theme = "(furo|pydata_sphinx_theme)"', conf)
    assert '"write_computation_times": False' in conf  # sphinx-gallery's timing page loads DataTables from a CDN


def test_the_readme_names_the_docs_build_and_keeps_its_quick_start() -> None:
    readme = (ROOT / "README.md").read_text()
    assert BUILD in readme
    lines = re.search(r"## Quick start\n\n```sh\n(.*?)```", readme, re.S).group(1).splitlines()
    assert lines == [
        'pip install -e ".[view]" && armctl bench --quick --out bench-out',
        'pip install -e ".[test]" && python -m pytest -q',
    ]
    for image in re.findall(r"!\[[^]]*\]\(([^)]+)\)", readme):
        assert (ROOT / image).is_file(), image
