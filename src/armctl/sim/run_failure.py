"""What a run that raised hands on: its samples, as the exception's ``result``; and the controller's ``end_run``,
called once after every run, never raising in place of the run's own exception."""

from __future__ import annotations

from typing import Any

from armctl.sim.result import SimResult


def end_run(controller: Any, failure: BaseException | None) -> BaseException | None:
    """Call the controller's ``end_run()`` (if it has one) after a run that raised ``failure`` (None: it did not).

    Returns the exception the run raises: ``failure``, with a note if ``end_run`` raised too, or what ``end_run``
    raised after a run that did not.
    """
    finish = getattr(controller, "end_run", None)
    if not callable(finish):
        return failure
    try:
        finish()  # the controller's account of the run (e.g. the OSC's solver fallbacks), once
    except BaseException as exc:
        if failure is None:
            return exc
        if hasattr(failure, "add_note"):
            failure.add_note(f"the controller's end_run() then raised {type(exc).__name__}: {exc}")
    return failure


def attach(exc: BaseException, res: SimResult, t: float) -> None:
    """Hand the samples simulated up to ``exc`` (raised at t [s]) on with it, as ``exc.result``."""
    try:
        exc.result = res  # type: ignore[attr-defined]  # the samples travel with the exception
    except AttributeError:  # an exception type that takes no attributes: nothing to attach
        return
    note = f"simulate: raised at t = {t:g} s; the {len(res.t)} samples up to it are in this exception's .result"
    if hasattr(exc, "add_note"):
        exc.add_note(note)
