"""The docstring sections the OSC package writes once: :func:`~armctl.controllers.osc.docstrings.fill` puts a
section where a docstring's mark line is, indented as the mark; the frame tasks' class docstrings so get their
constructor's Parameters and Raises, each in its own sizes and name."""

from __future__ import annotations

import inspect
import warnings

import pytest

from armctl.controllers.osc import FrameOrientationTask, FramePoseTask, FramePositionTask
from armctl.controllers.osc.docstrings import STEP_MARK, fill
from armctl.controllers.osc.tasks.frame_task import PARAMETERS_MARK

numpydoc = pytest.importorskip("numpydoc.docscrape", reason="numpydoc is in the test extra")


def test_fill_puts_the_section_at_the_marks_indentation() -> None:
    doc = "Summary.\n\n    MARK\n\n    Notes\n    -----\n    text"
    section = "Parameters\n----------\nx : int\n    A count."
    expected = (
        "Summary.\n\n    Parameters\n    ----------\n    x : int\n        A count.\n\n    Notes\n    -----\n    text"
    )
    assert fill(doc, "MARK", section) == expected
    assert fill("Summary without a mark.", "MARK", section) == "Summary without a mark."
    assert fill(None, "MARK", section) is None  # docstrings stripped (python -OO)


@pytest.mark.parametrize(
    ("cls", "dim", "name"),
    [(FramePositionTask, 3, "position"), (FrameOrientationTask, 3, "orientation"), (FramePoseTask, 6, "pose")],
)
def test_frame_tasks_document_their_constructor_in_their_own_terms(cls: type, dim: int, name: str) -> None:
    doc = inspect.getdoc(cls)
    assert doc is not None and PARAMETERS_MARK not in doc
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        parsed = numpydoc.NumpyDocString(doc)
    params = {p.name: " ".join(p.desc) for p in parsed["Parameters"]}
    assert list(params) == ["frame", "kp", "kd", "weight", "priority", "name"]
    assert f"a ({dim},) diagonal or a {dim}×{dim} symmetric positive definite matrix" in params["kp"]
    assert params["weight"].endswith(f"(scalar or ({dim},)).")
    assert f'``"{name}[FRAME]"``' in params["name"]
    assert [r.type for r in parsed["Raises"]] == ["InvalidParameterError, ShapeError, NonFiniteError"]
    assert parsed["Notes"]  # the section after the mark is still there
    assert (cls is FramePoseTask) == ("[linear; angular]" in params["kp"])


def test_the_step_parameters_are_filled_in() -> None:
    from armctl.controllers.osc import MotionTask, QPBuilder, Task

    for fn in (
        Task.residual,
        MotionTask.kinematics,
        MotionTask.desired_acceleration,
        MotionTask.error,
        QPBuilder.build,
    ):
        doc = inspect.getdoc(fn)
        assert doc is not None and STEP_MARK not in doc
        assert "state : ModelState" in doc and "t : float" in doc and "ref : Reference" in doc
