"""One `Dynamics` shared between threads gives every thread the results a lone caller gets.

Each thread evaluates on a kernel (workspace) of its own. With one shared workspace, regressors, frame poses,
gravity and forward dynamics came back from another thread's state (regressors of the Pinocchio backend, every
compiled term, every method of the Lagrange backend)."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager

import numpy as np
import pytest

import armctl

METHODS: dict[str, Callable[[armctl.Dynamics, np.ndarray], np.ndarray]] = {
    "regressor": lambda d, s: d.regressor(s[0], s[1], s[2]),
    "passivity_regressor": lambda d, s: d.passivity_regressor(s[0], s[1], s[2], s[3]),
    "passivity_torque": lambda d, s: d.passivity_torque(s[0], s[1], s[2], s[3]),
    "frame_pose": lambda d, s: d.frame_pose(s[0]),
    "gravity_torque": lambda d, s: d.gravity_torque(s[0]),
    "forward_dynamics": lambda d, s: d.forward_dynamics(s[0], s[1], s[2]),
    "inverse_dynamics": lambda d, s: d.inverse_dynamics(s[0], s[1], s[2]),
    "mass_matrix": lambda d, s: d.mass_matrix(s[0]),
    "jacobian": lambda d, s: d.jacobian(s[0]),
}


@contextmanager
def _frequent_switches() -> Iterator[None]:
    """Threads switched every microsecond, so that calls interleave within a method."""
    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        yield
    finally:
        sys.setswitchinterval(old)


@pytest.mark.parametrize(
    ("name", "backend", "options"),
    [("panda", "pinocchio", {}), ("panda", "pinocchio", {"compile": True}), ("planar_3r", "lagrange", {})],
    ids=["pinocchio", "compiled", "lagrange"],
)
def test_a_shared_dynamics_gives_each_thread_its_own_results(name: str, backend: str, options: dict) -> None:
    model = getattr(armctl.models, name)().with_friction(viscous=0.1, coulomb=0.2)
    dyn = armctl.Dynamics(model, backend=backend, **options)
    states = list(np.random.default_rng(3).uniform(-1.0, 1.0, (60, 4, model.n)))
    for method, f in METHODS.items():
        alone = [f(dyn, s) for s in states]

        def job(i: int, f: Callable = f) -> tuple[int, np.ndarray]:
            return i, f(dyn, states[i % len(states)])

        with _frequent_switches(), ThreadPoolExecutor(4) as pool:
            got = list(pool.map(job, range(8 * len(states))))
        wrong = [i for i, out in got if not np.array_equal(out, alone[i % len(states)])]
        assert not wrong, f"{method}: {len(wrong)} of {len(got)} results from another thread's state"


def test_each_thread_has_its_own_kernel_and_the_first_is_made_at_construction() -> None:
    dyn = armctl.Dynamics(armctl.models.planar_2r())
    main = dyn.kernel
    with ThreadPoolExecutor(2) as pool:
        others = list(pool.map(lambda _: id(dyn.kernel), range(4)))
    assert dyn.kernel is main and id(main) not in others
