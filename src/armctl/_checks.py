"""Input checks shared by the whole package (private).

Each raises an :class:`~armctl.errors.ArmctlError` subclass naming the value and what is expected.
"""

from __future__ import annotations

import datetime
import math
import os
from collections.abc import Iterable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
#: the dtype of a native float array (compare with ``==``: an unpickled array's dtype is an equal, distinct object)
FLOAT = np.dtype(np.float64)


def real_array(x: object, name: str) -> FloatArray:
    """``x`` as a float array; raise if it holds anything but real numbers (complex values are refused rather
    than cut to their real part, strings and None rather than passed on to fail somewhere else, booleans rather
    than taken as 0 and 1, dates and durations (``datetime64``, ``timedelta64``) rather than taken as counts of
    their unit, masked entries rather than read through the mask)."""
    if isinstance(x, np.ma.MaskedArray) and np.ma.getmaskarray(x).any():  # asarray would take the hidden data
        raise InvalidParameterError(f"{name} has masked entries: fill them first (x.filled(value)), got {x!r}", value=x)
    ragged = None
    try:
        a = np.asarray(x)
        kind = a.dtype.kind
        if kind in "mM":  # datetime64 / timedelta64: astype(float) would give days, seconds, … since 1970
            raise InvalidParameterError(
                f"{name} must hold real numbers, not dates or durations ({a.dtype}): convert them to seconds "
                f"first (e.g. (t - t[0]) / np.timedelta64(1, 's')), got {_shown(x)}",
                value=x,
            )
        # complex, text (NumPy would parse "0.3"), or an object array holding any of them, or a boolean, a date,
        # a masked element among numbers
        if kind in "cUS" or (kind == "O" and any(map(_not_a_number, a.flat))):  # None: NumPy would make it NaN
            raise TypeError(kind)
        if kind != "b":
            if kind != "O" and isinstance(x, list | tuple) and _holds_bool(x):  # [1.0, True]: NumPy gives 1.0
                raise TypeError("bool")
            return a.astype(float, copy=False)
    except (TypeError, ValueError, OverflowError) as exc:
        if isinstance(exc, InvalidParameterError):
            raise
        if isinstance(exc, ValueError) and "inhomogeneous" in str(exc):  # rows of different shapes?
            ragged = _row_shapes(x)
        if ragged is None:
            raise InvalidParameterError(f"{name} must hold real numbers, got {_shown(x)}", value=x) from None
    if ragged is not None:
        raise ShapeError(
            f"{name} must be a rectangular array, but its rows have different shapes {ragged}: got {_shown(x)}", value=x
        )
    what = "a real number, not a boolean" if a.ndim == 0 else "real numbers, not booleans"
    raise InvalidParameterError(f"{name} must be {what}, got {_shown(x)}", value=x)


#: what an object array may not hold where numbers are meant (NumPy would convert each to a float)
_NOT_NUMBERS = (
    str,
    bytes,
    complex,
    bool,
    np.complexfloating,
    np.bool_,
    np.datetime64,
    np.timedelta64,
    datetime.date,
    datetime.timedelta,
    np.ma.core.MaskedConstant,
)


def _not_a_number(v: Any) -> bool:
    return v is None or isinstance(v, _NOT_NUMBERS)


def _holds_bool(x: list[Any] | tuple[Any, ...]) -> bool:
    """Whether a (nested) list or tuple of numbers holds a boolean."""
    types = set(map(type, x))
    if not _BOOLS.isdisjoint(types):
        return True
    return (list in types or tuple in types) and any(_holds_bool(v) for v in x if isinstance(v, list | tuple))


_BOOLS = frozenset((bool, np.bool_))


def _row_shapes(x: Any) -> list[tuple[int, ...]] | None:
    """The shapes of the rows of ``x`` if they differ (a ragged array), else None."""
    try:
        if any(isinstance(r, str | bytes) for r in x):  # text is the problem, not the shape
            return None
        shapes = [np.shape(r) for r in x]
    except Exception:
        return None
    return shapes if len(set(shapes)) > 1 else None


def _shown(x: Any, limit: int = 200) -> str:
    """repr(x), cut to ``limit`` characters (a whole log passed by mistake would fill the screen)."""
    text = repr(x)
    return text if len(text) <= limit else f"{text[:limit]}… ({len(text)} characters)"


def vector(x: object, n: int, name: str) -> FloatArray:
    """Return ``x`` as a float vector of length ``n``; raise if its shape is wrong or it is not finite."""
    a = real_array(x, name)
    if a.shape != (n,):
        raise ShapeError(f"{name} must have shape ({n},), got shape {a.shape}", value=x)
    if not all(map(math.isfinite, a.tolist())):
        raise NonFiniteError(f"{name} holds NaN or inf: {a!r}", value=x)
    return a


