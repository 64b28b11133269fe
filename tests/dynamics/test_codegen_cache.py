"""The cache of compiled libraries heals instead of crashing or lying.

Damage is done to real files of a cache in a temporary folder (truncated, bytes flipped, garbage, empty,
another model's library under the expected name); a library that may be damaged is only ever loaded in a child
process, since a loader that maps it may crash the process (SIGBUS, SIGSEGV). Compilers are real scripts given as
``$CC`` (one that exits 0 and writes garbage, one that hangs and is killed with its build). Every result is
checked against the uncompiled Pinocchio backend (an independent evaluation of the same model).
"""

from __future__ import annotations

import fcntl
import json
import os
import shutil
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import armctl
from armctl.errors import BackendError, CacheWarning

SRC = Path(armctl.__file__).resolve().parents[1]
Q = [0.3, -0.4]
QD = [0.5, 0.2]
TAU = [1.0, -2.0]

# Loads (or builds) one user of the cache in a child process and prints what it computed and every warning
CHILD = f"""
import json, sys, warnings
import numpy as np
import armctl
from armctl.sim.compiled import compiled_step

user, cache, payload = sys.argv[1], sys.argv[2], float(sys.argv[3])
q, qd, tau = np.array({Q}), np.array({QD}), np.array({TAU})
model = armctl.models.planar_2r().reduced(friction=False)
if payload:
    model = model.with_payload(payload, (0.1, 0.0, 0.0))
with warnings.catch_warnings(record=True) as seen:
    warnings.simplefilter("always")
    if user == "dynamics":
        out = armctl.Dynamics(model, compile=True, cache_dir=cache).gravity_torque(q)
    elif user == "lagrange":
        dyn = armctl.Dynamics(model, backend="lagrange", rotor_coupling=False, compile=True, cache_dir=cache)
        out = dyn.mass_matrix(q).ravel()
    else:
        out = compiled_step(model, "euler", cache_dir=cache)(q, qd, tau, 1e-3)[2]
print(json.dumps({{"out": out.tolist(), "warnings": [[type(w.message).__name__, str(w.message)] for w in seen]}}))
"""


def _model(payload: float = 0.0) -> armctl.RobotModel:
    model = armctl.models.planar_2r().reduced(friction=False)
    return model.with_payload(payload, (0.1, 0.0, 0.0)) if payload else model


def _reference(user: str, payload: float = 0.0) -> np.ndarray:
    """What the child computes, from the uncompiled Pinocchio backend."""
    dyn = armctl.Dynamics(_model(payload))
    q = np.array(Q)
    if user == "dynamics":
        return dyn.gravity_torque(q)
    if user == "lagrange":
        return dyn.mass_matrix(q).ravel()
    return dyn.forward_dynamics(q, np.array(QD), np.array(TAU))


def _build(cache: Path, user: str = "dynamics", payload: float = 0.0) -> np.ndarray:
    """Build the library of ``user`` in this process and return what it computes. Only for libraries that are
    never damaged in place afterwards: a file the process has mapped, rewritten in place, crashes the process
    (SIGBUS) — which is why the cache only ever replaces files by renaming."""
    from armctl.sim.compiled import compiled_step

    model, q = _model(payload), np.array(Q)
    if user == "dynamics":
        return armctl.Dynamics(model, compile=True, cache_dir=cache).gravity_torque(q)
    if user == "lagrange":
        dyn = armctl.Dynamics(model, backend="lagrange", rotor_coupling=False, compile=True, cache_dir=cache)
        return dyn.mass_matrix(q).ravel()
    return compiled_step(model, "euler", cache_dir=cache)(q, np.array(QD), np.array(TAU), 1e-3)[2].copy()


def _built_cache(tmp_path: Path, user: str = "dynamics", payloads: tuple[float, ...] = (0.0,)) -> Path:
    """A cache holding the libraries of ``user`` for ``payloads``: built in this process, then copied (new
    files, which this process has not mapped and the test may damage in place)."""
    for payload in payloads:
        np.testing.assert_allclose(
            _build(tmp_path / "built", user, payload), _reference(user, payload), rtol=1e-10, atol=1e-12
        )
    return Path(shutil.copytree(tmp_path / "built", tmp_path / "cache"))


