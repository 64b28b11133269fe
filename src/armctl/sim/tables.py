"""Results as tables and labelled arrays: :meth:`SimResult.to_dataframe <armctl.sim.SimResult.to_dataframe>`,
:meth:`SimResult.to_xarray <armctl.sim.SimResult.to_xarray>` and :meth:`SweepResult.to_dataframe
<armctl.sim.SweepResult.to_dataframe>`.

pandas and xarray are optional (``pip install "armctl[data]"``, which adds pyarrow for Parquet files too): they
are imported here, when a conversion is first asked for, never by ``import armctl``; without them the methods
raise :class:`~armctl.errors.OptionalDependencyError` saying how to install them.

A sweep's table has one row per case: the case's settings (numbers, strings and booleans as they are; other
objects by their ``name``, a function by its qualified name, anything else by its ``repr``), the outcome
(``"ok"``, ``"raised"``, ``"worker_died"``, ``"timed_out"``, with the exception's type and message; ``"not_run"``
for a case a partially loaded store lacks) and the
scalar metrics of what the case returned (a number, the scalar entries of a mapping or the fields of a
dataclass, or for a full :class:`~armctl.sim.SimResult` its status and tracking error).
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections.abc import Collection, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from armctl.errors import InvalidParameterError, OptionalDependencyError

if TYPE_CHECKING:
    from armctl.sim.result import SimResult
    from armctl.sim.sweep_result import SweepResult

INSTALL = 'pip install "armctl[data]"'
LAYOUTS = ("long", "wide")
SHOWN = 120  # characters of a setting's repr kept in a table

# per-joint arrays of a SimResult in a table: (column, attribute, what, unit of a revolute / prismatic joint)
_JOINT_ARRAYS = (
    ("q", "q", "joint position", "rad", "m"),
    ("qd", "qd", "joint velocity", "rad/s", "m/s"),
    ("qdd", "qdd", "joint acceleration", "rad/s²", "m/s²"),
    ("tau", "tau", "commanded torque", "N·m", "N"),
    ("tau_applied", "tau_applied", "applied torque (after saturation)", "N·m", "N"),
)
_REFERENCE = (
    ("q_ref", "q", "reference position", "rad", "m"),
    ("qd_ref", "qd", "reference velocity", "rad/s", "m/s"),
    ("qdd_ref", "qdd", "reference acceleration", "rad/s²", "m/s²"),
)
_WRENCH_AXES = ("fx", "fy", "fz", "mx", "my", "mz")


def require(module: str, feature: str) -> Any:
    """The module ``module`` (pandas, xarray, pyarrow), or an OptionalDependencyError naming ``feature`` and the
    install command."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise OptionalDependencyError(
            f"{feature} needs {module}, which is not installed ({exc}); install it with {INSTALL}", value=module
        ) from exc


# ------------------------------------------------------------------------------------------------ SimResult
def _columns(res: SimResult) -> list[tuple[str, Any, str, str]]:
    """(name, (N, n) array, description, unit) of every per-joint quantity of ``res`` in a table."""
    kinds = [j.kind for j in res.plant.joints] if res.plant is not None else None
    out = []
    arrays = [(c, getattr(res, a), w, r, p) for c, a, w, r, p in _JOINT_ARRAYS]
    if res.reference is not None and len(res.reference.q) == len(res.t):
        arrays += [(c, getattr(res.reference, a), w, r, p) for c, a, w, r, p in _REFERENCE]
        arrays.append(("error", res.error, "tracking error q_ref − q", "rad", "m"))
    for name, a, what, rev, pri in arrays:
        if kinds is None or len(set(kinds)) > 1:
            unit = f"{rev} or {pri}" if kinds is None else f"{rev} (revolute), {pri} (prismatic)"
        else:
            unit = rev if kinds[0] == "revolute" else pri
        out.append((name, a, what, unit))
    return out


def sim_dataframe(res: SimResult, layout: str = "long") -> Any:
    """A run as a pandas DataFrame (see :meth:`SimResult.to_dataframe <armctl.sim.SimResult.to_dataframe>`)."""
    pd = require("pandas", "SimResult.to_dataframe")
    if layout not in LAYOUTS:
        raise InvalidParameterError(f"layout must be 'long' or 'wide', got {layout!r}", value=layout)
    names = list(res.joint_names)
    columns = _columns(res)
    t = np.asarray(res.t)
    if layout == "wide":
        data = {(name, joint): a[:, j] for name, a, _, _ in columns for j, joint in enumerate(names)}
        frame = pd.DataFrame(data, index=pd.Index(t, name="t"))
        frame.columns = pd.MultiIndex.from_tuples(frame.columns, names=["quantity", "joint"])
        return frame
    n = len(names)
    long = {
        "t": np.repeat(t, n),
        "joint": pd.Categorical(np.tile(names, len(t)), categories=names),
    }
    for name, a, _, _ in columns:
        long[name] = np.asarray(a).reshape(-1)
    return pd.DataFrame(long)


