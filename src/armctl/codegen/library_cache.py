"""Why a compiled library found in the cache can be trusted: its record, its embedded key, its lock.

A library ``armctl_<key>.so`` of the cache (see :mod:`armctl.codegen.library`) is published in steps that are
each atomic: it is compiled and checked in a temporary folder of the cache (``armctl_<key>-<random>.build``),
renamed into place, and then its *record* ``armctl_<key>.json`` is written beside it (into the temporary folder
first, then renamed). The record holds the library's size, its SHA-256 and the full key it was built for.

Before a library is handed to the dynamic loader, its record must exist, name the expected key, and match the
file's size and SHA-256 (:func:`check`): a truncated, altered, empty or foreign file is never opened — the
loader would crash on it (SIGBUS on a truncated file, SIGSEGV or an abort on altered bytes). After it is opened,
a function generated into the library, :data:`KEY_FUNCTION`, returns the key it was generated for, which must
match as well (:func:`key_matches`): a library copied from another model together with a record that claims
the expected key fails there.

Builds of one library are serialised across processes by ``flock`` on ``armctl_<key>.lock`` (:func:`build_lock`),
held from before its temporary folder is made until the library is published, and removed by its holder when it
is done (a process that locked a lock file that was removed meanwhile locks the new one instead). A build killed
midway (SIGKILL) leaves its temporary folder and its lock file, which no live process holds: the next build of
the same library removes the library's temporary folders (:func:`clean_key`, under the lock: no other build of it
runs), and the first use of the cache folder in a process removes lock files nobody holds and temporary folders
older than :data:`STALE_AFTER` whose lock nobody holds (:func:`clean_stale`).
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import casadi as cs
import numpy as np

from armctl.errors import BackendError

#: the name of the function generated into every library, returning the library's key (see :func:`key_code`)
KEY_FUNCTION = "armctl_cache_key"
#: a temporary folder of the cache older than this [s], and not locked by a build, is removed
STALE_AFTER = 15 * 60.0
#: what :func:`check` returns for a library that is not there (nothing to distrust: it is simply built)
MISSING = "missing"


def record_path(lib: Path) -> Path:
    """The record (size, SHA-256, key) of the library ``lib``."""
    return lib.with_suffix(".json")


def lock_path(lib: Path) -> Path:
    """The lock file held while ``lib`` is built."""
    return lib.with_suffix(".lock")


def unwritable(folder: Path, err: OSError) -> BackendError:
    """The error for a cache folder that cannot be written to (``err``: what the system said)."""
    return BackendError(
        f"the cache folder for compiled code {str(folder)!r} is not writable ({err.strerror or err}): pass a "
        "writable folder as cache_dir=, or set $ARMCTL_CACHE to one",
        value=str(folder),
    )


def check(lib: Path, key: str) -> str | None:
    """Why the library ``lib`` cannot be trusted as the build of ``key`` (a full SHA-256 in hex), or None if
    its record names ``key`` and matches the file's size and SHA-256; :data:`MISSING` if there is no library.
    Reads the file once (a library is checked once per process)."""
    try:
        data = lib.read_bytes()
    except FileNotFoundError:
        return MISSING
    except OSError as e:
        return f"it cannot be read: {e.strerror or e}"
    try:
        record = json.loads(record_path(lib).read_text())
        size, digest, built_for = int(record["size"]), str(record["sha256"]), str(record["key"])
    except FileNotFoundError:
        return "it has no record of its checksum"
    except (OSError, ValueError, TypeError, KeyError) as e:
        return f"its record cannot be read: {e!r}"
    if built_for != key:
        return "its record says it was built for another model or other options"
    if len(data) != size:
        return f"it holds {len(data)} bytes where {size} were written: truncated or overwritten"
    if hashlib.sha256(data).hexdigest() != digest:
        return "its SHA-256 differs from the one written with it: altered"
    return None


def write_record(lib: Path, key: str, data: bytes, scratch: Path) -> None:
    """Write the record of the library ``lib`` holding ``data`` built for ``key``: into the folder ``scratch``
    first, then renamed beside ``lib`` (same file system), so that it is never seen half-written."""
    tmp = scratch / record_path(lib).name
    record = {"key": key, "size": len(data), "sha256": hashlib.sha256(data).hexdigest()}
    tmp.write_text(json.dumps(record))
    os.replace(tmp, record_path(lib))


def key_code(key: str) -> list[float]:
    """The 256 bits of ``key`` (64 hex digits) as eight 32-bit integers, each exact in a double."""
    return [float(int(key[i : i + 8], 16)) for i in range(0, 64, 8)]


def key_function(key: str) -> cs.Function:
    """The function :data:`KEY_FUNCTION` generated into the library of ``key``: no input, :func:`key_code` out."""
    return cs.Function(KEY_FUNCTION, [], [cs.DM(key_code(key))])


def key_matches(stamp: cs.Function, key: str) -> bool:
    """Whether the :data:`KEY_FUNCTION` ``stamp`` loaded from a library returns the code of ``key``."""
    try:
        out = np.asarray(stamp.call([])[0], dtype=float).ravel()
    except RuntimeError:
        return False
    return out.tolist() == key_code(key)


@contextmanager
def build_lock(lib: Path) -> Iterator[None]:
    """Hold the build lock of ``lib`` (waiting for another process that holds it); the lock file is removed when
    the block ends. Raises :class:`~armctl.errors.BackendError` if the lock file cannot be created (an unwritable
    cache folder)."""
    import fcntl

    path = lock_path(lib)
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as e:
            raise unwritable(lib.parent, e) from None
        fcntl.flock(fd, fcntl.LOCK_EX)
        if _still_named(fd, path):
            break
        os.close(fd)  # its holder removed it while this process waited: lock the file the name now gives
    try:
        yield
    finally:
        _remove(path)
        os.close(fd)  # releases the lock


def _still_named(fd: int, path: Path) -> bool:
    """Whether the open file ``fd`` is still the file named ``path`` (not removed, not replaced)."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return False
    own = os.fstat(fd)
    return (st.st_dev, st.st_ino) == (own.st_dev, own.st_ino)