def _child(
    cache: Path, user: str = "dynamics", payload: float = 0.0, env: dict[str, str] | None = None, **popen: object
) -> subprocess.Popen[str]:
    environ = {**os.environ, "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")])}
    return subprocess.Popen(
        [sys.executable, "-c", CHILD, user, str(cache), str(payload)],
        env={**environ, **(env or {})},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **popen,  # type: ignore[call-overload]
    )


def _run(cache: Path, user: str = "dynamics", payload: float = 0.0, env: dict[str, str] | None = None) -> dict:
    """Run the child to its end; it must exit normally (not crash, not raise)."""
    proc = _child(cache, user, payload, env)
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, f"the child exited with {proc.returncode}: {err[-3000:]}"
    return json.loads(out.splitlines()[-1])  # type: ignore[no-any-return]


def _libraries(cache: Path) -> list[Path]:
    return sorted((cache / "casadi").glob("*.so"))


def _build_folders(cache: Path) -> list[Path]:
    return sorted(p for p in (cache / "casadi").iterdir() if p.is_dir())


def _script(path: Path, body: str) -> Path:
    """An executable shell script (a fake C compiler)."""
    path.write_text("#!/bin/sh\n" + body)
    path.chmod(0o755)
    return path


def _output_argument() -> str:
    return 'while [ $# -gt 0 ]; do if [ "$1" = "-o" ]; then out="$2"; fi; shift; done\n'


