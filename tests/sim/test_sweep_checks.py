"""What a sweep refuses before anything runs, by name: a case that cannot be pickled for a worker process (a
lambda controller or reference), a keyword ``run`` does not take (a misspelt ``simulate`` keyword), a timeout
that cannot be enforced."""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

import armctl
from armctl.errors import InvalidParameterError
from armctl.sim import sweep
from tests.sim.helpers import PDGravity

pytestmark = pytest.mark.one_step  # sweeps and the step functions themselves: not a choice of step

MODEL = armctl.models.planar_2r()


def _case(**changes: object) -> dict[str, object]:
    case: dict[str, object] = {
        "plant": MODEL,
        "controller": PDGravity(armctl.Dynamics(MODEL), 400.0, 40.0),
        "reference": armctl.Reference.hold([0.3, -0.2]),
        "duration": 0.05,
        "q0": [0.0, 0.0],
    }
    case.update(changes)
    return case


def test_a_lambda_is_refused_by_case_and_key_before_anything_starts() -> None:
    dyn = armctl.Dynamics(MODEL)
    lambda_controller = _case(controller=lambda t, q, qd, ref: dyn.gravity_torque(q))
    lambda_reference = _case(reference=lambda t: armctl.Reference.hold([0.1, 0.2]))
    for i, key, bad in ((1, "controller", lambda_controller), (2, "reference", lambda_reference)):
        cases = [_case(), _case(), _case()]
        cases[i] = bad
        with pytest.raises(InvalidParameterError, match=rf"sweep case {i}: its '{key}' \(<function .*<lambda>") as e:
            sweep(cases, max_workers=2, progress=False)
        assert "cannot be pickled" in str(e.value) and "executor='serial'" in str(e.value)  # the way out
        assert e.value.value is bad[key]
    assert multiprocessing.active_children() == []  # no worker was started
    # a pool the caller owns is refused the same way and still works afterwards (a pickling error inside its
    # machinery can leave shutdown(wait=True) hanging)
    with ProcessPoolExecutor(2) as pool:
        with pytest.raises(InvalidParameterError, match="sweep case 1: its 'controller'"):
            sweep([_case(), lambda_controller], executor=pool, progress=False)
        assert pool.submit(abs, -3).result(timeout=60) == 3
    # in this process or in threads nothing is pickled: the same lambdas run
    serial = sweep([lambda_controller, lambda_reference], executor="serial", progress=False)
    with ThreadPoolExecutor(2) as pool:
        threaded = sweep([lambda_controller, lambda_reference], executor=pool, progress=False)
    assert serial.all_ok and threaded.all_ok
    assert np.array_equal(serial[1].q, threaded[1].q)


def test_a_run_function_that_does_not_pickle_is_refused() -> None:
    with pytest.raises(InvalidParameterError, match=r"the sweep's run \(<function .*<lambda>.* cannot be pickled"):
        sweep([{"x": 1}], run=lambda x: x, max_workers=1, progress=False)
    with pytest.raises(InvalidParameterError, match=r"the sweep's summary \(<function"):
        sweep([_case()], summary=lambda res: res.q[-1], max_workers=1, progress=False)


def test_a_misspelt_keyword_is_refused_by_name_with_the_valid_ones() -> None:
    cases = [_case(), _case(), _case()]
    cases[2]["durration"] = cases[2].pop("duration")
    for executor in (None, "serial"):
        with pytest.raises(InvalidParameterError) as info:
            sweep(cases, executor=executor, progress=False)
        text = str(info.value)
        assert text.startswith("sweep case 2: 'durration' is not a keyword of simulate (did you mean 'duration'?)")
        assert "its keywords: plant, controller, reference, duration, q0" in text and info.value.value == "durration"
    with pytest.raises(InvalidParameterError, match=r"sweep case 1: 'zzz' is not a keyword of simulate; its"):
        sweep([_case(), _case(zzz=1)], progress=False)  # nothing close: no suggestion
    missing = _case()
    del missing["reference"]
    with pytest.raises(InvalidParameterError, match="sweep case 0 does not fit simulate: missing a required argument"):
        sweep([missing], progress=False)
    # a run that takes **kwargs takes any keyword
    assert sweep([{"a": 1, "b": 2}], run=_keywords, executor="serial", progress=False) == [["a", "b"]]


def _keywords(**kw: object) -> list[str]:
    return sorted(kw)


def test_a_timeout_is_refused_where_it_cannot_be_enforced() -> None:
    with pytest.raises(InvalidParameterError, match=r"a run in this process cannot be stopped .*max_workers=1"):
        sweep([_case()], executor="serial", timeout=5.0, progress=False)
    with ThreadPoolExecutor(1) as pool, pytest.raises(InvalidParameterError, match="on ThreadPoolExecutor"):
        sweep([_case()], executor=pool, timeout=5.0, progress=False)
    for bad in (0.0, -1.0, float("inf"), float("nan"), True, "5"):
        with pytest.raises(InvalidParameterError, match="timeout must be a positive number of seconds"):
            sweep([_case()], timeout=bad, progress=False)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="on_error must be 'record' or 'raise', got 'ignore'"):
        sweep([_case()], on_error="ignore", progress=False)  # type: ignore[arg-type]
