"""`ControllerLog`: the controller's ``last_log`` entries of a run, sample by sample, stacked into
``SimResult.logs`` at the end.

An entry that is a float64 array (or a float) of one shape throughout is written into a (samples, *shape) array
made at its first sample; any other entry (integers, booleans, changing shapes, objects) is kept as a copy per
sample and stacked at the end, where what cannot be stacked into numbers is left out with a warning. (An entry
that cannot change after it is logged — a number, a string, a tuple of them — is kept as it is, and made an array
when the entries are stacked.)
"""

from __future__ import annotations

from typing import Any

import numpy as np

from armctl._checks import FLOAT, FloatArray

#: the types of entries that cannot change after they are logged (kept as they are, see the module)
_IMMUTABLE = (int, float, bool, str, np.integer, np.floating, np.bool_)
#: the exact types of the usual such entries (ControllerLog.add's quick test; the others take _kept_as_is)
_EXACT = frozenset((int, float, bool, str, np.bool_, np.float64, np.int64))


class ControllerLog:
    """The logged entries of a run of ``samples`` samples (see the module)."""

    def __init__(self, samples: int) -> None:
        self.samples = samples
        self._arrays: dict[str, FloatArray] = {}  # key → (samples, *shape) rows
        self._logged: dict[str, list[int]] = {}  # key → the rows that hold an entry, in order
        #: key → (its rows, the rows logged, the shape of an entry): what :meth:`add` needs, in one lookup
        self._slots: dict[str, tuple[FloatArray, list[int], tuple[int, ...]]] = {}
        self._copies: dict[str, list[Any]] = {}  # key → the entries kept one by one
        self._copy_rows: dict[str, list[int]] = {}

    def add(self, k: int, log: dict[str, Any]) -> None:
        """Record the entries of ``log`` at sample k."""
        slots, copies = self._slots, self._copies
        for key, val in log.items():
            slot = slots.get(key)
            kind = type(val)
            if slot is not None:
                if kind is np.ndarray and val.shape == slot[2] and val.dtype == FLOAT:
                    slot[0][k] = val  # (the usual entry: an array of the key's shape)
                    slot[1].append(k)
                    continue
            elif (  # (a key kept one by one, and an entry of the exact types that cannot change)
                kind in _EXACT or (kind is tuple and set(map(type, val)) <= _EXACT)
            ) and key in copies:
                copies[key].append(val)
                self._copy_rows[key].append(k)
                continue
            self._add_other(k, key, val)

    def _add_other(self, k: int, key: str, val: Any) -> None:
        """:meth:`add` of an entry that is not a float64 array of its key's rows: a float of a key of floats, a
        key's first entry, or one kept as a copy."""
        slot = self._slots.get(key)
        if slot is not None:
            rows, logged, shape = slot
            if type(val) is float and not shape:
                rows[k] = val
                logged.append(k)
                return
            self._keep_copies(key)  # another shape or kind from now on: kept one by one
        elif key not in self._copies and ((type(val) is np.ndarray and val.dtype == FLOAT) or type(val) is float):
            shape = np.shape(val)
            rows = self._arrays[key] = np.empty((self.samples, *shape))
            self._logged[key] = [k]
            self._slots[key] = (rows, self._logged[key], shape)
            rows[k] = val
            return
        self._copies.setdefault(key, []).append(val if _kept_as_is(val) else np.array(val, copy=True))
        self._copy_rows.setdefault(key, []).append(k)

    def _keep_copies(self, key: str) -> None:
        """Move ``key``'s rows so far into copies (its entries change shape or kind)."""
        rows, logged = self._arrays.pop(key), self._logged.pop(key)
        del self._slots[key]
        self._copies[key] = [rows[i].copy() for i in logged]
        self._copy_rows[key] = logged

    def stacked(self, rows: int) -> tuple[dict[str, np.ndarray], list[str]]:
        """(logs, skipped) of the first ``rows`` samples: each key's entries stacked (with ``key:sample``, the
        samples it was logged at, where it was not logged at every one), and what could not be stacked."""
        logs: dict[str, np.ndarray] = {}
        skipped: list[str] = []
        for key, arr in self._arrays.items():
            idx = np.array([i for i in self._logged[key] if i < rows], dtype=np.intp)
            if not len(idx):  # logged only after the last recorded sample
                continue
            if len(idx) == idx[-1] + 1:  # at every sample from the first
                logs[key] = arr[: len(idx)].copy()
            else:
                logs[key] = arr[idx]
                logs[f"{key}:sample"] = idx
        for key, vals in self._copies.items():
            idx_list = [i for i in self._copy_rows[key] if i < rows]
            if not idx_list:
                continue
            arrays = [np.asarray(v) for v in vals[: len(idx_list)]]
            try:
                stacked = np.stack(arrays)
            except ValueError:  # entries of different shapes
                skipped.append(f"{key!r} (entries of different shapes)")
                continue
            if stacked.dtype.kind == "O":  # None, dicts, …: npz cannot store them without pickle
                bad = next((v for v in arrays if v.dtype.kind == "O"), stacked)
                skipped.append(f"{key!r} (not numbers: {type(bad.item() if bad.ndim == 0 else bad).__name__})")
                continue
            logs[key] = stacked
            if idx_list != list(range(len(idx_list))):
                logs[f"{key}:sample"] = np.array(idx_list)
        return logs, skipped


def _kept_as_is(val: Any) -> bool:
    """Whether a logged entry cannot change after it is logged: a number, a string, or a tuple of them."""
    t = type(val)
    if t is tuple:
        return all(isinstance(v, _IMMUTABLE) for v in val)
    return t in _IMMUTABLE
