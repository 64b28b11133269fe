"""`Verdict`: what a textbook stability condition says about given gains, with its margin and source."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from armctl._checks import gain_matrix
from armctl.errors import InvalidParameterError
from armctl.tuning.bounds import ModelBounds


@dataclass(frozen=True)
class Verdict:
    """The outcome of one stability condition.

    Attributes
    ----------
    name : str
        The condition's name.
    holds : bool
        The condition is met.
    margin : float
        How far inside it (> 0) or outside (< 0), in ``unit``.
    factor : float
        The same as a ratio (> 1 inside; e.g. λ_min(K_p)/k_g).
    unit : str
        The unit of ``margin``.
    condition : str
        The inequality with the numbers put in.
    certified : bool
        Every model constant it rests on is a certified bound (else estimates from a sample: the condition may
        fail somewhere the sample missed).
    source : str
        Where the condition is proved.
    details : dict
        The other figures (named in each function's docstring).
    """

    name: str
    holds: bool
    margin: float
    factor: float
    unit: str
    condition: str
    certified: bool
    source: str
    details: dict[str, Any] = field(default_factory=dict)

    def summary(self) -> str:
        """One line: the condition, whether it holds, its margin and on what it rests (certified bounds or sampled
        estimates).

        Returns
        -------
        str
        """
        state = "holds" if self.holds else "fails"
        basis = "certified bounds" if self.certified else "sampled estimates of the bounds"
        unit = f" {self.unit}" if self.unit else ""
        return (
            f"{self.name}: {state} ({self.condition}; margin {self.margin:.4g}{unit}, factor "
            f"{self.factor:.4g}; on {basis}). Source: {self.source}"
        )

    def __str__(self) -> str:
        return self.summary()


_FAILS = {">": "≤", "<": "≥"}


def inequality(left: str, relation: str, right: str, holds: bool) -> str:
    """The comparison as it stands: ``"a > b"`` when it holds, ``"a ≤ b: fails (a > b required)"`` when not.

    Parameters
    ----------
    left, right : str
        The two sides, with their numbers (``"λ_min(K_p) = 10"``).
    relation : {">", "<"}
        The relation the condition requires.
    holds : bool
        Whether it holds.

    Returns
    -------
    str
    """
    if holds:
        return f"{left} {relation} {right}"
    required = f"{left.split(' = ')[0]} {relation} {right.split(' = ')[0]}"
    return f"{left} {_FAILS[relation]} {right}: fails ({required} required)"


def certified_inputs(bounds: ModelBounds, *names: str) -> bool:
    """True if the constants ``names`` of ``bounds`` are certified; raise if an inertia bound is not usable."""
    if not isinstance(bounds, ModelBounds):
        raise InvalidParameterError(
            f"bounds must be a ModelBounds (armctl.tuning.model_bounds(dynamics)), got {type(bounds).__name__}",
            value=bounds,
        )
    for name in names:
        if not bounds.details[name].informative:
            raise InvalidParameterError(
                f"the certified {name} of {bounds.model!r} is not positive ({bounds.details[name].value:.3g}): the "
                "certificate ran out of boxes; raise max_boxes, narrow joint_ranges, or use method='sampled'",
                value=bounds.details[name].value,
            )
    return all(bounds.details[name].certified for name in names)


def eigen_range(gain: Any, n: int, name: str) -> tuple[float, float]:
    """(λ_min, λ_max) of a gain given as a scalar, a vector (diagonal) or a symmetric positive definite matrix."""
    k = gain_matrix(gain, n, name)
    eig = np.linalg.eigvalsh(k)
    return float(eig[0]), float(eig[-1])
