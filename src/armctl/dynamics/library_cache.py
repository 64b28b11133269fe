"""Deprecated alias of :mod:`armctl.codegen.library_cache`: importing it warns, and it will be removed in the next
release."""

from __future__ import annotations

import warnings

from armctl.codegen.library_cache import (  # noqa: F401  (re-exported)
    KEY_FUNCTION,
    MISSING,
    STALE_AFTER,
    build_lock,
    check,
    clean_key,
    clean_stale,
    key_code,
    key_function,
    key_matches,
    lock_path,
    record_path,
    unwritable,
    write_record,
)

warnings.warn(
    "armctl.dynamics.library_cache moved to armctl.codegen.library_cache: import it from there; this alias will "
    "be removed in the next release",
    DeprecationWarning,
    stacklevel=2,
)
