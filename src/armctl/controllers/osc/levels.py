"""Task rows of one priority level: `LevelPlan` (what stays fixed between steps) and `LevelRows` (one step's
stacked rows [J | b] and weights)."""

from __future__ import annotations

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.layout import Layout
from armctl.controllers.osc.tasks.base import Task


class LevelRows:
    """Stacked task rows of one level: ``jr`` = [J | b] (m × (nx+1), unweighted), ``sqrt_w`` (m, 1) and the
    per-task row slices; ``T``, ``t`` the weighted rows W^{1/2} J, W^{1/2} b."""

    __slots__ = ("_Tt", "jr", "nx", "slices", "sqrt_w", "tasks")

    def __init__(self, tasks: tuple[Task, ...], jr: FloatArray, sqrt_w: FloatArray, slices: dict[str, slice]
                 ) -> None:
        self.tasks = tasks
        self.jr = jr
        self.nx = jr.shape[1] - 1
        self.sqrt_w = sqrt_w
        self.slices = slices
        self._Tt: FloatArray | None = None

    @property
    def Tt(self) -> FloatArray:
        """[T | t] = W^{1/2} [J | b]."""
        if self._Tt is None:
            self._Tt = self.sqrt_w * self.jr
        return self._Tt

    @property
    def T(self) -> FloatArray:
        return self.Tt[:, : self.nx]

    @property
    def t(self) -> FloatArray:
        return self.Tt[:, self.nx]

    def residuals(self, x: FloatArray) -> dict[str, FloatArray]:
        """Unweighted residual J_i x_i − b_i of every task of the level at ``x``."""
        r = self.jr[:, : self.nx] @ x[: self.nx] - self.jr[:, self.nx]
        return {name: r[s] for name, s in self.slices.items()}


class LevelPlan:
    """What does not change between steps for one level and one layout: its tasks, their rows and columns,
    [J | b] with the identity blocks already in place, and the square-root weights."""

    def __init__(self, tasks: tuple[Task, ...], lay: Layout) -> None:
        self.tasks = tasks
        m = sum(tk.dim for tk in tasks)
        nx = lay.nx
        self.template = np.zeros((m, nx + 1))
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
        self.version = -1
        self.sqrt_w = np.zeros((m, 1))

    def weights(self) -> FloatArray:
        if self.version != Task.weights_version:
            self.sqrt_w = np.concatenate([tk.sqrt_weight for tk in self.tasks])[:, None] if self.tasks \
                else np.zeros((0, 1))
            self.version = Task.weights_version
        return self.sqrt_w
