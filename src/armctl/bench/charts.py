"""The bench's charts on matplotlib: pyplot on the non-interactive Agg backend with the bench's font sizes, log axes
ticked plainly, and writing a figure to a file."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the non-interactive Agg backend, imported on first use."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update({"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10, "legend.fontsize": 9})
    return plt


def plain_log_ticks(ax: Any) -> None:
    """Log axes of ``ax`` ticked at 1, 2, 5 × 10^k and labelled plainly ("20", "0.005", never "2×10⁰"),
    without minor labels (over less than a decade matplotlib labels the minor ticks, which collide)."""
    import matplotlib.ticker

    for axis in (ax.xaxis, ax.yaxis):
        if axis.get_scale() == "log":
            axis.set_major_locator(matplotlib.ticker.LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
            axis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda v, _: f"{v:g}"))
            axis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def save_figure(fig: Any, path: Path, dpi: int = 110, rect: tuple[float, float, float, float] | None = None) -> None:
    """Lay ``fig`` out (matplotlib's ``tight_layout`` within ``rect``, (left, bottom, right, top) as fractions of
    the figure; None: all of it), write it to ``path`` and free it."""
    fig.tight_layout(rect=rect)
    fig.savefig(path, dpi=dpi)
    pyplot().close(fig)
