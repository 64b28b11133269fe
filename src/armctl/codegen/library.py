"""C code generated from CasADi functions, compiled once and cached on disk.

The cache key is the model's fingerprint, the backend options, the CasADi version and the compiler flags,
so a changed model rebuilds and an unchanged one loads in milliseconds. The cache lives in
``$ARMCTL_CACHE`` (default ``~/.cache/armctl``), in its ``casadi`` folder; it is safe to delete.

A library is opened only after it is checked (:mod:`armctl.codegen.library_cache`): its record's SHA-256 and
key before the dynamic loader sees it, the key generated into it after. A library that fails a check is
rebuilt with a :class:`~armctl.errors.CacheWarning`; a freshly compiled library that fails to load or holds
the wrong key is never cached and raises :class:`~armctl.errors.BackendError` naming the compiler. Loaded
libraries are kept for the life of the process (the one in-process cache of compiled code), so each is checked
once per process; a build is logged once, with the time it took (logger ``armctl.codegen``).
"""

from __future__ import annotations

import hashlib
import logging
import os
import shutil
import subprocess
import tempfile
import threading
import time
import warnings
from collections import OrderedDict
from collections.abc import Callable
from pathlib import Path

import casadi as cs

from armctl.codegen import library_cache
from armctl.codegen.toolchain import required
from armctl.errors import BackendError, CacheWarning, InvalidParameterError

CFLAGS = ("-O1", "-fPIC", "-shared")
#: the flags of a library whose code runs in a hot loop (the simulator's step): a slower build for faster code
CFLAGS_FAST = ("-O3", "-fPIC", "-shared")
Flags = tuple[str, ...]
#: bumped when what a library holds besides the user's functions changes (the key function), or how their code is
#: generated (:func:`merged`)
_LAYOUT = 3
#: libraries loaded by this process, by path, most recently used last (at most _KEEP)
_loaded: OrderedDict[Path, dict[str, cs.Function]] = OrderedDict()
_KEEP = 64
#: folders whose stale temporary folders this process has cleaned
_cleaned: set[Path] = set()
#: one thread of the process loads or builds at a time (builds across processes: the build lock)
_mutex = threading.Lock()
_log = logging.getLogger(__name__.rpartition(".")[0])  # armctl.codegen


def _after_fork() -> None:  # a child forked while another thread held the mutex would wait for it forever
    global _mutex
    _mutex = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_after_fork)


