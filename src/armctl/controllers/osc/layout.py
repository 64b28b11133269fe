"""`Layout`: the decision variables of the QP for one set of active contacts, and the parts of the rows that
do not change between control steps (C, the names, the constant bounds, the regularisation).

    x = [q̈ (n); τ (n); f_c (3) per active contact]
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from armctl._checks import FloatArray
from armctl.controllers.osc.contact import Contact
from armctl.controllers.osc.limits.base import Limit
from armctl.model.robot import RobotModel

#: regularisation of the levels above the last, relative to ``regularization``
UPPER_REGULARIZATION_FACTOR = 1e-4


class Layout:
    """Variable blocks and the constant parts (C, names) for one set of active contacts."""

    def __init__(
        self, model: RobotModel, limits: Sequence[Limit], contacts: Sequence[Contact], regularization: float
    ) -> None:
        n = model.n
        self.n = n
        self.contacts = tuple(contacts)
        self.variables: dict[str, slice] = {"qdd": slice(0, n), "tau": slice(n, 2 * n)}
        col = 2 * n
        for c in contacts:
            self.variables[c.name] = slice(col, col + c.dim)
            col += c.dim
        self.nx = col
        self.eq_names = tuple(
            [f"dynamics[{j}]" for j in model.joint_names] + [nm for c in contacts for nm in c.eq_names]
        )
        rows: list[FloatArray] = []
        names: list[str] = []
        lo: list[FloatArray] = []
        up: list[FloatArray] = []
        for lim in limits:
            blk = np.zeros((n, col))
            blk[:, self.variables[lim.variable]] = np.eye(n)
            rows.append(blk)
            names += lim.row_names
        for c in contacts:
            cf, cl, cu, cn = c.cone_rows()
            blk = np.zeros((cf.shape[0], col))
            blk[:, self.variables[c.name]] = cf
            rows.append(blk)
            lo.append(cl)
            up.append(cu)
            names += cn
        self.C = np.vstack(rows) if rows else np.zeros((0, col))
        self.C.flags.writeable = False
        self.ineq_names = tuple(names)
        self.cone_l = np.concatenate(lo) if lo else np.zeros(0)
        self.cone_u = np.concatenate(up) if up else np.zeros(0)
        self.limits = tuple(limits)
        self.regularization = np.full(col, regularization)
        self.regularization.flags.writeable = False
        self.reg_matrix = np.diag(self.regularization)
        self.reg_matrix_upper = UPPER_REGULARIZATION_FACTOR * self.reg_matrix
        # bounds that do not depend on the state (e.g. torque limits) are concatenated once
        self.constant_bounds: tuple[FloatArray, FloatArray] | None = None
        if all(lim.constant for lim in limits):
            bounds = [lim.bounds(None) for lim in limits]  # type: ignore[arg-type]  # constant: no state read
            self.constant_bounds = (
                np.concatenate([bd[0] for bd in bounds] + [self.cone_l]),
                np.concatenate([bd[1] for bd in bounds] + [self.cone_u]),
            )
            for a in self.constant_bounds:
                a.flags.writeable = False
        # equation of motion: A = [M, −I, −J_cᵀ …]; the −I block is constant
        self.A_template = np.zeros((len(self.eq_names), col))
        self.A_template[:n, n : 2 * n] = -np.eye(n)
        #: A's columns right of M's (contiguous: without contacts, A = [M, A_rest] in one concatenation)
        self.A_rest = np.ascontiguousarray(self.A_template[:, n:])
        self.A_rest.flags.writeable = False
