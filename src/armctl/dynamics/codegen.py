"""C code generated from CasADi functions, compiled once and cached on disk.

The cache key is the model's fingerprint, the backend options, the CasADi version and the compiler flags,
so a changed model rebuilds and an unchanged one loads in milliseconds. The cache lives in
``$ARMCTL_CACHE`` (default ``~/.cache/armctl``); it is safe to delete.
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Callable
from pathlib import Path

import casadi as cs

from armctl.errors import BackendError, InvalidParameterError

CFLAGS = ("-O1", "-fPIC", "-shared")


def cache_root(cache_dir: str | os.PathLike[str] | None = None) -> Path:
    if cache_dir is not None:
        try:
            return Path(os.fspath(cache_dir))
        except TypeError:
            raise InvalidParameterError(
                f"cache_dir must be a path (str or os.PathLike) or None, got {cache_dir!r}", value=cache_dir
            ) from None
    env = os.environ.get("ARMCTL_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "armctl"


def library_path(names: list[str], tag: str, cache_dir: str | os.PathLike[str] | None = None) -> Path:
    """Where the compiled library of the functions ``names`` with cache ``tag`` lives (it may not exist yet)."""
    key = hashlib.sha256(f"{tag}|{cs.__version__}|{CFLAGS}|{names}".encode())
    return cache_root(cache_dir) / "casadi" / f"armctl_{key.hexdigest()[:20]}.so"


def compiled(
    functions: list[cs.Function], tag: str, cache_dir: str | os.PathLike[str] | None = None
) -> list[cs.Function]:
    """The same functions, evaluated by C code compiled from them (built on first use, then cached)."""
    names = [f.name() for f in functions]
    found = cached(names, tag, lambda: functions, cache_dir)
    return [found[name] for name in names]


def cached(
    names: list[str], tag: str, make: Callable[[], list[cs.Function]], cache_dir: str | os.PathLike[str] | None = None
) -> dict[str, cs.Function]:
    """The compiled functions ``names`` by name, from the library of ``tag``; ``make()`` (the symbolic
    functions, in the order of ``names``) is called only if the library is not cached yet, so that loading does
    not pay for building the symbolic model (0.2 s for 7 joints)."""
    lib = library_path(names, tag, cache_dir)
    if not lib.exists():
        build(make(), lib)
    return {name: _load(name, str(lib)) for name in names}


@functools.lru_cache(maxsize=64)
def _load(name: str, path: str) -> cs.Function:
    return cs.external(name, path)


def build(functions: list[cs.Function], lib: Path) -> None:
    """Generate C code for ``functions`` and compile it into the shared library ``lib`` (replaced atomically:
    concurrent builders never load a half-written library)."""
    cc = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    folder, name = lib.parent, lib.stem
    if cc is None:
        raise BackendError(
            "compiling generated code needs a C compiler (cc or gcc on PATH, or $CC): install "
            "one, or do without compiled code (compile=False)",
            value=None,
        )
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise BackendError(
            f"cannot create the cache folder for compiled code {str(folder)!r} ({e}): pass a "
            "writable cache_dir or set $ARMCTL_CACHE",
            value=str(folder),
        ) from None
    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        gen = cs.CodeGenerator(f"{name}.c", {"with_header": False})
        for f in functions:
            gen.add(f)
        src = Path(gen.generate(tmp + os.sep))
        tmp_lib = Path(tmp) / f"{name}.so"
        proc = subprocess.run(
            [cc, *CFLAGS, str(src), "-o", str(tmp_lib), "-lm"], capture_output=True, text=True, check=False
        )
        if proc.returncode != 0:
            raise BackendError(f"compiling generated code failed ({cc}): {proc.stderr[-2000:]}", value=str(src))
        os.replace(tmp_lib, lib)
