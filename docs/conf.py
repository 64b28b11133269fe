"""Sphinx configuration of armctl's documentation: ``sphinx-build -W -b html docs docs/_build/html``.

Everything a page needs ships with it: the theme's assets (furo), MathJax for the equations (copied into the build
by ``sphinx-mathjax-offline``, from its Python package: nothing fetched from a CDN when a page is viewed), no
intersphinx inventories fetched at build time. Typography leaves dashes alone (``smartquotes_action``), so a
command such as ``armctl bench --out DIR`` reads and copies as written. The example gallery runs
``examples/`` (sphinx-gallery); ``ARMCTL_DOCS_NO_GALLERY=1`` builds the pages without running them.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT / "src"))  # document this checkout, whatever is installed
sys.path.insert(0, str(DOCS / "sphinxext"))

import armctl  # noqa: E402

project = "armctl"
author = "the armctl authors"
copyright = "the armctl authors"
release = armctl.__version__
version = release

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.viewcode",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "sphinx-mathjax-offline",  # MathJax 3 shipped with the pages (sets mathjax_path to the copy in _static)
]
# quotes and ellipses, but no dashes: "--out" stays two hyphens wherever it is written
smartquotes_action = "qe"
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "sphinxext", "**/README.md", "images/*.py", "sg_execution_times.rst"]
templates_path = ["_templates"]
root_doc = "index"

# -- API reference ------------------------------------------------------------------------------------------
autosummary_generate = True
autosummary_imported_members = True
autodoc_typehints = "none"  # the signatures stay readable; types and units are in the docstrings
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_mock_imports: list[str] = []
numpydoc_show_class_members = False  # autodoc lists the members
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
numpydoc_validation_checks: set[str] = set()
add_module_names = False
python_display_short_literal_types = True

# -- example gallery ---------------------------------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"\.py$",  # run every example, not only those named plot_*
    "plot_gallery": "False" if os.environ.get("ARMCTL_DOCS_NO_GALLERY") else "True",
    "reset_argv": "armctl_gallery.reset_argv",
    "image_scrapers": ("armctl_gallery.unmanaged_figures", "matplotlib"),  # before pyplot's are closed
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": True,
    "download_all_examples": False,
    "remove_config_comments": True,
    "min_reported_time": 1,
    "write_computation_times": False,  # its page loads DataTables from a CDN
    "show_memory": False,
    "backreferences_dir": None,
    "doc_module": (),
    "capture_repr": (),
}

# -- HTML -------------------------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"armctl {release}"
html_static_path = ["_static"]
html_css_files = ["armctl.css"]
html_show_sourcelink = False
html_theme_options = {"navigation_with_keys": True}
highlight_language = "none"  # literal blocks hold equations; code blocks say their language
pygments_style = "friendly"
pygments_dark_style = "monokai"
myst_heading_anchors = 3

import armctl_gallery  # noqa: E402, F401 - records the Figures an example draws (see there)

_BAR = re.compile(r"(?<!\\)\|")


def escape_bars(app: object, what: str, name: str, obj: object, options: object, lines: list[str]) -> None:
    """armctl's docstrings write |x| for absolute values and norms, never an rST substitution: escape the bars
    outside inline literals and literal blocks, so that the docstrings read the same in ``help()`` and here."""
    literal = None  # the indentation of the paragraph that opened a literal block, while in it
    for i, line in enumerate(lines):
        text = line.lstrip()
        indent = len(line) - len(text)
        if literal is not None:
            if text and indent <= literal:
                literal = None
            else:
                continue
        if "|" in line:
            parts = line.split("``")
            parts[::2] = [_BAR.sub(r"\\|", part) for part in parts[::2]]
            lines[i] = "``".join(parts)
        if text.endswith("::") or text.startswith((".. code-block::", ".. math::")):
            literal = indent


def constant_comments(app: object, what: str, name: str, obj: object, options: object, lines: list[str]) -> None:
    """A module constant's description: its ``#:`` comment where it is defined (autodoc finds the comment only in
    the module it documents the name under, and otherwise shows the docstring of the value's type, such as
    "Built-in immutable sequence."). The build fails on a public constant without one."""
    if what != "data" or (lines and not _type_doc(obj, lines)):
        return
    from sphinx.pycode import ModuleAnalyzer

    short = name.rsplit(".", 1)[-1]
    for module in sorted(m for m in sys.modules if m == "armctl" or m.startswith("armctl.")):
        if getattr(sys.modules[module], short, None) is not obj:
            continue
        try:
            docs = ModuleAnalyzer.for_module(module).find_attr_docs()
        except Exception:
            continue
        if ("", short) in docs:
            lines[:] = [line for line in docs[("", short)] if line is not None]
            return
    raise RuntimeError(f"the public constant {name} has no #: comment where it is defined: write one there")


def _type_doc(obj: object, lines: list[str]) -> bool:
    """Whether ``lines`` are the docstring of ``obj``'s type (what autodoc shows for an undocumented constant)."""
    doc = type(obj).__doc__
    return doc is not None and " ".join(" ".join(lines).split()) == " ".join(doc.split())


def setup(app: object) -> None:
    app.connect("autodoc-process-docstring", escape_bars, priority=600)  # type: ignore[attr-defined]
    app.connect("autodoc-process-docstring", constant_comments, priority=400)  # type: ignore[attr-defined]
