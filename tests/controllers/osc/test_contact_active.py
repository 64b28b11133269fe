"""Contact(active=...) takes True or False only: text such as "False" is truthy, and taking it would switch the
contact on."""

from __future__ import annotations

import numpy as np
import pytest

from armctl.controllers.osc import Contact
from armctl.errors import InvalidParameterError


@pytest.mark.parametrize("value", ["False", "True", 0, 1, None, [False]])
def test_active_must_be_true_or_false(value: object) -> None:
    with pytest.raises(InvalidParameterError, match=r"^active must be True or False, got "):
        Contact(active=value)  # type: ignore[arg-type]


def test_booleans_are_taken() -> None:
    assert Contact(active=False).active is False
    assert Contact(active=np.bool_(True)).active is True