def _remove(path: Path) -> None:
    try:
        os.unlink(path)
    except OSError:  # a read-only folder, or gone already: harmless, the next holder locks it as it is
        pass


def _is_locked(lock: Path) -> bool:
    """Whether another open file (this process's included) holds ``lock``; False if it does not exist."""
    import fcntl

    try:
        fd = os.open(lock, os.O_RDONLY)
    except FileNotFoundError:
        return False
    except OSError:
        return True  # cannot tell: leave it be
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False


def _remove_if_free(lock: Path) -> bool:
    """Remove the lock file ``lock`` if no process holds it (its holder died: a build killed midway); True if
    removed. It is locked while it is removed, so that no process takes it meanwhile."""
    import fcntl

    try:
        fd = os.open(lock, os.O_RDONLY)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        return False
    try:
        if not _still_named(fd, lock):
            return False
        _remove(lock)
        return not lock.exists()
    finally:
        os.close(fd)


def clean_key(lib: Path) -> list[Path]:
    """Remove the temporary folders of builds of ``lib`` (``armctl_<key>-<random>.build``) that were killed
    midway: the caller holds the build lock of ``lib``, so no build of it is running. Returns the folders
    removed."""
    removed = []
    for folder in lib.parent.glob(f"{lib.stem}-*.build"):
        shutil.rmtree(folder, ignore_errors=True)
        if not folder.exists():
            removed.append(folder)
    return removed


def clean_stale(folder: Path, now: float | None = None) -> list[Path]:
    """Remove what killed builds left in ``folder``: the lock files ``armctl_<key>.lock`` that no process holds,
    the temporary folders older than :data:`STALE_AFTER` (by modification time, ``now`` the current time [s
    since the epoch]) whose build lock nobody holds (``armctl_<key>-<random>.build``), and the unlocked ``tmp*``
    folders of builds that took no lock. Best effort: what cannot be removed (a read-only folder) stays.
    Returns the files and folders removed."""
    now = time.time() if now is None else now
    removed: list[Path] = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    for entry in entries:
        name = entry.name
        if name.startswith("armctl_") and name.endswith(".lock"):
            if _remove_if_free(Path(entry.path)):
                removed.append(Path(entry.path))
            continue
        ours = name.startswith("armctl_") and name.endswith(".build")
        if not (ours or name.startswith("tmp")):
            continue
        try:
            if not entry.is_dir(follow_symlinks=False) or now - entry.stat().st_mtime < STALE_AFTER:
                continue
        except OSError:
            continue
        if ours and _is_locked(folder / f"{name.split('-')[0]}.lock"):
            continue
        shutil.rmtree(entry.path, ignore_errors=True)
        if not os.path.exists(entry.path):
            removed.append(Path(entry.path))
    return removed
