"""Normal-force laws of compliant contact: Kelvin–Voigt and Hunt–Crossley.

A law maps the penetration depth δ ≥ 0 [m] and its rate δ̇ [m/s] (positive while pressing in) to the normal
force magnitude f_n ≥ 0 [N] that pushes the bodies apart, with its partial derivatives (for the implicit
integrator). Forces are clamped at zero: a compliant contact never pulls.

Which law fits
--------------
Kelvin–Voigt, f_n = k δ + b δ̇: a linear spring and damper. Simple and exactly linear (static force = k δ),
but the damping force jumps to b δ̇ at first touch and, clamped, the contact loses energy in a way that does not
depend on the impact velocity the way real impacts do.

Hunt–Crossley, f_n = k δᵖ (1 + d δ̇): the damping grows with the depth, so the force is continuous at first
touch and the coefficient of restitution is e ≈ 1 − (2/3) d v_impact (Hunt & Crossley 1975); p = 3/2 is
Hertz's law for spheres, p = 1 a linear spring. Prefer it for impacts.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

from armctl._checks import scalar
from armctl.errors import InvalidParameterError

#: the largest contact coefficient taken (stiffness [N/m or N/mᵖ], damping [N·s/m], dissipation [s/m]): real
#: contacts lie around 1e3 to 1e10 N/m; far larger ones overflow the forces and the step's stability check
LARGEST_COEFFICIENT = 1e150


def coefficient(x: Any, name: str, unit: str, *, positive: bool = False) -> float:
    """A contact law's coefficient: a finite real number, > 0 if ``positive`` else >= 0, at most
    :data:`LARGEST_COEFFICIENT`."""
    v = scalar(x, f"{name} [{unit}]", positive=positive, nonnegative=not positive)
    if v > LARGEST_COEFFICIENT:
        raise InvalidParameterError(
            f"{name} = {v:g} {unit} is beyond what a simulation can represent (at most {LARGEST_COEFFICIENT:g}; "
            "real contacts lie around 1e3 to 1e10 N/m): its forces and the step's stability check would overflow",
            value=x,
        )
    return v


class NormalForce(ABC):
    """f_n(δ, δ̇) ≥ 0 and its partial derivatives."""

    @abstractmethod
    def force(self, depth: float, rate: float) -> tuple[float, float, float]:
        """(f_n, ∂f_n/∂δ, ∂f_n/∂δ̇) for a depth δ > 0 [m] and rate δ̇ [m/s]."""

    @property
    @abstractmethod
    def stiffness(self) -> float:
        """k, the static stiffness (for p = 1 in N/m)."""

    def depth_at(self, force: float) -> float:
        """Static penetration δ [m] under a normal force [N] (δ̇ = 0); the contact only pushes, so force >= 0."""
        f = scalar(force, "force", nonnegative=True)
        return float((f / self.stiffness) ** (1.0 / getattr(self, "exponent", 1.0)))


class KelvinVoigt(NormalForce):
    """Spring–damper contact f_n = max(0, k δ + b δ̇). stiffness: k [N/m] > 0; damping: b [N·s/m] ≥ 0."""

    def __init__(self, stiffness: float, damping: float = 0.0) -> None:
        self._k = coefficient(stiffness, "contact stiffness", "N/m", positive=True)
        self.damping = coefficient(damping, "contact damping", "N·s/m")

    @property
    def stiffness(self) -> float:
        return self._k

    def force(self, depth: float, rate: float) -> tuple[float, float, float]:
        f = self._k * depth + self.damping * rate
        if f <= 0.0:
            return 0.0, 0.0, 0.0
        return f, self._k, self.damping

    def __repr__(self) -> str:
        return f"KelvinVoigt(stiffness={self._k:g}, damping={self.damping:g})"


class HuntCrossley(NormalForce):
    """Hunt–Crossley contact f_n = max(0, k δᵖ (1 + d δ̇)).

    stiffness: k [N/mᵖ] > 0; dissipation: d [s/m] ≥ 0 (Hunt–Crossley's 3α/2); exponent: p ≥ 1 (1.5: Hertz)."""

    def __init__(self, stiffness: float, dissipation: float = 0.0, exponent: float = 1.0) -> None:
        self._k = coefficient(stiffness, "contact stiffness", "N/mᵖ", positive=True)
        self.dissipation = coefficient(dissipation, "contact dissipation", "s/m")
        self.exponent = scalar(exponent, "contact exponent", positive=True)
        if self.exponent < 1.0:
            raise InvalidParameterError(
                f"contact exponent must be >= 1 (its stiffness would be infinite at first touch), got {exponent}",
                value=exponent,
            )

    @classmethod
    def from_restitution(
        cls, stiffness: float, restitution: float, impact_velocity: float, exponent: float = 1.0
    ) -> HuntCrossley:
        """The law whose impacts at ``impact_velocity`` [m/s] rebound with coefficient of restitution e
        (d = 3(1 − e) / (2 v_impact), Hunt & Crossley's approximation, good for e near 1)."""
        e = scalar(restitution, "restitution", nonnegative=True)
        if e > 1.0:
            raise InvalidParameterError(
                f"restitution must be in [0, 1] (1: no loss; a passive contact cannot return "
                f"more energy than it took), got {e:g}",
                value=restitution,
            )
        v = scalar(impact_velocity, "impact velocity", positive=True)
        return cls(stiffness, 1.5 * (1.0 - e) / v, exponent)

    @property
    def stiffness(self) -> float:
        return self._k

    def force(self, depth: float, rate: float) -> tuple[float, float, float]:
        p = self.exponent
        dp = depth if p == 1.0 else depth**p
        damp = 1.0 + self.dissipation * rate
        if damp <= 0.0:
            return 0.0, 0.0, 0.0
        ddp = 1.0 if p == 1.0 else p * depth ** (p - 1.0)
        return self._k * dp * damp, self._k * ddp * damp, self._k * dp * self.dissipation

    def __repr__(self) -> str:
        return f"HuntCrossley(stiffness={self._k:g}, dissipation={self.dissipation:g}, exponent={self.exponent:g})"
