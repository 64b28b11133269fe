"""Sweeps: the same answers through the sweep's own process pool, a ProcessPoolExecutor, a thread pool and
serially; diverged runs as answers; failures recorded per case, or raised with the case's index on request."""

from __future__ import annotations

import threading
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import armctl
from armctl.errors import ArmctlError, InvalidParameterError, SweepWarning, UnknownNameError
from armctl.sim import CaseFailure, SimResult, StopRules, SweepResult, sweep
from tests.sim.helpers import PDGravity

pytestmark = pytest.mark.one_step  # sweeps and the step functions themselves: not a choice of step

MODEL = armctl.models.planar_2r()


def final_state(res: SimResult) -> tuple[bool, float, float]:
    """What comes back from a worker: diverged, final error, final time."""
    return res.diverged, float(np.abs(res.q[-1] - [0.3, -0.2]).max()), float(res.t[-1])


def cases(gains: list[float]) -> list[dict[str, object]]:
    # each case gets its own Dynamics (a Dynamics' workspace is not shared between threads)
    return [
        {
            "plant": MODEL,
            "controller": PDGravity(armctl.Dynamics(MODEL), kp, 0.1 * kp),
            "reference": armctl.Reference.hold([0.3, -0.2]),
            "duration": 0.3,
            "q0": [0.0, 0.0],
            "stop": StopRules(max_velocity=20.0),
            "saturate": False,
        }
        for kp in gains
    ]


GAINS = [2e3, 1e4, 5e4, 3e7]  # the last one is far too stiff for a 1 kHz loop


# its run saturates the torque, as expected
@pytest.mark.filterwarnings("ignore:torque at its limit on most samples:armctl.errors.SimulationWarning")
def test_process_pool_thread_pool_and_serial_agree() -> None:
    pooled = sweep(cases(GAINS), summary=final_state, max_workers=2, progress=False)
    with ProcessPoolExecutor(2) as ex:
        theirs = sweep(cases(GAINS), summary=final_state, executor=ex, progress=False)
    with ThreadPoolExecutor(2) as ex:
        threaded = sweep(cases(GAINS), summary=final_state, executor=ex, progress=False)
    serial = sweep(cases(GAINS), summary=final_state, executor="serial", progress=False)
    assert pooled == theirs == threaded == serial
    assert isinstance(pooled, SweepResult) and pooled.all_ok and pooled.counts["ok"] == 4
    assert [d for d, _, _ in serial] == [False, False, False, True]  # divergence is an answer, not a failure
    assert serial[2][1] < serial[0][1]  # stiffer gain, smaller final error


def test_full_results_come_back_without_summary() -> None:
    out = sweep(cases(GAINS[:2]), max_workers=2, progress=False)
    assert all(isinstance(r, SimResult) for r in out)
    assert len(out[0].t) == 301


def test_a_custom_run_function() -> None:
    out = sweep([{"x": 1}, {"x": 2}], run=_square, executor="serial", progress=False)
    assert out == [1, 4]


def _square(x: int) -> int:
    return x * x


def test_a_bad_case_is_recorded_or_raised_with_its_index() -> None:
    bad = cases(GAINS[:3])
    bad[1]["duration"] = -1.0
    for executor in ("serial", None):
        with pytest.warns(SweepWarning, match="case 1 raised armctl.errors.InvalidParameterError"):
            out = sweep(bad, executor=executor, max_workers=2, progress=False)
        assert isinstance(out[0], SimResult) and isinstance(out[2], SimResult)  # the others come back
        fail = out[1]
        assert isinstance(fail, CaseFailure) and not fail.ok and fail.case is bad[1] and fail.index == 1
        assert fail.kind == "raised" and fail.error_type == "armctl.errors.InvalidParameterError"
        assert "duration" in fail.message and fail.message in fail.traceback
        assert "in simulate" in fail.traceback  # where it was raised
        assert isinstance(fail.exception, InvalidParameterError)
        with pytest.raises(InvalidParameterError) as info:
            sweep(bad, executor=executor, max_workers=2, progress=False, on_error="raise")
        assert "sweep case 1" in "".join(getattr(info.value, "__notes__", []))


class _Unpicklable(Exception):
    def __init__(self, a: int, b: int) -> None:
        super().__init__(f"broken with {a} and {b}")
        # a lock does not pickle, whoever pickles the exception (tblib, which dask installs, pickles exceptions
        # that would not rebuild from their args, but not their attributes)
        self.lock = threading.Lock()


def _raises_unpicklable(**case: object) -> None:
    raise _Unpicklable(1, 2)