def _damage(lib: Path, how: str) -> None:
    data = lib.read_bytes()
    if how == "truncated":  # was: SIGBUS when the loader touched the missing pages
        lib.write_bytes(data[: len(data) // 2])
    elif how == "flipped":  # was: SIGSEGV or an abort inside the loader
        flipped = bytearray(data)
        for i in range(0x1000, len(flipped), 97):
            flipped[i] ^= 0xFF
        lib.write_bytes(bytes(flipped))
    elif how == "garbage":  # was: DllLibrary::init_handle on every later run
        lib.write_bytes(b"not a shared library\n" * 50)
    else:  # "empty": the same
        lib.write_bytes(b"")


@pytest.mark.parametrize("how", ["truncated", "flipped", "garbage", "empty"])
def test_a_damaged_library_is_rebuilt_with_one_warning_instead_of_crashing(tmp_path: Path, how: str) -> None:
    """A truncated cached library gave SIGBUS, flipped bytes SIGSEGV, and a garbage or empty file a RuntimeError
    (DllLibrary::init_handle) on every later run. Now the run that finds it rebuilds it with one warning naming
    the file, computes the right gravity, and the next run loads the rebuilt library silently."""
    cache = _built_cache(tmp_path)
    (lib,) = _libraries(cache)
    _damage(lib, how)
    healed = _run(cache)
    assert [w[0] for w in healed["warnings"]] == ["CacheWarning"] and str(lib) in healed["warnings"][0][1]
    np.testing.assert_allclose(healed["out"], _reference("dynamics"), rtol=1e-12)
    after = _run(cache)
    assert after["warnings"] == [] and _libraries(cache) == [lib]
    np.testing.assert_allclose(after["out"], _reference("dynamics"), rtol=1e-12)


@pytest.mark.parametrize("user", ["lagrange", "step"])
def test_every_user_of_the_cache_heals_a_truncated_library(tmp_path: Path, user: str) -> None:
    """The Lagrange backend's compile=True and simulate's compiled step crashed on a truncated library as
    Dynamics(compile=True) did; they heal the same way (M from the Lagrange code against Pinocchio's CRBA, the
    step's q̈ against Pinocchio's ABA)."""
    cache = _built_cache(tmp_path, user)
    (lib,) = _libraries(cache)
    _damage(lib, "truncated")
    if user == "lagrange":  # does not say yes to a library that cannot be loaded
        from armctl.dynamics.lagrange import LagrangeDynamics

        assert not LagrangeDynamics.is_compiled_cached(_model(), rotor_coupling=False, cache_dir=str(cache))
    healed = _run(cache, user)
    assert [w[0] for w in healed["warnings"]] == ["CacheWarning"]
    np.testing.assert_allclose(healed["out"], _reference(user), rtol=1e-10, atol=1e-12)
    assert _run(cache, user)["warnings"] == []


def _with_a_foreign_library(tmp_path: Path) -> tuple[Path, Path, Path]:
    """A cache holding the library of the arm and that of the arm with a 2 kg payload (same functions, same
    sizes, other numbers): (the cache, the arm's library, the payload's)."""
    _build(tmp_path / "built")
    (base,) = _libraries(tmp_path / "built")
    _built_cache(tmp_path, payloads=(2.0,))
    lib = tmp_path / "cache" / "casadi" / base.name
    (other,) = set(_libraries(tmp_path / "cache")) - {lib}
    return tmp_path / "cache", lib, other


def test_another_models_library_under_the_expected_name_is_not_used(tmp_path: Path) -> None:
    """Another model's library copied over the expected file loaded, and gave that model's dynamics (off by
    994 in the case first seen; here the payload's gravity). Now it is rebuilt with one warning."""
    cache, lib, other = _with_a_foreign_library(tmp_path)
    shutil.copyfile(other, lib)
    assert not np.allclose(_reference("dynamics", 2.0), _reference("dynamics"), rtol=1e-3)  # the test can fail
    healed = _run(cache)
    assert [w[0] for w in healed["warnings"]] == ["CacheWarning"]
    np.testing.assert_allclose(healed["out"], _reference("dynamics"), rtol=1e-12)


def test_another_models_library_with_a_record_claiming_the_key_is_caught_by_its_embedded_key(
    tmp_path: Path,
) -> None:
    """A foreign library copied together with its record, the record edited to name the expected key (so that
    size and SHA-256 match): the key generated into the library differs, it is rebuilt with one warning."""
    from armctl.codegen.library_cache import record_path

    cache, lib, other = _with_a_foreign_library(tmp_path)
    record = json.loads(record_path(lib).read_text())
    shutil.copyfile(other, lib)
    forged = json.loads(record_path(other).read_text()) | {"key": record["key"]}
    record_path(lib).write_text(json.dumps(forged))
    healed = _run(cache)
    assert [w[0] for w in healed["warnings"]] == ["CacheWarning"]
    assert "key generated into it" in healed["warnings"][0][1]
    np.testing.assert_allclose(healed["out"], _reference("dynamics"), rtol=1e-12)
    assert _run(cache)["warnings"] == []


@pytest.mark.parametrize("writes", ["garbage", "nothing", "another library"])
def test_a_compiler_that_exits_0_without_a_usable_library_is_named_and_poisons_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, writes: str
) -> None:
    """A $CC that exited 0 and wrote garbage had its output cached, and every later run failed even with a
    working compiler. Now the fresh library is loaded and its key checked before it is cached: BackendError
    naming the compiler and the way out, nothing left in the cache, and a working compiler then builds."""
    cache = tmp_path / "cache"
    if writes == "another library":  # a real library, of another model (loads; its embedded key differs)
        _build(tmp_path / "elsewhere", payload=2.0)
        (foreign,) = _libraries(tmp_path / "elsewhere")
        body = f'cp "{foreign}" "$out"\n'
    else:
        body = 'printf "garbage" > "$out"\n' if writes == "garbage" else ""
    cc = _script(tmp_path / "bad-cc", _output_argument() + body + "exit 0\n")
    monkeypatch.setenv("CC", str(cc))
    with pytest.raises(BackendError, match=r"the C compiler .*bad-cc.* exited without error") as err:
        armctl.Dynamics(_model(), compile=True, cache_dir=cache)
    assert "$CC" in str(err.value) and "compile=False" in str(err.value)
    assert [p.name for p in (cache / "casadi").iterdir() if p.suffix != ".lock"] == []  # (an empty lock file)
    monkeypatch.delenv("CC")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        np.testing.assert_allclose(_build(cache), _reference("dynamics"), rtol=1e-12)
    assert [w.message for w in seen if issubclass(w.category, CacheWarning)] == []


def _kill_a_build_while_it_compiles(tmp_path: Path, cache: Path) -> None:
    """Start a build of the test model into ``cache`` in a child process whose $CC hangs, and kill the child and
    its compiler (SIGKILL) once the compiler runs."""
    started = tmp_path / "compiler-started"
    cc = _script(tmp_path / "hanging-cc", f'touch "{started}"\nexec sleep 300\n')
    child = _child(cache, env={"CC": str(cc)}, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while not started.exists():
            assert child.poll() is None and time.monotonic() < deadline, child.communicate()[1][-3000:]
            time.sleep(0.05)
    finally:
        os.killpg(child.pid, signal.SIGKILL)
        child.communicate()


def test_a_build_killed_midway_leaves_no_folder_behind_for_long(tmp_path: Path) -> None:
    """A build killed while compiling left its temporary folder (generated C included) in the cache forever.
    The child is killed (SIGKILL, its compiler too) while its $CC runs; the folder is there, and once it is
    older than the stale age and no build holds its lock, the next process to use the cache removes it."""
    from armctl.codegen.library_cache import STALE_AFTER

    cache = tmp_path / "cache"
    _kill_a_build_while_it_compiles(tmp_path, cache)
    (left,) = _build_folders(cache)
    assert any(left.glob("*.c")) and _libraries(cache) == []
    old = time.time() - STALE_AFTER - 60
    os.utime(left, (old, old))
    dyn = armctl.Dynamics(_model(), compile=True, cache_dir=cache)
    assert _build_folders(cache) == []
    np.testing.assert_allclose(dyn.gravity_torque(np.array(Q)), _reference("dynamics"), rtol=1e-12)


def test_stale_cleaning_spares_live_and_recent_builds(tmp_path: Path) -> None:
    """Only folders both old and unlocked go: an old folder whose build lock another process holds (a build
    still compiling) and a recent unlocked one stay; an old unlocked one and an old ``tmp*`` folder (left by
    builds that took no lock) are removed; libraries, records and other files are never touched."""
    from armctl.codegen.library_cache import STALE_AFTER, clean_stale

    folder = tmp_path / "casadi"
    folder.mkdir()
    for name in ("armctl_aaaa-x1.build", "armctl_bbbb-x2.build", "armctl_cccc-x3.build", "tmpq8w1"):
        (folder / name).mkdir()
    (folder / "armctl_dddd.so").write_bytes(b"x")
    old = time.time() - STALE_AFTER - 60
    for name in ("armctl_aaaa-x1.build", "armctl_cccc-x3.build", "tmpq8w1", "armctl_dddd.so"):
        os.utime(folder / name, (old, old))
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import fcntl, os, sys, time\n"
            "fd = os.open(sys.argv[1], os.O_RDWR | os.O_CREAT)\n"
            "fcntl.flock(fd, fcntl.LOCK_EX)\n"
            "print('locked', flush=True)\n"
            "time.sleep(300)\n",
            str(folder / "armctl_aaaa.lock"),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "locked"
        removed = clean_stale(folder)
    finally:
        holder.kill()
        holder.wait()
    assert sorted(p.name for p in removed) == ["armctl_cccc-x3.build", "tmpq8w1"]
    assert {p.name for p in folder.iterdir()} == {
        "armctl_aaaa.lock",
        "armctl_aaaa-x1.build",
        "armctl_bbbb-x2.build",
        "armctl_dddd.so",
    }
    fd = os.open(folder / "armctl_aaaa.lock", os.O_RDONLY)  # released by the holder's death: now it goes
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    finally:
        os.close(fd)
    assert sorted(p.name for p in clean_stale(folder)) == ["armctl_aaaa-x1.build", "armctl_aaaa.lock"]
    assert {p.name for p in folder.iterdir()} == {"armctl_bbbb-x2.build", "armctl_dddd.so"}


def test_the_next_build_after_a_build_killed_midway_leaves_nothing_stale(tmp_path: Path) -> None:
    """A build killed (SIGKILL, its compiler too) while its $CC runs leaves its temporary folder and its lock file;
    the next build of the same library, at once (no waiting for the stale age), succeeds and leaves neither
    behind: the folder is the dead build's (no other build of the library can run while the lock is held), and
    the lock's owner is dead. What the library computes is checked against the uncompiled backend."""
    cache = tmp_path / "cache"
    _kill_a_build_while_it_compiles(tmp_path, cache)
    folder = cache / "casadi"
    assert len(_build_folders(cache)) == 1 and len(list(folder.glob("*.lock"))) == 1  # what the kill left
    dyn = armctl.Dynamics(_model(), compile=True, cache_dir=cache)
    np.testing.assert_allclose(dyn.gravity_torque(np.array(Q)), _reference("dynamics"), rtol=1e-12)
    assert _build_folders(cache) == [] and list(folder.glob("*.lock")) == []
    assert [p.suffix for p in sorted(folder.iterdir())] == [".json", ".so"]


def _make_read_only(folder: Path) -> str:
    """Make ``folder`` refuse new entries: chmod for a user, the immutable attribute for root (whom chmod does
    not stop). Returns how, or skips the test if neither works here."""
    if os.geteuid() != 0:
        folder.chmod(0o555)
        how = "chmod"
    else:
        chattr = shutil.which("chattr")
        if chattr is None or subprocess.run([chattr, "+i", str(folder)], capture_output=True).returncode != 0:
            pytest.skip("running as root, and the immutable attribute (chattr +i) is not available here")
        how = "chattr"
    try:
        (folder / "probe").mkdir()
    except OSError:
        return how
    (folder / "probe").rmdir()
    _make_writable(folder, how)
    pytest.skip(f"{folder} stays writable after {how}: cannot test an unwritable cache here")


def _make_writable(folder: Path, how: str) -> None:
    if how == "chmod":
        folder.chmod(0o755)
    else:
        subprocess.run(["chattr", "-i", str(folder)], check=True)


def test_an_unwritable_cache_folder_is_named_with_the_way_out(tmp_path: Path) -> None:
    """A read-only casadi/ folder gave a raw PermissionError. Now: BackendError naming the folder, cache_dir
    and $ARMCTL_CACHE. A casadi/ that is a regular file (works without privileges) too."""
    cache = tmp_path / "cache"
    folder = cache / "casadi"
    folder.mkdir(parents=True)
    how = _make_read_only(folder)
    try:
        with pytest.raises(BackendError) as err:
            armctl.Dynamics(_model(), compile=True, cache_dir=cache)
    finally:
        _make_writable(folder, how)
    assert str(folder) in str(err.value) and "cache_dir" in str(err.value) and "ARMCTL_CACHE" in str(err.value)
    other = tmp_path / "other"
    other.mkdir()
    (other / "casadi").write_text("a file where the folder goes")
    with pytest.raises(BackendError, match="cache_dir") as err:
        armctl.Dynamics(_model(), compile=True, cache_dir=other)
    assert str(other / "casadi") in str(err.value) and "ARMCTL_CACHE" in str(err.value)


def test_a_read_only_cache_holding_good_libraries_loads_them(tmp_path: Path) -> None:
    """Loading needs no write (no lock, no record): a cache made read-only after its build serves its library."""
    cache = tmp_path / "cache"
    _build(cache)
    folder = cache / "casadi"
    how = _make_read_only(folder)
    try:
        loaded = _run(cache)
    finally:
        _make_writable(folder, how)
    assert loaded["warnings"] == []
    np.testing.assert_allclose(loaded["out"], _reference("dynamics"), rtol=1e-12)


def test_two_processes_building_one_library_at_once_build_it_once(tmp_path: Path) -> None:
    """Two processes start the same build together (a slow $CC makes them overlap): both get the right
    gravity without a warning; the library is compiled once (the second waits for the first's build lock and
    loads its library), passes its checks, and no temporary folder is left."""
    cache, log = tmp_path / "cache", tmp_path / "compiles"
    real = shutil.which("cc") or shutil.which("gcc")
    if real is None:
        pytest.skip("no C compiler")
    cc = _script(tmp_path / "slow-cc", f'echo run >> "{log}"\nsleep 1\nexec "{real}" "$@"\n')
    children = [_child(cache, env={"CC": str(cc)}) for _ in range(2)]
    for child in children:
        out, err = child.communicate(timeout=300)
        assert child.returncode == 0, err[-3000:]
        result = json.loads(out.splitlines()[-1])
        assert result["warnings"] == []
        np.testing.assert_allclose(result["out"], _reference("dynamics"), rtol=1e-12)
    assert log.read_text().split() == ["run"]
    assert len(_libraries(cache)) == 1 and _build_folders(cache) == []
    assert _run(cache)["warnings"] == []  # what they left passes its checks