def matrix(x: object, shape: tuple[int, ...], name: str) -> FloatArray:
    a = real_array(x, name)
    if a.shape != shape:
        raise ShapeError(f"{name} must have shape {shape}, got shape {a.shape}", value=x)
    if not np.isfinite(a).all():
        raise NonFiniteError(f"{name} holds NaN or inf", value=x)
    return a


def scalar(x: Any, name: str, *, positive: bool = False, nonnegative: bool = False) -> float:
    """``x`` as a finite float (> 0 if ``positive``, >= 0 if ``nonnegative``); text, None, complex numbers,
    arrays and booleans are refused by name."""
    if isinstance(x, bool | np.bool_):  # float(True) would be 1.0
        raise InvalidParameterError(f"{name} must be a real number, not a boolean, got {x!r}", value=x)
    if isinstance(x, np.ma.MaskedArray) and np.ma.getmaskarray(x).any():  # float(np.ma.masked) would be NaN
        raise InvalidParameterError(f"{name} is masked: give a number (x.filled(value)), got {x!r}", value=x)
    try:
        if isinstance(x, str | bytes | complex | np.complexfloating):  # float("0.5") would parse text
            raise TypeError(type(x).__name__)
        v = float(x)
    except (TypeError, ValueError, OverflowError):
        raise InvalidParameterError(f"{name} must be a real number, got {x!r}", value=x) from None
    if not math.isfinite(v):
        raise NonFiniteError(f"{name} must be finite, got {v}", value=x)
    if positive and v <= 0:
        raise InvalidParameterError(f"{name} must be > 0, got {v}", value=x)
    if nonnegative and v < 0:
        raise InvalidParameterError(f"{name} must be >= 0, got {v}", value=x)
    return v


def boolean(x: Any, name: str) -> bool:
    """``x`` as a bool: only True or False (a NumPy bool too); text such as ``"False"`` would be truthy."""
    if not isinstance(x, bool | np.bool_):
        raise InvalidParameterError(f"{name} must be True or False, got {x!r}", value=x)
    return bool(x)


def flag(name: str, doc: str) -> Any:
    """A boolean option as a property: read from ``_<name>``, checked by :func:`boolean` on assignment (``doc``:
    its docstring)."""

    def get(self: Any) -> bool:
        return bool(getattr(self, f"_{name}"))

    def set_(self: Any, value: Any) -> None:
        setattr(self, f"_{name}", boolean(value, name))

    return property(get, set_, doc=doc)


def instances(items: Any, cls: type, name: str, label: str, *, single: bool = False) -> tuple[Any, ...]:
    """``items`` as a tuple of ``cls`` objects: a sequence of them (not text), or one of them if ``single``;
    anything else raises an InvalidParameterError naming it (``label``: how the class is named to the user)."""
    if single and isinstance(items, cls):
        return (items,)
    try:
        if isinstance(items, str | bytes | cls):
            raise TypeError(type(items).__name__)
        out = tuple(items)
    except TypeError:
        raise InvalidParameterError(
            f"{name} must be {f'a {label} or ' if single else ''}a sequence of {label} objects, got {items!r}",
            value=items,
        ) from None
    for it in out:
        if not isinstance(it, cls):
            raise InvalidParameterError(f"{name} must be {label} objects, got {it!r} ({type(it).__name__})", value=it)
    return out


def whole_number(x: Any, name: str, minimum: int = 0) -> int:
    """``x`` as an int: an int, a NumPy integer or a float with an integral value (2.0), at least ``minimum``.
    Booleans, fractions, NaN/inf and anything else raise an InvalidParameterError naming the value."""
    whole = not isinstance(x, bool | np.bool_ | np.timedelta64) and (  # (a timedelta64 is a NumPy integer)
        isinstance(x, int | np.integer)
        or (isinstance(x, float | np.floating) and math.isfinite(x) and float(x).is_integer())
    )
    if not whole or x < minimum:
        raise InvalidParameterError(f"{name} must be a whole number >= {minimum}, got {x!r}", value=x)
    return int(x)


def per_joint(x: object, n: int, name: str) -> FloatArray:
    """A scalar (for every entry) or an (n,) vector of real numbers, as an (n,) float array; NaN and inf are the
    caller's to check (a limit may be infinite)."""
    a = real_array(x, name)
    if a.ndim == 0:
        return np.full(n, float(a))
    if a.shape != (n,):
        raise ShapeError(f"{name} must be a scalar or an ({n},) vector, got shape {a.shape}", value=x)
    return a


def nonnegative_vector(x: object, n: int, name: str) -> FloatArray:
    """A scalar (for every entry) or an (n,) vector, finite and ≥ 0 — weights, standard deviations, …"""
    a = per_joint(x, n, name)
    if not np.isfinite(a).all():
        raise NonFiniteError(f"{name} holds NaN or inf: {a}", value=x)
    if (a < 0).any():
        raise InvalidParameterError(f"{name} must be >= 0, got {a.tolist()}", value=x)
    return a