def cache_root(cache_dir: str | os.PathLike[str] | None = None) -> Path:
    """The cache folder: ``cache_dir`` if given, else ``$ARMCTL_CACHE``, else ``~/.cache/armctl``."""
    if cache_dir is not None:
        try:
            return Path(os.fspath(cache_dir))
        except TypeError:
            raise InvalidParameterError(
                f"cache_dir must be a path (str or os.PathLike) or None, got {cache_dir!r}", value=cache_dir
            ) from None
    env = os.environ.get("ARMCTL_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "armctl"


def cache_key(names: list[str], tag: str, flags: Flags | None = None) -> str:
    """The full key (SHA-256, 64 hex digits) of the library of the functions ``names`` with cache ``tag``, compiled
    with ``flags`` (default :data:`CFLAGS`)."""
    cflags = flags or CFLAGS
    return hashlib.sha256(f"{tag}|{cs.CasadiMeta.version()}|{cflags}|{names}|{_LAYOUT}".encode()).hexdigest()


def library_path(
    names: list[str], tag: str, cache_dir: str | os.PathLike[str] | None = None, flags: Flags | None = None
) -> Path:
    """Where the compiled library of the functions ``names`` with cache ``tag`` lives (it may not exist yet): an
    absolute path (CasADi looks for a relative one in its own folders first)."""
    return cache_root(cache_dir).absolute() / "casadi" / f"armctl_{cache_key(names, tag, flags)[:20]}.so"


def is_cached(
    names: list[str], tag: str, cache_dir: str | os.PathLike[str] | None = None, flags: Flags | None = None
) -> bool:
    """Whether the library of ``names`` and ``tag`` is cached and passes its checksum (loading it would not
    compile)."""
    return library_cache.check(library_path(names, tag, cache_dir, flags), cache_key(names, tag, flags)) is None


def compiled(
    functions: list[cs.Function], tag: str, cache_dir: str | os.PathLike[str] | None = None
) -> list[cs.Function]:
    """The same functions, evaluated by C code compiled from them (built on first use, then cached)."""
    names = [f.name() for f in functions]
    found = cached(names, tag, lambda: functions, cache_dir)
    return [found[name] for name in names]


def cached(
    names: list[str],
    tag: str,
    make: Callable[[], list[cs.Function]],
    cache_dir: str | os.PathLike[str] | None = None,
    source: str = "",
    flags: Flags | None = None,
    what: str = "",
) -> dict[str, cs.Function]:
    """The compiled functions ``names`` by name, from the library of ``tag``; ``make()`` (the symbolic
    functions, in the order of ``names``) is called only if the library is not cached yet, so that loading does
    not pay for building the symbolic model (0.2 s for 7 joints). ``source``: C code appended to the generated
    code (it may call the generated functions, and define functions of ``names`` that ``make`` does not make,
    with CasADi's external-function interface); ``tag`` must change when it does. ``flags``: the compiler's
    (default :data:`CFLAGS`; part of the library's key). ``what``: the code in words, for the one line logged
    (at WARNING, logger ``armctl.codegen``) with the time a build takes (default: the functions' names).

    Raises
    ------
    BackendError
        No C compiler, a compiler that fails or writes something that is not the library, or a cache folder
        that cannot be written to when a library has to be built.

    Warns
    -----
    CacheWarning
        The cached library failed its checks (truncated, altered, foreign) and was rebuilt.
    """
    names = list(names)
    lib = library_path(names, tag, cache_dir, flags)
    with _mutex:
        found = _loaded.get(lib)
        if found is None:
            found = _load_or_build(names, cache_key(names, tag, flags), lib, make, source, flags, what)
            _loaded[lib] = found
            while len(_loaded) > _KEEP:
                _loaded.popitem(last=False)
        else:
            _loaded.move_to_end(lib)
    return dict(found)


def _load_or_build(
    names: list[str],
    key: str,
    lib: Path,
    make: Callable[[], list[cs.Function]],
    source: str = "",
    flags: Flags | None = None,
    what: str = "",
) -> dict[str, cs.Function]:
    """The functions from ``lib`` if it passes its checks, else from a fresh build (under the build lock),
    logged with its time."""
    folder = lib.parent
    if folder not in _cleaned:
        _cleaned.add(folder)
        library_cache.clean_stale(folder)
    if library_cache.check(lib, key) is None:
        found, _ = _open(lib, names, key)
        if found is not None:
            return found
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise BackendError(
            f"cannot create the cache folder for compiled code {str(folder)!r} ({e}): pass a "
            "writable cache_dir or set $ARMCTL_CACHE",
            value=str(folder),
        ) from None
    with library_cache.build_lock(lib):  # another process may be building it: wait, then look again
        reason = library_cache.check(lib, key)
        if reason is None:
            found, reason = _open(lib, names, key)
            if found is not None:
                return found
        if reason != library_cache.MISSING:
            warnings.warn(
                f"the cached compiled library {str(lib)!r} cannot be trusted ({reason}); rebuilding it",
                CacheWarning,
                stacklevel=4,
            )
        library_cache.clean_stale(folder)
        library_cache.clean_key(lib)  # what builds of this library killed midway left (no other can be running)
        t0 = time.perf_counter()
        found = build(make(), lib, key, source, names, flags)
        _log.warning(
            "armctl: generated and compiled %s in %.1f s (cached in %s: later runs load it)",
            what or f"the functions {', '.join(names)}",
            time.perf_counter() - t0,
            folder.parent,
        )
        return found


def _open(path: Path, names: list[str], key: str) -> tuple[dict[str, cs.Function] | None, str | None]:
    """The functions ``names`` loaded from the library ``path`` and the reason (None) if it loads and its key
    function returns ``key``; (None, the reason) if not."""
    try:
        found = {name: cs.external(name, str(path)) for name in names}
        stamp = cs.external(library_cache.KEY_FUNCTION, str(path))
    except RuntimeError as e:
        return None, f"it does not load: {_loader_error(str(e), str(path))}"
    if not library_cache.key_matches(stamp, key):
        return None, "the key generated into it is another model's"
    return found, None


def _loader_error(message: str, path: str) -> str:
    """What the dynamic loader said about ``path`` in CasADi's ``message`` (which lists every folder it tried)."""
    for line in message.splitlines():
        head, _, said = line.strip().partition(f"{path}: ")
        if head == "Error code: " and said:
            return said
    return message.strip().splitlines()[-1][:300]


def merged(fn: cs.Function) -> cs.Function:
    """``fn`` with its common subexpressions evaluated once (CasADi's ``cse``): an SX function's expression
    graph can hold the same subexpression twice (built twice, as the forward kinematics of a contact point and of
    the dynamics are); the code generated from it then computes it twice. The values are the same; other
    functions are returned as they are."""
    if not fn.is_a("SXFunction"):
        return fn
    inputs = fn.sx_in()
    return cs.Function(fn.name(), inputs, fn.call(inputs), fn.name_in(), fn.name_out(), {"cse": True})


def build(
    functions: list[cs.Function],
    lib: Path,
    key: str,
    source: str = "",
    names: list[str] | None = None,
    flags: Flags | None = None,
) -> dict[str, cs.Function]:
    """Generate C code for ``functions`` (and the key function of ``key``), append ``source``, compile it (with
    ``flags``, default :data:`CFLAGS`) into a temporary folder beside ``lib``, load the functions ``names``
    (default: those of ``functions``) from there and check its key, then publish it as ``lib`` (renamed: never
    seen half-written) with its record. Returns the loaded functions by name. The caller holds the build lock.

    Raises
    ------
    BackendError
        No C compiler; the compiler failed, or exited without error but wrote no library, one that does not
        load, or one that holds another key (nothing is cached then); the folder cannot be written to.
    """
    cc = required()
    folder, stem = lib.parent, lib.stem
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f"{stem}-", suffix=".build", dir=folder))
    except OSError as e:
        raise library_cache.unwritable(folder, e) from None
    try:
        gen = cs.CodeGenerator(f"{stem}.c", {"with_header": False})
        for f in functions:
            gen.add(merged(f))
        gen.add(library_cache.key_function(key))
        try:
            src = Path(gen.generate(str(tmp) + os.sep))
        except RuntimeError as e:
            raise BackendError(f"cannot write generated code into {str(tmp)!r}: {e}", value=str(folder)) from None
        if source:
            with open(src, "a") as out:
                out.write("\n" + source)
        tmp_lib = tmp / f"{stem}.so"
        proc = subprocess.run(
            [cc, *(flags or CFLAGS), str(src), "-o", str(tmp_lib), "-lm"], capture_output=True, text=True, check=False
        )
        if proc.returncode != 0:
            raise BackendError(f"compiling generated code failed ({cc}): {proc.stderr[-2000:]}", value=str(src))
        names = names if names is not None else [f.name() for f in functions]
        reason: str | None
        try:
            data = tmp_lib.read_bytes()
        except OSError:
            found, reason = None, "wrote no library"
        else:
            found, reason = _open(tmp_lib, names, key)
            reason = reason and f"wrote a library that cannot be used: {reason}"
        if found is None:
            raise BackendError(
                f"the C compiler {cc!r} exited without error but {reason}; nothing was cached: set $CC to a "
                "working C compiler (e.g. gcc or clang), or do without compiled code (compile=False)",
                value=cc,
            )
        try:
            os.replace(tmp_lib, lib)  # loaded from its temporary name: the mapping stays valid
            library_cache.write_record(lib, key, data, tmp)
        except OSError as e:
            raise library_cache.unwritable(folder, e) from None
        return found
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
