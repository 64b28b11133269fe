"""Progress of ``armctl bench`` on tqdm: a bar over the sections and one over the steps inside a long section.

On a terminal the bars are drawn on stderr and cleared when done (each section's results are printed on
stdout as it finishes, so a finished bar has nothing left to say). Written to anything else (a log file, a
pipe) there are no bars: the section headings and results, one line at a time, are the progress.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator
from typing import Any, TypeVar

T = TypeVar("T")


def _terminal() -> bool:
    try:
        return bool(sys.stderr.isatty())
    except (AttributeError, ValueError, OSError):
        return False


def sections(total: int) -> Any:
    """The bar over ``total`` sections (their durations differ by ×100, so it shows the elapsed time and no
    estimate of the time left). ``.set_description(name)`` as each one starts, ``.update()`` as it ends."""
    from tqdm import tqdm

    return tqdm(
        total=total,
        desc="armctl bench",
        unit="section",
        leave=False,
        disable=not _terminal(),
        file=sys.stderr,
        dynamic_ncols=True,
        bar_format="{desc}{n_fmt}/{total_fmt} sections |{bar}| {elapsed}",
    )


def steps(items: Iterable[T], desc: str, total: int | None = None) -> Iterator[T]:
    """``items``, with a bar of their count under the sections' bar, cleared when done."""
    from tqdm import tqdm

    yield from tqdm(
        items,
        desc=desc,
        total=total,
        leave=False,
        disable=not _terminal(),
        file=sys.stderr,
        dynamic_ncols=True,
        position=1,
    )
