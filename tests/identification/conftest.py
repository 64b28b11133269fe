"""Fixtures built once per test run: the identified Puma 560 and Panda (see ``_cases``)."""

from __future__ import annotations

import pytest

from tests.identification._cases import Case, case


@pytest.fixture(scope="session")
def puma_case() -> Case:
    return case("puma560")


@pytest.fixture(scope="session")
def panda_case() -> Case:
    return case("panda")
