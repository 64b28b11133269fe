"""A run as a table and as labelled arrays: :meth:`SimResult.to_dataframe <armctl.sim.SimResult.to_dataframe>` and
:meth:`SimResult.to_xarray <armctl.sim.SimResult.to_xarray>`, and a run's scalar metrics (:func:`run_metrics`,
also a ready ``summary=`` for :func:`~armctl.sim.sweep`). A sweep's table is :mod:`armctl.sim.sweep_table`.

pandas and xarray are optional (``pip install "armctl[data]"``, which adds pyarrow for Parquet files too): they
are imported here, when a conversion is first asked for, never by ``import armctl``; without them the methods
raise :class:`~armctl.errors.OptionalDependencyError` saying how to install them.

The functions read a run through :class:`~armctl.sim.run_record.RunRecord` (what a
:class:`~armctl.sim.SimResult` is), so that the result can offer them as methods.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

import numpy as np

from armctl.errors import InvalidParameterError, OptionalDependencyError
from armctl.sim.case_settings import plain
from armctl.sim.run_record import RunRecord

INSTALL = 'pip install "armctl[data]"'
LAYOUTS = ("long", "wide")

# per-joint arrays of a run in a table: (column, attribute, what, unit of a revolute / prismatic joint)
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


def _columns(res: RunRecord) -> list[tuple[str, Any, str, str]]:
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


def sim_dataframe(res: RunRecord, layout: str = "long") -> Any:
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


def sim_xarray(res: RunRecord) -> Any:
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
            attrs[k] = plain(v)
    return xr.Dataset(data, coords=coords, attrs=attrs)


def run_metrics(res: RunRecord) -> dict[str, Any]:
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
