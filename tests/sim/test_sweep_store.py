"""A sweep's store: outcomes written as they finish, read back as a table; a sweep interrupted (SIGINT) and
killed (SIGKILL) resumes with every finished case kept and none of them run again; a store made from other
cases is refused, naming the difference."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from armctl.errors import InvalidParameterError
from armctl.sim import CaseFailure, SweepResult, sweep
from tests.sim.helpers import failing_cases, failing_job

pytestmark = pytest.mark.one_step  # sweeps, not a choice of step

ROOT = Path(__file__).resolve().parents[2]
N = 24  # cases of the interrupted sweep
PAUSE = 0.15  # [s] each of them takes


def paced_job(x: int, log: str, pause: float) -> int:
    """x², after noting ``round x`` in ``log`` (the round from $SWEEP_ROUND) and ``pause`` seconds."""
    with open(log, "a") as f:
        f.write(f"{os.environ.get('SWEEP_ROUND', '?')} {x}\n")
    time.sleep(pause)
    return x * x


def paced_cases(log: Path) -> list[dict[str, object]]:
    return [{"x": x, "log": str(log), "pause": PAUSE} for x in range(N)]


SCRIPT = """
import sys
from pathlib import Path
from armctl.sim import sweep
from tests.sim.test_sweep_store import paced_cases, paced_job

sweep(paced_cases(Path(sys.argv[1])), run=paced_job, store=sys.argv[2], resume=sys.argv[3] == "resume",
      max_workers=2, progress=False)
