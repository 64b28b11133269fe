"""One bench section run on its own, as ``python -m armctl.bench.<section> [--quick]``: its results printed and its
chart written in the working directory."""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any


def section_main(
    run: Callable[..., dict[str, Any]],
    summary: Callable[[dict[str, Any]], str],
    plot: Callable[[dict[str, Any], Path], None],
    chart: str,
    argv: Sequence[str] | None = None,
) -> None:
    """Run a section (``--quick`` in ``argv``, default ``sys.argv[1:]``: the short version), print ``summary``
    of its figures and write the chart ``chart`` in the working directory."""
    args = sys.argv[1:] if argv is None else list(argv)
    data = run(quick="--quick" in args)
    print(summary(data))
    plot(data, Path(chart))
