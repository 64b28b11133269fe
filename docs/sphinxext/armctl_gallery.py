"""sphinx-gallery helpers for armctl's examples: their command-line arguments and their figures.

* :func:`reset_argv`: the examples that write files are given ``--out`` in the build folder, so a docs build
  never writes into ``examples/`` (nor over the shipped presets).
* :func:`unmanaged_figures`: armctl's plotting functions return ``matplotlib.figure.Figure`` objects that pyplot
  does not manage (the library keeps no global figure state), which sphinx-gallery's matplotlib scraper cannot
  see. Every Figure created while an example runs is kept here and drawn into the example's page.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

#: examples that take ``--out DIR`` for the files they write
WRITES_FILES = ("closed_loop_simulation.py", "model_views.py", "mujoco_comparison.py", "tune_gains.py")

_created: list[Figure] = []
_figure_init = Figure.__init__


def _record_init(self: Figure, *args: Any, **kwargs: Any) -> None:
    _figure_init(self, *args, **kwargs)
    _created.append(self)


Figure.__init__ = _record_init  # type: ignore[method-assign]


def reset_argv(gallery_conf: dict[str, Any], script_vars: dict[str, Any]) -> list[str]:
    """Arguments of an example run by the gallery: ``--out`` in the build folder for those that write files."""
    name = Path(script_vars["src_file"]).name
    if name in WRITES_FILES:
        return ["--out", str(Path(gallery_conf["src_dir"]) / "_build" / "gallery-out" / Path(name).stem)]
    return []


def unmanaged_figures(block: Any, block_vars: dict[str, Any], gallery_conf: dict[str, Any], **kwargs: Any) -> str:
    """The rST of the Figures created since the last call that pyplot does not manage, each saved as a PNG."""
    from sphinx_gallery.scrapers import figure_rst

    figures = [f for f in _created if f.canvas.manager is None]
    _created.clear()
    paths = []
    for fig, path in zip(figures, block_vars["image_path_iterator"], strict=False):
        fig.savefig(path, dpi=90)
        paths.append(path)
    return figure_rst(paths, gallery_conf["src_dir"])  # type: ignore[no-any-return]
