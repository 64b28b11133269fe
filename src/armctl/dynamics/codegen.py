"""Deprecated alias of :mod:`armctl.codegen.library` (generated C code has its own package, :mod:`armctl.codegen`,
under the dynamics): importing it warns, and it will be removed in the next release."""

from __future__ import annotations

import warnings

from armctl.codegen.library import (  # noqa: F401  (re-exported)
    CFLAGS,
    CFLAGS_FAST,
    Flags,
    build,
    cache_key,
    cache_root,
    cached,
    compiled,
    is_cached,
    library_path,
)
from armctl.codegen.toolchain import INSTALL_A_COMPILER, compiler  # noqa: F401  (re-exported)

warnings.warn(
    "armctl.dynamics.codegen moved to armctl.codegen.library (and armctl.codegen for the compile policy and the "
    "compiler): import it from there; this alias will be removed in the next release",
    DeprecationWarning,
    stacklevel=2,
)