"""


def _stored(store: Path) -> set[int]:
    return {int(p.stem) for p in (store / "outcomes").glob("*.pkl")}


def _started(log: Path, round_: str) -> set[int]:
    return {int(x) for r, x in (line.split() for line in log.read_text().splitlines()) if r == round_}


def _start(round_: str, log: Path, store: Path, resume: bool) -> subprocess.Popen[str]:
    env = {**os.environ, "SWEEP_ROUND": round_, "PYTHONPATH": f"{ROOT / 'src'}{os.pathsep}{ROOT}"}
    args = [sys.executable, "-c", SCRIPT, str(log), str(store), "resume" if resume else "new"]
    return subprocess.Popen(args, cwd=ROOT, env=env, stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)


def _wait_for(store: Path, count: int, proc: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + 120.0
    while len(_stored(store)) < count:
        assert proc.poll() is None, proc.communicate()[1][-3000:]
        assert time.monotonic() < deadline, "the sweep stores nothing"
        time.sleep(0.02)


@pytest.mark.slow
def test_a_sweep_interrupted_then_killed_resumes_without_running_a_finished_case_again(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    log, store = tmp_path / "starts.log", tmp_path / "store"
    log.touch()
    # round 1: Ctrl-C (SIGINT) once a few cases are stored
    proc = _start("1", log, store, resume=False)
    _wait_for(store, 4, proc)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode != 0 and "KeyboardInterrupt" in err
    after_1 = _stored(store)
    note = re.search(r"sweep interrupted: (\d+) of 24 cases are stored in '(.*?)'; run the same sweep with", err)
    assert note is not None, err[-3000:]
    assert int(note.group(1)) == len(after_1) and Path(note.group(2)) == store and "resume=True" in err
    lines = len(log.read_text().splitlines())
    time.sleep(3 * PAUSE)
    assert len(log.read_text().splitlines()) == lines  # the workers were stopped: nothing starts any more
    # round 2: resumed, then killed outright (SIGKILL: no handler runs) after a few more cases
    proc = _start("2", log, store, resume=True)
    _wait_for(store, len(after_1) + 3, proc)
    proc.kill()
    proc.communicate(timeout=60)
    time.sleep(2.5)  # the orphaned workers notice their parent is gone (within a second) and end
    after_2 = _stored(store)
    assert after_1 < after_2 and len(after_2) < N
    # round 3: resumed here, to the end
    monkeypatch.setenv("SWEEP_ROUND", "3")
    out = sweep(paced_cases(log), run=paced_job, store=store, resume=True, max_workers=2, progress=False)
    assert out == [x * x for x in range(N)] and _stored(store) == set(range(N))
    assert not _started(log, "2") & after_1  # no finished case ran again
    assert not _started(log, "3") & after_2
    assert _started(log, "3") == set(range(N)) - after_2  # and every other one ran
    assert not list((store / "outcomes").glob(".*"))  # no half-written file left behind
    table = SweepResult.load(store).to_dataframe()
    assert list(table["summary"]) == [x * x for x in range(N)] and set(table["outcome"]) == {"ok"}


def test_a_store_round_trips_to_the_same_table(tmp_path: Path) -> None:
    cases = failing_cases(tmp_path / "log", {2: "raise"}, n=5)
    with pytest.warns(Warning, match="1 raised"):
        out = sweep(cases, run=failing_job, store=tmp_path / "store", executor="serial", progress=False)
    assert out.store == str(tmp_path / "store")
    loaded = SweepResult.load(tmp_path / "store")
    assert [loaded[i] for i in (0, 1, 3, 4)] == [out[i] for i in (0, 1, 3, 4)] == [0, 1, 9, 16]
    assert (loaded[2].kind, loaded[2].error_type, loaded[2].traceback) == ("raised", "ValueError", out[2].traceback)
    assert isinstance(loaded[2], CaseFailure) and loaded[2].message == "x = 2 is not allowed"
    assert isinstance(loaded[2].exception, ValueError) and loaded[2].case == {"x": 2, "log": cases[2]["log"],
                                                                              "mode": "raise"}  # fmt: skip
    live, stored = out.to_dataframe(), loaded.to_dataframe()
    assert live.equals(stored)
    assert list(stored["outcome"]) == ["ok", "ok", "raised", "ok", "ok"]
    assert list(stored["summary"][[0, 1, 3, 4]]) == [0, 1, 9, 16]


def test_a_partial_store_loads_only_when_asked(tmp_path: Path) -> None:
    cases = [{"x": x, "log": str(tmp_path / "log"), "pause": 0.0} for x in range(4)]
    store = tmp_path / "store"
    sweep(cases, run=paced_job, store=store, executor="serial", progress=False)
    (store / "outcomes" / "00000002.pkl").unlink()  # as if case 2 had not finished
    with pytest.raises(InvalidParameterError, match=r"holds 3 of its 4 cases' outcomes.*resume=True"):
        SweepResult.load(store)
    partial = SweepResult.load(store, partial=True)
    assert partial.pending == {2} and partial[2] is None
    assert list(partial.to_dataframe()["outcome"]) == ["ok", "ok", "not_run", "ok"]
    again = sweep(cases, run=paced_job, store=store, resume=True, executor="serial", progress=False)
    assert again == [0, 1, 4, 9] and (tmp_path / "log").read_text().split()[-2:] == ["?", "2"]


def test_a_store_made_from_other_cases_is_refused_naming_the_difference(tmp_path: Path) -> None:
    log, store = tmp_path / "log", tmp_path / "store"
    cases = [{"x": x, "log": str(log), "pause": 0.0, "gain": np.array([1.0, 2.0])} for x in range(3)]
    sweep(cases, run=lambda x, log, pause, gain: x, store=store, executor="serial", progress=False)
    other = [dict(c) for c in cases]
    other[1]["gain"] = np.array([1.0, 2.5])
    with pytest.raises(InvalidParameterError, match=r"case 1 differs in 'gain' \(stored: '\[1.0, 2.0\]', given: "):
        sweep(other, run=lambda x, log, pause, gain: x, store=store, resume=True, executor="serial", progress=False)
    with pytest.raises(InvalidParameterError, match=r"made from other cases: it holds 3 cases, these are 2"):
        sweep(cases[:2], run=lambda x, log, pause, gain: x, store=store, resume=True, executor="serial")
    renamed = [{"y" if k == "x" else k: v for k, v in c.items()} for c in cases]
    with pytest.raises(InvalidParameterError, match=r"case 0 has the keys \['x'\] only in the store and \['y'\]"):
        sweep(renamed, run=lambda y, log, pause, gain: y, store=store, resume=True, executor="serial")
    with pytest.raises(InvalidParameterError, match=r"already holds 3 of these 3 cases' outcomes: pass resume=True"):
        sweep(cases, run=lambda x, log, pause, gain: x, store=store, executor="serial", progress=False)
    assert sweep(cases, run=lambda x, log, pause, gain: -1, store=store, resume=True, executor="serial") == [0, 1, 2]


def test_bad_store_arguments_are_named(tmp_path: Path) -> None:
    cases = [{"x": 1, "log": str(tmp_path / "log"), "pause": 0.0}]
    with pytest.raises(InvalidParameterError, match=r"resume=True needs the store to resume from"):
        sweep(cases, run=paced_job, resume=True, executor="serial")
    (tmp_path / "file").write_text("")
    with pytest.raises(InvalidParameterError, match=r"is a file, not a folder"):
        sweep(cases, run=paced_job, store=tmp_path / "file", executor="serial")
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "notes.txt").write_text("mine")
    with pytest.raises(InvalidParameterError, match=r"is not an empty folder nor a sweep store"):
        sweep(cases, run=paced_job, store=tmp_path / "full", executor="serial")
    with pytest.raises(InvalidParameterError, match=r"is not a sweep store \(it has no manifest.json\)"):
        SweepResult.load(tmp_path / "full")


def simulation_cases() -> list[dict[str, object]]:
    """Cases of simulate: a model, a Dynamics, controllers holding their own Dynamics, references, arrays."""
    import armctl
    from armctl.controllers import Adaptive, ComputedTorque
    from armctl.references import Quintic

    model = armctl.models.planar_2r()
    return [
        {
            "plant": model if kp < 1e3 else armctl.Dynamics(model),
            "controller": ComputedTorque(armctl.Dynamics(model), kp, 2 * kp**0.5),
            "reference": Quintic([0.0, 0.0], [0.3, -0.2], duration=0.5),
            "duration": 0.5,
            "q0": np.zeros(2),
        }
        for kp in (100.0, 1e3)
    ] + [{"plant": model, "controller": Adaptive(armctl.Dynamics(model), 5.0, 10.0, 0.1), "duration": 0.1,
          "reference": armctl.Reference.hold([0.1, 0.2])}]  # fmt: skip


def test_a_case_list_has_the_same_digests_in_another_process() -> None:
    """A study resumed from a new process builds its cases anew: their digests must be the same there (no
    address, hash seed or cache in them), or the store would be refused."""
    from armctl.sim.sweep_store import _manifest

    code = (
        "import json\nfrom armctl.sim.sweep_store import _manifest\n"
        "from tests.sim.test_sweep_store import simulation_cases\n"
        "print(json.dumps(_manifest(simulation_cases())['keys']))"
    )
    env = {**os.environ, "PYTHONPATH": f"{ROOT / 'src'}{os.pathsep}{ROOT}", "PYTHONHASHSEED": "123"}
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, check=True)
    here = _manifest(simulation_cases())["keys"]
    assert json.loads(out.stdout) == here
    assert len({d["controller"] for d in here}) == 3  # and the digests tell different controllers apart