def gain_matrix(k: object, n: int, name: str) -> FloatArray:
    """A gain given as a scalar, a vector (diagonal) or an n×n matrix, returned as a symmetric positive
    definite n×n matrix; raise if it is not one."""
    a = real_array(k, name)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.ndim == 1:
        if a.shape != (n,):
            raise ShapeError(f"{name} as a vector must have length {n}, got {a.shape}", value=k)
        a = np.diag(a)
    if a.shape != (n, n):
        raise ShapeError(f"{name} must be a scalar, a ({n},) vector or a ({n}, {n}) matrix, got {a.shape}", value=k)
    if not np.isfinite(a).all():
        raise NonFiniteError(f"{name} holds NaN or inf", value=k)
    if not np.allclose(a, a.T, rtol=1e-10, atol=1e-12):
        raise InvalidParameterError(f"{name} must be symmetric", value=k)
    lo = float(np.linalg.eigvalsh(a).min())
    if lo <= 0:
        raise InvalidParameterError(f"{name} must be positive definite; its smallest eigenvalue is {lo:g}", value=k)
    return a


def readonly(a: FloatArray) -> FloatArray:
    a.flags.writeable = False
    return a


def readonly_fields(obj: Any, names: Iterable[str]) -> None:
    """Set each field of ``names`` of the frozen dataclass ``obj`` (in its ``__post_init__``) to a read-only float
    copy of its value: the caller's arrays are not shared, and the result's cannot be written to."""
    for name in names:
        object.__setattr__(obj, name, readonly(np.array(getattr(obj, name), dtype=float)))


def compact_gain(k: FloatArray) -> FloatArray:
    """A gain matrix in its cheapest form for :func:`apply_gain`: the diagonal if it is diagonal."""
    return np.diag(k).copy() if np.count_nonzero(k - np.diag(np.diag(k))) == 0 else k


def apply_gain(k: FloatArray, x: FloatArray) -> FloatArray:
    """K x for a gain from :func:`compact_gain` (elementwise for a diagonal, else a matrix product)."""
    return k * x if k.ndim == 1 else k.dot(x)


def all_finite(a: FloatArray) -> bool:
    """True if every entry of the float array ``a`` is finite.

    A small array's entries are summed as Python floats: the sum is finite exactly when no entry is NaN or inf,
    unless finite entries add up beyond the range of floats (then False, and callers take their careful path,
    ``np.isfinite``). Python's float arithmetic raises no floating-point warning for inf − inf, as NumPy's would.
    A larger array is tested entry by entry (``np.isfinite``), where the sum's conversion would cost more."""
    if a.size <= _SUMMED:
        return math.isfinite(sum((a if a.ndim == 1 else a.ravel(order="K")).tolist()))  # a vector: no ravel
    return bool(np.isfinite(a).all())


#: arrays up to this many entries are checked by :func:`all_finite` through a Python sum (the faster way there)
_SUMMED = 256


def float_vectors(*arrays: Any) -> bool:
    """True if every one of ``arrays`` is a native float64 1-D ndarray (finite or not; their lengths are not
    compared). None is not one: an argument left out by the caller is refused here like any other non-array."""
    for a in arrays:
        if type(a) is not np.ndarray or a.ndim != 1 or a.dtype != FLOAT:
            return False
    return True


def memory_limit() -> float:
    """The memory [bytes] a process may use at most: the machine's physical memory, or a smaller limit of its
    control group (a container's); inf where neither can be read."""
    limit = math.inf
    try:
        limit = float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):  # no sysconf (Windows)
        pass
    for path in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            with open(path) as f:
                text = f.read().strip()
            if text.isdigit():
                limit = min(limit, float(text))
        except OSError:
            pass
    return limit


def byte_size(nbytes: float) -> str:
    """A size for people: 3.2 GB, 1.4 TB, …"""
    for unit in ("B", "kB", "MB", "GB", "TB", "PB"):
        if nbytes < 1000.0 or unit == "PB":
            return f"{nbytes:.3g} {unit}"
        nbytes /= 1000.0
    raise AssertionError  # pragma: no cover


def check_memory(nbytes: float, what: str, fix: str, value: Any) -> None:
    """Raise an InvalidParameterError before a request allocates more than :func:`memory_limit`: ``what`` names
    the request ("duration = 1e7 s …"), ``fix`` says how to make it smaller."""
    limit = memory_limit()
    if nbytes > limit:
        raise InvalidParameterError(
            f"{what} needs at least {byte_size(nbytes)} of memory, more than the {byte_size(limit)} this machine "
            f"has: {fix}",
            value=value,
        )
