"""The identification problem W θ = y, built from data before anything is solved.

Stacking the base regressor over the S samples (sample-major: rows k n … k n + n − 1 are sample k) gives

    y = [τ(t_1); …; τ(t_S)] = W θ + e,     W = [Y_b(x_1)  O(q̇_1); …; Y_b(x_S)  O(q̇_S)]

where θ are the base parameters and, when ``offsets`` is on, n extra unknowns: the Coulomb asymmetry
δ = ½(F_c⁺ − F_c⁻) of each joint, with the column O = diag(|sgn q̇_i|) (see ``Dynamics.coulomb_offset``). A
real robot also puts its torque-sensor offsets there. Y_b's Coulomb columns are sgn q̇_i here
(:func:`~armctl.dynamics.identification.base_parameters.identification_regressor`), so θ holds the mean
level and O the asymmetry, whatever the model's own ratio of the two.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from armctl._checks import FloatArray, boolean, readonly, real_array, whole_number
from armctl.dynamics.base import Dynamics
from armctl.dynamics.identification.base_parameters import (
    BaseParameters,
    find_base_parameters,
    identification_regressor,
    random_states,
)
from armctl.dynamics.identification.data import IdentificationData
from armctl.errors import IdentifiabilityError, InvalidParameterError, NonFiniteError, ShapeError


@dataclass(frozen=True)
class IdentificationProblem:
    """W θ = y (see the module).

    Attributes
    ----------
    regressor : ndarray, shape (S n, p)
        The stacked regressor W.
    torque : ndarray, shape (S n,)
        The stacked torques y [N·m].
    base : BaseParameters
        The base parameters.
    n : int
        The number of joints.
    offsets : bool
        Whether the last n unknowns are Coulomb offsets.
    names : tuple of str
        The (p,) names of the unknowns.
    """

    regressor: FloatArray
    torque: FloatArray
    base: BaseParameters
    n: int
    offsets: bool
    names: tuple[str, ...]

    def __post_init__(self) -> None:
        n = whole_number(self.n, "n", minimum=1)
        object.__setattr__(self, "n", n)
        object.__setattr__(self, "offsets", boolean(self.offsets, "offsets"))
        if not isinstance(self.base, BaseParameters):
            raise InvalidParameterError(
                f"base must be a BaseParameters (see find_base_parameters), got {type(self.base).__name__}",
                value=self.base,
            )
        w = np.array(real_array(self.regressor, "regressor"))
        y = np.array(real_array(self.torque, "torque")).reshape(-1)
        if w.ndim != 2 or w.shape[0] != y.shape[0] or w.shape[1] != len(self.names) or y.shape[0] % self.n:
            raise ShapeError(
                f"regressor {w.shape}, torque {y.shape} and {len(self.names)} names do not match (n = {self.n})",
                value=(w.shape, y.shape),
            )
        for name, a in (("regressor", w), ("torque", y)):
            if not np.isfinite(a).all():
                first = np.argwhere(~np.isfinite(a))[0].tolist()
                raise NonFiniteError(
                    f"{name} holds NaN or inf (first at index {first}); check the data the problem was built from",
                    value=a,
                )
        object.__setattr__(self, "regressor", readonly(w))
        object.__setattr__(self, "torque", readonly(y))

    @property
    def samples(self) -> int:
        return self.torque.shape[0] // self.n

    @property
    def n_unknowns(self) -> int:
        return self.regressor.shape[1]

    def joint_rows(self, i: int) -> slice:
        """The rows of joint i in W and y.

        Parameters
        ----------
        i : int
            The joint, 0-based.

        Returns
        -------
        slice
        """
        return slice(i, None, self.n)


def offset_names(n: int) -> tuple[str, ...]:
    return tuple(f"Fc_offset[{i}]" for i in range(n))


def problem_regressor(
    dynamics: Dynamics, base: BaseParameters, q: FloatArray, qd: FloatArray, qdd: FloatArray, offsets: bool
) -> FloatArray:
    """The regressor blocks [Y_b  O] (S, n, p) for samples (S, n) of q, q̇, q̈ (see the module)."""
    n = dynamics.n
    cols = list(base.independent)
    out = np.zeros((q.shape[0], n, base.n_base + (n if offsets else 0)))
    diag = np.arange(n)
    for k in range(q.shape[0]):
        out[k, :, : base.n_base] = identification_regressor(dynamics, q[k], qd[k], qdd[k])[:, cols]
        if offsets:
            out[k, diag, base.n_base + diag] = np.abs(np.sign(qd[k]))
    return out


def structural_offsets(dynamics: Dynamics, base: BaseParameters, seed: int = 0) -> list[int]:
    """The joints whose Coulomb-offset column is, at random states (every joint moving), a combination of the
    base parameters' columns to rounding: offsets no trajectory can identify."""
    rng = np.random.default_rng(seed)
    n, nb = dynamics.n, base.n_base
    states = random_states(dynamics, 4 * (nb + n) // n + 8, rng)
    w = problem_regressor(dynamics, base, states[:, 0], states[:, 1], states[:, 2], True).reshape(-1, nb + n)
    yb, cols = w[:, :nb], w[:, nb:]
    residual = cols - yb @ np.linalg.lstsq(yb, cols, rcond=None)[0]  # one factorisation for every joint
    return [i for i in range(n) if np.linalg.norm(residual[:, i]) <= 1e-8 * np.linalg.norm(cols[:, i])]


def build_problem(
    dynamics: Dynamics,
    data: IdentificationData | Sequence[IdentificationData],
    base: BaseParameters | None = None,
    offsets: bool = True,
) -> IdentificationProblem:
    """Stack the regressor of an arm over data (one experiment or several).

    The regressor is evaluated at every sample, then it and τ are filtered and decimated alike
    (``IdentificationData.reduce``).

    Parameters
    ----------
    dynamics : Dynamics
        The arm.
    data : IdentificationData or sequence of IdentificationData
        The experiments.
    base : BaseParameters, optional
        The base parameters (default: found with :func:`find_base_parameters`).
    offsets : bool, optional
        Add the Coulomb asymmetry of each joint as an unknown.

    Returns
    -------
    IdentificationProblem
    """
    offsets = boolean(offsets, "offsets")
    experiments = (
        [data]
        if isinstance(data, IdentificationData)
        else list(data)
        if isinstance(data, Sequence) and not isinstance(data, str | bytes)
        else [data]
    )
    if not experiments or not all(isinstance(d, IdentificationData) for d in experiments):
        raise InvalidParameterError(
            f"data must be an IdentificationData (see prepare_data) or a non-empty sequence of them, got {data!r:.80}",
            value=data,
        )
    for d in experiments:
        if d.n != dynamics.n:
            raise ShapeError(f"data have {d.n} joints, the model {dynamics.n}", value=d.n)
    base = base if base is not None else find_base_parameters(dynamics)
    if not isinstance(base, BaseParameters):
        raise InvalidParameterError(
            f"base must be a BaseParameters (see find_base_parameters), got {type(base).__name__}", value=base
        )
    if base.n_full != dynamics.n * 13:
        raise ShapeError(f"base parameters are for {base.n_full // 13} joints, the model has {dynamics.n}", value=base)
    if offsets:
        lumped = structural_offsets(dynamics, base)
        if lumped:
            raise IdentifiabilityError(
                f"the Coulomb offset of joint(s) {lumped} (0-based) cannot be told apart from the base parameters "
                "for any motion: its column |sgn q̇_i| is a combination of theirs, as when the joint's load has a "
                "constant part (the gravity load of a vertical prismatic axis). No trajectory can excite it; pass "
                "offsets=False (the Coulomb asymmetry is then not estimated)",
                value=lumped,
                directions=None,
            )
    ws, ys = [], []
    for d in experiments:
        w = problem_regressor(dynamics, base, d.q, d.qd, d.qdd, offsets)
        ws.append(d.reduce(w.reshape(d.samples, -1)).reshape(-1, w.shape[2]))
        ys.append(d.reduce(d.tau).reshape(-1))
    names = base.base_names() + (offset_names(dynamics.n) if offsets else ())
    return IdentificationProblem(np.vstack(ws), np.concatenate(ys), base, dynamics.n, offsets, names)
