"""Where a sweep keeps its outcomes as they finish: ``sweep(..., store=PATH)``, resumed with ``resume=True``.

The store is an append-only folder::

    PATH/manifest.json            the case list: its digest, each case's settings and per-key digests
    PATH/outcomes/00000042.pkl    case 42's outcome, written once, when it finished

Each outcome is written to a temporary file and renamed into place, so a sweep stopped at any instant (Ctrl-C,
SIGKILL, a lost node, a batch job's wall-clock limit) leaves every finished outcome whole and nothing half
written; files are never rewritten, so nothing already stored can be lost by a later crash. An outcome holds the
case's index, how it ended (``"ok"``, or a :class:`~armctl.sim.CaseFailure`'s kind, type, message
and traceback) and the value the sweep returns for it: ``summary``'s output, or the full result without
``summary``. The outcome files are pickles: read only stores you wrote yourself.

A store belongs to one case list. Each case is reduced to a digest per key (numbers and strings by value,
arrays by their bytes, other objects by their pickle), and a store opened with other cases is refused, naming
the first case and key that differ. Two sweeps must not write to one store at the same time.
"""

from __future__ import annotations

import hashlib
import json
import os
import pickle
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from armctl.errors import ArmctlError, InvalidParameterError
from armctl.sim.case_failure import CaseFailure, ErrorReport
from armctl.sim.case_settings import setting

FORMAT = "armctl.sweep-store/1"
MANIFEST = "manifest.json"
OUTCOMES = "outcomes"


def digest(value: Any) -> str:
    """A digest of one setting that is the same in every process for equal values (see the module)."""
    h = hashlib.sha256()
    _feed(h, value)
    return h.hexdigest()[:32]


def _feed(h: Any, value: Any) -> None:
    if value is None or isinstance(value, bool | int | float | complex | str | bytes):
        h.update(f"{type(value).__name__}:{value!r};".encode())
    elif isinstance(value, np.generic):
        _feed(h, value.item())
    elif isinstance(value, np.ndarray) and value.dtype.kind != "O":
        h.update(f"ndarray:{value.dtype.str}:{value.shape};".encode())
        h.update(np.ascontiguousarray(value).tobytes())
    elif isinstance(value, Mapping):
        h.update(f"mapping:{len(value)};".encode())
        for k in sorted(value, key=repr):
            _feed(h, k)
            _feed(h, value[k])
    elif isinstance(value, list | tuple):
        h.update(f"{type(value).__name__}:{len(value)};".encode())
        for v in value:
            _feed(h, v)
    else:
        try:
            blob = pickle.dumps(value, protocol=4)
        except Exception:
            from armctl.sim.sweep_checks import other_pickler

            try:
                blob = other_pickler()(value)
            except Exception:  # nothing to compare but the type
                blob = f"unpicklable {type(value).__module__}.{type(value).__qualname__}".encode()
        h.update(b"pickle:")
        h.update(blob)


def _manifest(cases: list[Mapping[str, Any]]) -> dict[str, Any]:
    keys = [{str(k): digest(v) for k, v in c.items()} for c in cases]
    return {
        "format": FORMAT,
        "cases": len(cases),
        "digest": hashlib.sha256(json.dumps(keys, sort_keys=True).encode()).hexdigest(),
        "keys": keys,
        "settings": [{str(k): _shown(v) for k, v in c.items()} for c in cases],
    }


def _shown(value: Any) -> Any:
    shown = setting(value)
    return shown if shown is None or isinstance(shown, bool | int | float | str) else str(shown)


def _difference(stored: dict[str, Any], given: dict[str, Any]) -> str:
    """What differs between the stored case list and the given one, in words."""
    if stored["cases"] != given["cases"]:
        return f"it holds {stored['cases']} cases, these are {given['cases']}"
    differing = [i for i, (a, b) in enumerate(zip(stored["keys"], given["keys"], strict=True)) if a != b]
    i = differing[0]
    a, b = stored["keys"][i], given["keys"][i]
    if set(a) != set(b):
        only_stored, only_given = sorted(set(a) - set(b)), sorted(set(b) - set(a))
        what = f"case {i} has the keys {only_stored} only in the store and {only_given} only here"
    else:
        key = next(k for k in a if a[k] != b[k])
        was, now = stored["settings"][i].get(key), given["settings"][i].get(key)
        what = f"case {i} differs in {key!r} (stored: {was!r}, given: {now!r})"
    more = len(differing) - 1
    return what + (f", and {more} other case{'s' if more > 1 else ''} differ{'' if more > 1 else 's'}" if more else "")


