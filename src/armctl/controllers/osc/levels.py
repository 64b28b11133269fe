"""Task rows of one priority level: `LevelPlan` (what stays fixed between steps) and `LevelRows` (one step's
stacked rows [J | b] and weights)."""

from __future__ import annotations

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.layout import Layout
from armctl.controllers.osc.tasks.base import Task


class LevelRows:
    """Stacked task rows of one level: ``jr`` = [J | b] (m × (nx+1), unweighted), ``scale`` (m × (nx+1): each
    row's square-root weight, negated in the last column) and the per-task row slices; ``T``, ``t`` the weighted
    rows W^{1/2} J, W^{1/2} b, and ``Tn`` = scale ⊙ jr = [T | −t], whose Gram matrix holds the cost's TᵀT and
    g = −Tᵀt (see build.level_cost)."""

    __slots__ = ("_Tn", "jr", "nx", "scale", "slices", "tasks")

    def __init__(self, tasks: tuple[Task, ...], jr: FloatArray, scale: FloatArray, slices: dict[str, slice]) -> None:
        self.tasks = tasks
        self.jr = jr
        self.nx = jr.shape[1] - 1
        self.scale = scale
        self.slices = slices
        self._Tn: FloatArray | None = None

    @property
    def Tn(self) -> FloatArray:
        """[T | −t] (an elementwise product with a weight matrix of the same shape)."""
        if self._Tn is None:
            self._Tn = self.scale * self.jr
        return self._Tn

    @property
    def T(self) -> FloatArray:
        return self.Tn[:, : self.nx]

    @property
    def t(self) -> FloatArray:
        return np.negative(self.Tn[:, self.nx])

    def residuals(self, x: FloatArray) -> dict[str, FloatArray]:
        """Unweighted residual J_i x_i − b_i of every task of the level at ``x``."""
        r = self.jr[:, : self.nx] @ x[: self.nx] - self.jr[:, self.nx]
        return {name: r[s] for name, s in self.slices.items()}


class LevelPlan:
    """What does not change between steps for one level and one layout: its tasks, their rows and columns,
    [J | b] with the identity blocks already in place, and the square-root weights. ``extra_rows`` rows of
    weight ``extra_weight`` follow the tasks' rows (left zero: the caller fills them every step; they are no
    task's and no residual reports them)."""

    def __init__(self, tasks: tuple[Task, ...], lay: Layout, extra_rows: int = 0, extra_weight: float = 0.0) -> None:
        self.tasks = tasks
        m = sum(tk.dim for tk in tasks)
        nx = lay.nx
        self.extra = (int(extra_rows), float(extra_weight))
        self.template = np.zeros((m + self.extra[0], nx + 1))
        self.slices: dict[str, slice] = {}
        self.entries: list[tuple[Task, slice, slice | None]] = []
        r = 0
        for tk in tasks:
            rows, cols = slice(r, r + tk.dim), lay.variables[tk.variable]
            if tk.identity_jacobian:
                blk = self.template[rows, cols]
                blk.flat[:: tk.dim + 1] = 1.0
            self.slices[tk.name] = rows
            self.entries.append((tk, rows, cols))
            r += tk.dim
        self.m = m
        self.nx = nx
        self._revisions: list[int] | None = None  # the tasks' revisions the scale was made from
        self._scale = np.zeros(self.template.shape)

    def scale(self) -> FloatArray:
        """The square-root weights of the rows, as LevelRows.scale (rows × (nx+1), last column negated); made
        again when a task's weight has changed (its ``revision``)."""
        revisions = [tk.revision for tk in self.tasks]
        if revisions != self._revisions:
            scale = np.zeros(self.template.shape)
            if self.tasks:
                scale[: self.m] = np.concatenate([tk.sqrt_weight for tk in self.tasks])[:, None]
            scale[self.m :] = np.sqrt(self.extra[1])
            scale[:, self.nx] *= -1.0
            self._scale = scale
            self._revisions = revisions
        return self._scale
