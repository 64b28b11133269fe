"""The bench's map of PD with desired gravity compensation: its exact border against the closed form of the
pendulum, g = m g ℓ sin q, and its cells on either side of it."""

from __future__ import annotations

import math

import pytest
from scipy.optimize import brentq

from armctl.bench import desired_gravity_map as dgm
from armctl.bench.textbook_borders import computed_torque_textbook


def test_exact_border_of_the_pendulum() -> None:
    """Upright, a second equilibrium appears exactly at K_p = m g ℓ; hanging, at max over x of −m g ℓ sin x / x,
    taken where tan x = x (x ≈ 4.4934)."""
    mgl = 2.0 * 9.81 * 0.25
    x = brentq(lambda x: math.tan(x) - x, 4.4, 4.6)
    assert dgm.exact_border(math.pi) == pytest.approx(mgl, rel=1e-6)
    assert dgm.exact_border(0.0) == pytest.approx(-mgl * math.sin(x) / x, rel=1e-6)


def test_cells_on_either_side_of_the_exact_border() -> None:
    """At q_d = π/2 the border lies at 0.72 k_g: below it a start settles elsewhere, above it every start
    reaches the set-point, although the textbook's K_p > k_g does not hold there."""
    kg = dgm._constants()[0]
    assert dgm.exact_border(math.pi / 2) / kg == pytest.approx(0.7177, abs=1e-3)
    assert dgm.run_cell(0.5, math.pi / 2, duration=15.0) == "second equilibrium"
    assert dgm.run_cell(0.9, math.pi / 2, duration=15.0) == "unique"


def test_computed_torque_textbook_borders() -> None:
    """The small-gain interval of f narrows towards the premise's f < 2 as the gains (and the damping) grow; the
    conservatism is the largest stable f over the guaranteed one."""
    tb = computed_torque_textbook([0.5, 8.0], [1.0, 3.0], [["stable", "stable"], ["stable", "unstable"]], 100.0, 20.0)
    assert tb["premise_f_max"] == 2.0
    assert tb["small_gain_f_max"][0] < tb["small_gain_f_max"][1] < 2.0
    assert tb["largest_stable_f"] == [3.0, 1.0]
    assert tb["conservatism"][0] == pytest.approx(3.0 / tb["small_gain_f_max"][0])
