"""The sweep's progress: a live bar on a terminal, a few whole lines in a log file, nothing with
``progress=False``; the failed count is shown and the finished display is closed with a newline."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from armctl.errors import SweepWarning
from armctl.sim import sweep

pytestmark = pytest.mark.one_step  # sweeps and the step functions themselves: not a choice of step


def _square(x: int) -> int:
    if x == 3:
        raise ValueError("three")
    return x * x


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_log_file_gets_a_few_whole_lines(tmp_path: Path) -> None:
    path = tmp_path / "sweep.log"
    with path.open("w") as log, pytest.warns(SweepWarning):
        out = sweep([{"x": x} for x in range(300)], run=_square, executor="serial", progress=log)
    assert len(out.failures) == 1
    text = path.read_text()
    assert "\r" not in text and text.endswith("\n")
    lines = text.splitlines()
    # 300 runs well within the 30 s between lines: the first line and the last, not one line per run
    assert 2 <= len(lines) <= 3, lines
    assert lines[0].startswith("sweep: 0/300 runs")
    assert lines[-1].startswith("sweep: 300/300 runs, 1 failed [")


def test_a_terminal_gets_a_live_bar_that_ends_with_a_newline() -> None:
    term = _Terminal()
    sweep([{"x": x} for x in range(3)], run=_square, executor="serial", progress=term)
    text = term.getvalue()
    assert "\r" in text and text.endswith("\n") and text.count("\n") == 1  # one line, redrawn
    assert "100%" in text.splitlines()[-1].split("\r")[-1] and "3/3" in text


def test_no_progress_writes_nothing_and_true_writes_on_stderr(capsys: pytest.CaptureFixture[str]) -> None:
    sweep([{"x": 1}], run=_square, executor="serial", progress=False)
    assert capsys.readouterr().err == ""
    sweep([{"x": 1}, {"x": 2}], run=_square, max_workers=2, progress=True)
    err = capsys.readouterr().err  # captured, so not a terminal: whole lines
    assert err.splitlines()[-1].startswith("sweep: 2/2 runs [") and "\r" not in err
