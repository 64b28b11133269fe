"""sphinx-gallery helpers for armctl's examples: their command-line arguments and their figures.

* :func:`reset_argv`: every example takes ``--out`` for the files it writes (its figures, and for some results,
  playbacks or presets). The gallery runs each one in ``examples/`` with ``--out example-out`` (a git-ignored
  folder there, never the shipped presets), so that its page prints the paths a user's own run prints. The
  figures an example saves are the ones its page shows.
* :func:`unmanaged_figures`: armctl's plotting functions return ``matplotlib.figure.Figure`` objects that pyplot
  does not manage (the library keeps no global figure state), which sphinx-gallery's matplotlib scraper cannot
  see. Every Figure created while an example runs is kept here and drawn into the example's page.
"""

from __future__ import annotations

from typing import Any

from matplotlib.figure import Figure

_created: list[Figure] = []
_figure_init = Figure.__init__


def _record_init(self: Figure, *args: Any, **kwargs: Any) -> None:
    _figure_init(self, *args, **kwargs)
    _created.append(self)


Figure.__init__ = _record_init  # type: ignore[method-assign]


def reset_argv(gallery_conf: dict[str, Any], script_vars: dict[str, Any]) -> list[str]:
    """Arguments of an example run by the gallery (in the examples' folder): ``--out example-out``."""
    return ["--out", "example-out"]


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