class SweepStore:
    """The store of one sweep (see the module): opened, or made, by :meth:`open`."""

    def __init__(self, path: Path, manifest: dict[str, Any]) -> None:
        self.path, self.manifest = path, manifest
        self.written = len(self.finished())

    @classmethod
    def open(cls, path: str | os.PathLike[str], cases: list[Mapping[str, Any]], resume: bool) -> SweepStore:
        """The store at ``path`` for ``cases``: made if the folder is missing or empty; else checked to hold these
        cases (and, unless ``resume``, no outcome yet)."""
        if not isinstance(path, str | os.PathLike):
            raise InvalidParameterError(f"store must be a folder path, got {path!r}", value=path)
        root = Path(path)
        given = _manifest(cases)
        if root.exists() and not root.is_dir():
            raise InvalidParameterError(f"store {str(root)!r} is a file, not a folder; pass a folder path", value=path)
        if not root.exists() or not any(root.iterdir()):
            (root / OUTCOMES).mkdir(parents=True, exist_ok=True)
            _write_atomically(root / MANIFEST, json.dumps(given).encode())
            return cls(root, given)
        stored = _read_manifest(root)
        if stored["digest"] != given["digest"]:
            raise InvalidParameterError(
                f"the sweep store {str(root)!r} was made from other cases: {_difference(stored, given)}. "
                "Pass the cases it was made from, or another store folder for these cases",
                value=str(root),
            )
        for stale in (root / OUTCOMES).glob(".*.tmp"):  # a write stopped before its rename
            stale.unlink(missing_ok=True)
        store = cls(root, stored)
        if store.written and not resume:
            raise InvalidParameterError(
                f"the sweep store {str(root)!r} already holds {store.written} of these {len(cases)} cases' outcomes: "
                "pass resume=True to run only the others, or another (or an emptied) folder to run them all again",
                value=str(root),
            )
        return store

    def finished(self) -> list[int]:
        """The indices of the cases whose outcome is stored, in order."""
        return sorted(int(p.stem) for p in (self.path / OUTCOMES).glob("*.pkl"))

    def load(self, cases: list[Mapping[str, Any]] | None = None) -> dict[int, Any]:
        """The stored outcomes, case index → the result or a CaseFailure (whose ``case`` is ``cases[i]``, or the
        stored settings)."""
        out = {}
        for i in self.finished():
            case = cases[i] if cases is not None else self.manifest["settings"][i]
            out[i] = _outcome(self.path / OUTCOMES / f"{i:08d}.pkl", case)
        return out

    def write(self, i: int, outcome: Any) -> None:
        """Store case i's outcome (once)."""
        if isinstance(outcome, CaseFailure):
            exc = outcome.exception
            exc_blob = ErrorReport.of(exc).pickled if exc is not None else None  # None: it does not pickle
            fields = (outcome.kind, outcome.error_type, outcome.message, outcome.traceback, outcome.attempts)
            record: dict[str, Any] = {"index": i, "outcome": outcome.kind, "failure": fields, "exception": exc_blob}
        else:
            record = {"index": i, "outcome": "ok", "value": outcome}
        try:
            blob = pickle.dumps(record, protocol=pickle.HIGHEST_PROTOCOL)
        except Exception as exc:
            raise ArmctlError(
                f"sweep case {i}'s result, a {type(outcome).__name__}, cannot be pickled into the store "
                f"{str(self.path)!r} ({type(exc).__name__}: {exc}); give sweep a summary= that returns numbers, "
                "arrays or dicts of them"
            ) from exc
        _write_atomically(self.path / OUTCOMES / f"{i:08d}.pkl", blob)
        self.written += 1


def _write_atomically(path: Path, data: bytes) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as f:
        f.write(data)
    os.replace(tmp, path)


def _read_manifest(root: Path) -> dict[str, Any]:
    try:
        manifest = json.loads((root / MANIFEST).read_text())
    except (OSError, ValueError) as exc:
        raise InvalidParameterError(
            f"{str(root)!r} is not an empty folder nor a sweep store (its {MANIFEST} cannot be read: {exc}); pass "
            "a new or empty folder, or the folder of an earlier sweep(..., store=...)",
            value=str(root),
        ) from None
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise InvalidParameterError(f"{str(root)!r} is not a sweep store of this version ({FORMAT})", value=str(root))
    return manifest


def _outcome(path: Path, case: Mapping[str, Any]) -> Any:
    with open(path, "rb") as f:
        record = pickle.load(f)  # the user's own store (see the module)
    if record["outcome"] == "ok":
        return record["value"]
    kind, error_type, message, traceback, attempts = record["failure"]
    exc = pickle.loads(record["exception"]) if record["exception"] is not None else None
    return CaseFailure(record["index"], case, kind, error_type, message, traceback, attempts, exc)


@dataclass(frozen=True)
class StoredOutcomes:
    """What a sweep's store holds, read by :func:`read_outcomes` (from which :meth:`SweepResult.load
    <armctl.sim.SweepResult.load>` makes its result).

    Attributes
    ----------
    outcomes : list
        One entry per case, in case order: the value stored for it (``summary``'s output or the full result),
        a :class:`~armctl.sim.CaseFailure`, or None for a case not finished.
    settings : list of dict
        Each case's settings as the manifest shows them (numbers and strings as they were, other objects by name
        or repr; see :mod:`armctl.sim.case_settings`).
    path : str
        The store's folder.
    pending : frozenset of int
        The cases not finished.
    """

    outcomes: list[Any]
    settings: list[dict[str, Any]]
    path: str
    pending: frozenset[int]


def read_outcomes(path: str | os.PathLike[str], partial: bool = False) -> StoredOutcomes:
    """The outcomes of a sweep's store (see :meth:`SweepResult.load <armctl.sim.SweepResult.load>`).

    Parameters
    ----------
    path : str or path-like
        The store's folder.
    partial : bool, optional
        Accept a store whose sweep did not finish (its unfinished cases are None and listed as pending).

    Returns
    -------
    StoredOutcomes

    Raises
    ------
    InvalidParameterError
        Not a store, or (without ``partial``) a store with unfinished cases.
    """
    root = Path(path)
    if not (root / MANIFEST).is_file():
        raise InvalidParameterError(
            f"{str(root)!r} is not a sweep store (it has no {MANIFEST}); pass the folder given as sweep's store=",
            value=str(root),
        )
    store = SweepStore(root, _read_manifest(root))
    n = store.manifest["cases"]
    done = store.load()
    if len(done) < n and not partial:
        raise InvalidParameterError(
            f"the sweep store {str(root)!r} holds {len(done)} of its {n} cases' outcomes: run the sweep again with "
            "store= this folder and resume=True to finish it, or load(..., partial=True) for the finished ones",
            value=str(root),
        )
    outcomes = [done.get(i) for i in range(n)]
    return StoredOutcomes(outcomes, list(store.manifest["settings"]), str(root), frozenset(range(n)) - frozenset(done))