def sim_xarray(res: SimResult) -> Any:
    """A run as an xarray Dataset (see :meth:`SimResult.to_xarray <armctl.sim.SimResult.to_xarray>`)."""
    xr = require("xarray", "SimResult.to_xarray")
    data: dict[str, Any] = {}
    for name, a, what, unit in _columns(res):
        data[name] = (("time", "joint"), np.array(a), {"long_name": what, "units": unit})
    data["wrench"] = (
        ("time", "wrench_axis"),
        np.array(res.wrench),
        {"long_name": "wrench the arm exerts, [force; moment] in world axes", "units": "N (force), N·m (moment)"},
    )
    for name, what in (
        ("work_actuator", "work of the applied torque since t = 0"),
        ("work_friction", "work of joint friction since t = 0"),
        ("work_external", "work of the external wrenches since t = 0"),
    ):
        data[name] = (("time",), np.array(getattr(res, name)), {"long_name": what, "units": "J"})
    coords: dict[str, Any] = {
        "time": ("time", np.array(res.t), {"long_name": "sample time", "units": "s"}),
        "joint": list(res.joint_names),
        "wrench_axis": list(_WRENCH_AXES),
    }
    if res.plant is not None:
        coords["joint_type"] = ("joint", [j.kind for j in res.plant.joints])
    attrs: dict[str, Any] = {"status": res.status, "diverged": int(res.diverged), "divergence": res.divergence}
    if res.diverged_at is not None:
        attrs["diverged_at"] = float(res.diverged_at)
    for k, v in res.info.items():  # the settings and counters that are plain numbers or strings (netCDF's types)
        if isinstance(v, bool | np.bool_):
            attrs[k] = int(v)
        elif isinstance(v, numbers.Integral):
            attrs[k] = int(v) if -(2**63) <= int(v) < 2**63 else str(v)  # (a seed may not fit an int64)
        elif isinstance(v, str | numbers.Real):
            attrs[k] = _plain(v)
    return xr.Dataset(data, coords=coords, attrs=attrs)


# ------------------------------------------------------------------------------------------------ SweepResult
def _is_scalar(x: Any) -> bool:
    return x is None or isinstance(x, str | bool | numbers.Number | np.generic)


def _plain(x: Any) -> Any:
    return x.item() if isinstance(x, np.generic) else x


def setting(value: Any) -> Any:
    """How a case's setting appears in a table: a scalar as it is; an object by its ``name`` (a RobotModel, a
    scene), a function or class by its qualified name, a small array as a list, an object without a repr of its
    own by its class's name; anything else by its repr (the first :data:`SHOWN` characters)."""
    if _is_scalar(value):
        return _plain(value)
    name = getattr(value, "name", None)
    if isinstance(name, str) and name:
        return name
    if isinstance(value, np.ndarray):
        return repr(value.tolist()) if value.size <= 12 else f"ndarray{value.shape}"
    if callable(value) and hasattr(value, "__qualname__"):
        return f"{getattr(value, '__module__', '')}.{value.__qualname__}".lstrip(".")
    if type(value).__repr__ is object.__repr__:  # "<… object at 0x…>": only its class says anything
        return type(value).__qualname__
    text = repr(value)
    return text if len(text) <= SHOWN else text[: SHOWN - 1] + "…"


def run_metrics(res: SimResult) -> dict[str, Any]:
    """The scalar metrics of a full result: status, divergence, duration, tracking error, peak torque."""
    out: dict[str, Any] = {
        "status": res.status,
        "diverged": bool(res.diverged),
        "diverged_at": math.nan if res.diverged_at is None else float(res.diverged_at),
        "duration": res.duration,
    }
    if res.reference is not None and len(res.reference.q) == len(res.t) and len(res.t):
        e = np.abs(res.error)
        e = e[~np.isnan(e).any(axis=1)]
        out["error_rms"] = float(np.sqrt((e**2).mean())) if e.size else math.nan
        out["error_max"] = float(e.max()) if e.size else math.nan
    if len(res.t):
        out["tau_peak"] = float(np.fmax.reduce(np.abs(res.tau_applied), axis=None))
    return out


def metrics(value: Any) -> dict[str, Any]:
    """The scalar metrics of what a case returned (see the module)."""
    from armctl.sim.result import SimResult

    if isinstance(value, SimResult):
        return run_metrics(value)
    if _is_scalar(value):
        return {"summary": _plain(value)}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        value = {f.name: getattr(value, f.name) for f in dataclasses.fields(value)}
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items() if _is_scalar(v)}
    if isinstance(value, Sequence) and all(_is_scalar(v) for v in value):
        return {f"summary[{k}]": _plain(v) for k, v in enumerate(value)}
    if isinstance(value, np.ndarray) and value.ndim == 1 and value.size <= 16:
        return {f"summary[{k}]": float(v) for k, v in enumerate(value)}
    return {}


def sweep_rows(
    outcomes: SweepResult, cases: Sequence[Mapping[str, Any]] | None, pending: Collection[int] = ()
) -> list[dict[str, Any]]:
    """One dict per case: settings, outcome, metrics (the columns of :func:`sweep_dataframe`); the cases in
    ``pending`` did not run (outcome ``"not_run"``)."""
    from armctl.sim.sweep_result import CaseFailure

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
    outcomes: SweepResult, cases: Sequence[Mapping[str, Any]] | None = None, pending: Collection[int] = ()
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
