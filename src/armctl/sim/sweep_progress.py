"""The sweep's progress display, on tqdm.

On a terminal, a live bar that stays, finished, as one line with the counts. On anything else (a log file, a
pipe, a captured stream), whole lines instead of a redrawn one, at most one every ``LOG_INTERVAL`` seconds
besides the first and the last, so a log holds a few readable lines rather than one endless ``\\r``-joined
line.
"""

from __future__ import annotations

import sys
from typing import Any, TextIO

from tqdm import tqdm

LOG_INTERVAL = 30.0  # [s] between lines written to something that is not a terminal


class _Lines:
    """A text stream for tqdm that writes each redraw as a line of its own (for logs)."""

    def __init__(self, stream: TextIO) -> None:
        self.stream, self.last = stream, ""

    def write(self, s: str) -> None:
        text = s.replace("\r", "").strip()
        if text and text != self.last:
            self.stream.write(text + "\n")
            self.last = text

    def flush(self) -> None:
        self.stream.flush()


def _is_terminal(stream: Any) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError, OSError):
        return False


class Progress:
    """Progress of ``total`` runs on ``stream`` (None: ``sys.stderr``), ``done`` of them finished before (a
    resumed sweep's), with the number that failed."""

    def __init__(self, total: int, stream: TextIO | None = None, done: int = 0) -> None:
        stream = sys.stderr if stream is None else stream
        self.failed = 0
        if _is_terminal(stream):
            self.bar = tqdm(
                total=total, initial=done, desc="sweep", unit=" runs", file=stream, leave=True, dynamic_ncols=True
            )
        else:
            self.bar = tqdm(
                total=total,
                initial=done,
                desc="sweep",
                unit=" runs",
                file=_Lines(stream),
                leave=True,
                mininterval=LOG_INTERVAL,
                miniters=1,
                bar_format="{desc}: {n_fmt}/{total_fmt} runs{postfix} [{elapsed}<{remaining}, {rate_fmt}]",
            )

    def update(self, failed: bool) -> None:
        """One more run ended (``failed``: without a result)."""
        if failed:
            self.failed += 1
            self.bar.set_postfix_str(f"{self.failed} failed", refresh=False)
        self.bar.update(1)

    def close(self) -> None:
        self.bar.close()