def test_errors_in_a_process_pool_arrive_with_their_message() -> None:
    bad = cases(GAINS[:2])
    bad[1]["integrator"] = "rk5"
    with pytest.raises(UnknownNameError, match="unknown integrator 'rk5'") as info:  # pickled by its arguments
        sweep(bad, max_workers=2, progress=False, on_error="raise")
    assert info.value.valid == armctl.sim.INTEGRATORS and info.value.value == "rk5"
    assert "sweep case 1" in "".join(getattr(info.value, "__notes__", []))
    with pytest.warns(SweepWarning):
        out = sweep(cases(GAINS[:1]), run=_raises_unpicklable, max_workers=1, progress=False)
    fail = out[0]
    assert fail.error_type == "tests.sim.test_sweep._Unpicklable" and fail.message == "broken with 1 and 2"
    assert "_raises_unpicklable" in fail.traceback  # the worker's traceback
    # the exception itself cannot travel back: an ArmctlError carries its type, message and traceback
    assert type(fail.exception) is ArmctlError and "_raises_unpicklable" in str(fail.exception)
    with pytest.raises(ArmctlError, match=r"_Unpicklable: broken with 1 and 2 \(raised in a worker"):
        sweep(cases(GAINS[:1]), run=_raises_unpicklable, max_workers=1, progress=False, on_error="raise")
    with ThreadPoolExecutor(2) as pool, pytest.warns(SweepWarning):
        out = sweep(cases(GAINS[:1]), run=_raises_unpicklable, executor=pool, progress=False)
    assert isinstance(out[0].exception, _Unpicklable)  # threads: the exception as it was raised
    with pytest.raises(_Unpicklable, match="broken with 1 and 2"), ThreadPoolExecutor(2) as pool:
        sweep(cases(GAINS[:1]), run=_raises_unpicklable, executor=pool, progress=False, on_error="raise")


def test_every_error_class_pickles() -> None:
    import pickle

    from armctl import errors

    for cls in vars(errors).values():
        if isinstance(cls, type) and issubclass(cls, ArmctlError):
            exc = cls("frame", "hand", ("tool", "base")) if cls is UnknownNameError else cls("message", value=3)
            back = pickle.loads(pickle.dumps(exc))
            assert type(back) is cls and str(back) == str(exc) and back.value == exc.value


def test_bad_sweep_arguments() -> None:
    with pytest.raises(InvalidParameterError, match="'dask'"):
        sweep(cases(GAINS[:1]), executor="dask", progress=False)
    with pytest.raises(InvalidParameterError, match="case 0"):
        sweep([("not", "a", "mapping")], progress=False)  # type: ignore[list-item]
    with pytest.raises(InvalidParameterError, match="max_workers"):
        sweep(cases(GAINS[:1]), max_workers=0, progress=False)
    with pytest.raises(InvalidParameterError, match="cases must be an iterable"):
        sweep(None, progress=False)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="progress must be True, False or a text stream, got 'yes'"):
        sweep(cases(GAINS[:1]), progress="yes")  # type: ignore[arg-type]
    # these ran into an AttributeError ('submit'), a TypeError ('int' object is not callable) or were accepted
    with pytest.raises(InvalidParameterError, match=r"executor must be an Executor .* got <object"):
        sweep(cases(GAINS[:1]), executor=object(), progress=False)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="run must be a function, got 5"):
        sweep(cases(GAINS[:1]), run=5, executor="serial", progress=False)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="summary must be a function"):
        sweep(cases(GAINS[:1]), summary="rms", executor="serial", progress=False)  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="max_workers must be a positive integer, got True"):
        sweep(cases(GAINS[:1]), max_workers=True, progress=False)


def test_a_friction_model_needs_the_model_not_the_dynamics() -> None:
    from armctl.sim.friction import SmoothFriction, StickSlip

    dyn = armctl.Dynamics(armctl.models.planar_2r())
    for cls in (SmoothFriction, StickSlip):
        with pytest.raises(InvalidParameterError, match=r"RobotModel \(dynamics.model\), got PinocchioDynamics"):
            cls(dyn)  # type: ignore[arg-type]


def test_unpicklable_errors_arrive_when_exceptions_pickle_through_tblib() -> None:
    """dask installs tblib's exception pickling, which follows an exception's context chain: the text-wrapped
    error must not carry the unpicklable original with it (it broke the pool). Run in a fresh process, so the
    installation does not leak into the other tests."""
    import subprocess
    import sys

    pytest.importorskip("tblib")
    code = (
        "from tblib import pickling_support\n"
        "pickling_support.install()\n"
        "from armctl.errors import ArmctlError\n"
        "from armctl.sim import sweep\n"
        "from tests.sim.test_sweep import GAINS, _raises_unpicklable, cases\n"
        "try:\n"
        "    sweep(cases(GAINS[:1]), run=_raises_unpicklable, max_workers=1, progress=False, on_error='raise')\n"
        "except ArmctlError as exc:\n"
        "    print(type(exc).__name__, str(exc).splitlines()[0][:80])\n"
    )
    root = Path(__file__).resolve().parents[2]
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=root)
    expected = "ArmctlError tests.sim.test_sweep._Unpicklable: broken with 1 and 2 (raised in a worker"
    assert out.stdout.startswith(expected), out.stderr[-2000:]
