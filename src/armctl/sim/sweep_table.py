"""A sweep as a table: :meth:`SweepResult.to_dataframe <armctl.sim.SweepResult.to_dataframe>` (pandas is optional,
``pip install "armctl[data]"``; see :mod:`armctl.sim.tables`).

A sweep's table has one row per case: the case's settings (numbers, strings and booleans as they are; other
objects by their ``name``, a function by its qualified name, anything else by its ``repr``; see
:mod:`armctl.sim.case_settings`), the outcome (``"ok"``, ``"raised"``, ``"worker_died"``, ``"timed_out"``, with
the exception's type and message; ``"not_run"`` for a case a partially loaded store lacks) and the scalar metrics
of what the case returned (a number, the scalar entries of a mapping or the fields of a dataclass, or for a full
:class:`~armctl.sim.SimResult` its status and tracking error, :func:`~armctl.sim.tables.run_metrics`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Collection, Mapping, Sequence
from typing import Any

import numpy as np

from armctl.errors import InvalidParameterError
from armctl.sim.case_failure import CaseFailure
from armctl.sim.case_settings import is_scalar, plain, setting
from armctl.sim.result import SimResult
from armctl.sim.tables import require, run_metrics


def metrics(value: Any) -> dict[str, Any]:
    """The scalar metrics of what a case returned (see the module)."""
    if isinstance(value, SimResult):
        return run_metrics(value)
    if is_scalar(value):
        return {"summary": plain(value)}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        value = {f.name: getattr(value, f.name) for f in dataclasses.fields(value)}
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items() if is_scalar(v)}
    if isinstance(value, Sequence) and all(is_scalar(v) for v in value):
        return {f"summary[{k}]": plain(v) for k, v in enumerate(value)}
    if isinstance(value, np.ndarray) and value.ndim == 1 and value.size <= 16:
        return {f"summary[{k}]": float(v) for k, v in enumerate(value)}
    return {}


def sweep_rows(
    outcomes: Sequence[Any], cases: Sequence[Mapping[str, Any]] | None, pending: Collection[int] = ()
) -> list[dict[str, Any]]:
    """One dict per case: settings, outcome, metrics (the columns of :func:`sweep_dataframe`); the cases in
    ``pending`` did not run (outcome ``"not_run"``)."""
    rows = []
    for i, outcome in enumerate(outcomes):
        case = cases[i] if cases is not None else outcome.case if isinstance(outcome, CaseFailure) else {}
        row: dict[str, Any] = {"case": i}
        row.update({str(k): setting(v) for k, v in case.items()})
        if i in pending:
            row.update(outcome="not_run", error_type=None, message=None)
        elif isinstance(outcome, CaseFailure):
            row.update(outcome=outcome.kind, error_type=outcome.error_type, message=outcome.message)
        else:
            row.update(outcome="ok", error_type=None, message=None)
            for k, v in metrics(outcome).items():
                row[k if k not in row else f"{k} (summary)"] = v
        rows.append(row)
    return rows


def sweep_dataframe(
    outcomes: Sequence[Any], cases: Sequence[Mapping[str, Any]] | None = None, pending: Collection[int] = ()
) -> Any:
    """A sweep as a pandas DataFrame (see :meth:`SweepResult.to_dataframe
    <armctl.sim.SweepResult.to_dataframe>`)."""
    pd = require("pandas", "SweepResult.to_dataframe")
    if cases is not None and len(cases) != len(outcomes):
        raise InvalidParameterError(
            f"cases has {len(cases)} entries but the sweep {len(outcomes)} outcomes; pass the sweep's own cases",
            value=len(cases),
        )
    frame = pd.DataFrame(sweep_rows(outcomes, cases, pending)).set_index("case")
    for column in frame.columns:  # a column mixing strings and numbers is shown as strings (one type a column)
        kinds = {type(v) for v in frame[column] if v is not None and not (isinstance(v, float) and math.isnan(v))}
        if str in kinds and len(kinds) > 1:
            frame[column] = [None if v is None else str(v) for v in frame[column]]
    return frame
