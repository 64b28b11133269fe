"""`ControllerLog`: each key's entries stacked as they were logged, whatever their kind — rows of float arrays,
copies of anything else — with the samples of a key logged at some samples only."""

from __future__ import annotations

import numpy as np
import pytest

from armctl.sim.controller_log import ControllerLog

pytestmark = pytest.mark.one_step  # no simulation


def test_entries_are_stacked_as_logged_whatever_their_kind() -> None:
    log = ControllerLog(6)
    for k in range(6):
        entries = {"e": np.array([k, 2.0 * k]), "f": float(k), "i": k, "b": k % 2 == 0}
        if k >= 3:
            entries["late"] = np.full(3, float(k))
        if k == 4:
            entries["e"] = np.zeros(3)  # another shape from here on
        log.add(k, entries)
        if k == 5:  # the caller's arrays change after the call: the log keeps what was logged
            entries["late"][:] = -1.0
    logs, skipped = log.stacked(6)
    assert skipped == ["'e' (entries of different shapes)"]
    np.testing.assert_array_equal(logs["f"], np.arange(6.0))
    np.testing.assert_array_equal(logs["i"], np.arange(6))
    assert logs["i"].dtype.kind == "i"  # integers stay integers
    np.testing.assert_array_equal(logs["b"], [True, False, True, False, True, False])
    np.testing.assert_array_equal(logs["late"], [[3.0] * 3, [4.0] * 3, [5.0] * 3])
    np.testing.assert_array_equal(logs["late:sample"], [3, 4, 5])


def test_only_the_samples_kept_are_stacked() -> None:
    log = ControllerLog(5)
    for k in range(5):
        log.add(k, {"x": np.array([float(k)])})
    logs, _ = log.stacked(3)  # a run that stopped after three samples
    np.testing.assert_array_equal(logs["x"], [[0.0], [1.0], [2.0]])
    assert "x:sample" not in logs
    logs["x"][0] = 9.0  # a copy: the log's own rows are not handed out
    np.testing.assert_array_equal(log.stacked(3)[0]["x"][0], [0.0])
