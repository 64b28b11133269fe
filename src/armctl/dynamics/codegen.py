"""C code generated from CasADi functions, compiled once and cached on disk.

The cache key is the model's fingerprint, the backend options, the CasADi version and the compiler flags,
so a changed model rebuilds and an unchanged one loads in milliseconds. The cache lives in
``$ARMCTL_CACHE`` (default ``~/.cache/armctl``); it is safe to delete.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import casadi as cs

from armctl.errors import BackendError

CFLAGS = ("-O1", "-fPIC", "-shared")


def cache_root(cache_dir: str | os.PathLike[str] | None = None) -> Path:
    if cache_dir is not None:
        return Path(cache_dir)
    env = os.environ.get("ARMCTL_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "armctl"


def library_path(names: list[str], tag: str, cache_dir: str | os.PathLike[str] | None = None) -> Path:
    """Where the compiled library of the functions ``names`` with cache ``tag`` lives (it may not exist yet)."""
    key = hashlib.sha256(f"{tag}|{cs.__version__}|{CFLAGS}|{names}".encode())
    return cache_root(cache_dir) / "casadi" / f"armctl_{key.hexdigest()[:20]}.so"


def compiled(functions: list[cs.Function], tag: str, cache_dir: str | os.PathLike[str] | None = None
             ) -> list[cs.Function]:
    """The same functions, evaluated by C code compiled from them (built on first use, then cached)."""
    lib = library_path([f.name() for f in functions], tag, cache_dir)
    if not lib.exists():
        build(functions, lib)
    return [cs.external(f.name(), str(lib)) for f in functions]


def build(functions: list[cs.Function], lib: Path) -> None:
    """Generate C code for ``functions`` and compile it into the shared library ``lib`` (replaced atomically:
    concurrent builders never load a half-written library)."""
    cc = shutil.which(os.environ.get("CC", "cc")) or shutil.which("gcc")
    folder, name = lib.parent, lib.stem
    if cc is None:
        raise BackendError("compiling generated code needs a C compiler (cc or gcc on PATH, or $CC): install "
                           "one, or do without compiled code (compile=False)", value=None)
    folder.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=folder) as tmp:
        gen = cs.CodeGenerator(f"{name}.c", {"with_header": False})
        for f in functions:
            gen.add(f)
        src = Path(gen.generate(tmp + os.sep))
        tmp_lib = Path(tmp) / f"{name}.so"
        proc = subprocess.run([cc, *CFLAGS, str(src), "-o", str(tmp_lib), "-lm"], capture_output=True,
                              text=True, check=False)
        if proc.returncode != 0:
            raise BackendError(f"compiling generated code failed ({cc}): {proc.stderr[-2000:]}", value=str(src))
        os.replace(tmp_lib, lib)
