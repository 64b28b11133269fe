"""Normal-force laws of compliant contact: :class:`KelvinVoigt` (a spring and damper) and :class:`HuntCrossley`
(damping that grows with the depth; prefer it for impacts). What a law computes is given with :class:`NormalForce`,
each law's equation and where it fits with its class.
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
    """A normal-force law of compliant contact: the force f_n(δ, δ̇) ≥ 0 [N] that pushes two bodies apart, from
    the penetration depth δ ≥ 0 [m] and its rate δ̇ [m/s] (positive while pressing in), with its partial
    derivatives (for the implicit integrators). A :class:`Plane` takes one.

    A subclass implements :meth:`force` and :attr:`stiffness`; forces are clamped at zero, since a compliant
    contact never pulls.
    """

    @abstractmethod
    def force(self, depth: float, rate: float) -> tuple[float, float, float]:
        """The normal force and its partial derivatives at one contact (unchecked: the simulator's plant calls it
        at every evaluation).

        Parameters
        ----------
        depth : float
            The penetration δ > 0 [m].
        rate : float
            Its rate δ̇ [m/s], positive while pressing in.

        Returns
        -------
        f_n : float
            The normal force [N], ≥ 0.
        df_ddepth : float
            ∂f_n/∂δ [N/m] (0 where f_n is clamped at 0).
        df_drate : float
            ∂f_n/∂δ̇ [N·s/m] (0 where f_n is clamped at 0).
        """

    @property
    @abstractmethod
    def stiffness(self) -> float:
        """k, the static stiffness: f_n = k δᵖ at rest [N/mᵖ] (N/m for p = 1)."""

    def depth_at(self, force: float) -> float:
        """The static penetration under a normal force (δ̇ = 0): δ = (f_n/k)^(1/p).

        Parameters
        ----------
        force : float
            The normal force f_n ≥ 0 [N] (the contact only pushes).

        Returns
        -------
        float
            δ [m].

        Raises
        ------
        InvalidParameterError
            ``force`` is negative or not a number.
        NonFiniteError
            ``force`` is NaN or infinite.
        """
        f = scalar(force, "force", nonnegative=True)
        return float((f / self.stiffness) ** (1.0 / getattr(self, "exponent", 1.0)))


class KelvinVoigt(NormalForce):
    """Spring–damper contact: f_n = max(0, k δ + b δ̇).

    Simple and exactly linear (the static force is k δ), but the damping force jumps to b δ̇ at first touch
    and, clamped at zero, the contact loses energy in a way that does not depend on the impact velocity the way
    real impacts do; prefer :class:`HuntCrossley` for impacts.

    Parameters
    ----------
    stiffness : float
        k > 0 [N/m].
    damping : float, optional
        b ≥ 0 [N·s/m].

    Attributes
    ----------
    damping : float
        The damping b [N·s/m].

    Raises
    ------
    InvalidParameterError
        ``stiffness`` not > 0, ``damping`` < 0, either not a number or above
        :data:`~armctl.sim.normal_force.LARGEST_COEFFICIENT`.
    NonFiniteError
        ``stiffness`` or ``damping`` is NaN or infinite.

    Notes
    -----
    The partial derivatives :meth:`force` returns are ∂f_n/∂δ = k and ∂f_n/∂δ̇ = b while f_n > 0.
    """

    def __init__(self, stiffness: float, damping: float = 0.0) -> None:
        self._k = coefficient(stiffness, "contact stiffness", "N/m", positive=True)
        self.damping = coefficient(damping, "contact damping", "N·s/m")

    @property
    def stiffness(self) -> float:
        return self._k

    def force(self, depth: float, rate: float) -> tuple[float, float, float]:
        # (a second source: armctl.sim.generated_plant.PlantExpressions.contact, the generated step's;
        # a change here is a change there: tests/sim/test_compiled_plant.py fails when they disagree)
        f = self._k * depth + self.damping * rate
        if f <= 0.0:
            return 0.0, 0.0, 0.0
        return f, self._k, self.damping

    def __repr__(self) -> str:
        return f"KelvinVoigt(stiffness={self._k:g}, damping={self.damping:g})"


class HuntCrossley(NormalForce):
    """Hunt–Crossley contact: f_n = max(0, k δᵖ (1 + d δ̇)).

    The damping grows with the depth, so the force is continuous at first touch and the energy an impact loses
    grows with its velocity, as in real impacts. :meth:`from_restitution` picks d for a coefficient of
    restitution.

    Parameters
    ----------
    stiffness : float
        k > 0 [N/mᵖ] (N/m for p = 1).
    dissipation : float, optional
        d ≥ 0 [s/m] (3α/2 in Hunt & Crossley's notation).
    exponent : float, optional
        p ≥ 1: 1 a linear spring, 1.5 Hertz's law for spheres.

    Attributes
    ----------
    dissipation : float
        The dissipation d [s/m].
    exponent : float
        The exponent p.

    Raises
    ------
    InvalidParameterError
        ``stiffness`` not > 0, ``dissipation`` < 0, ``exponent`` < 1 (the stiffness would be infinite at first
        touch), a value that is not a number, or a coefficient above
        :data:`~armctl.sim.normal_force.LARGEST_COEFFICIENT`.
    NonFiniteError
        A value is NaN or infinite.

    Notes
    -----
    The partial derivatives :meth:`force` returns, while f_n > 0, are::

        ∂f_n/∂δ = k p δᵖ⁻¹ (1 + d δ̇),        ∂f_n/∂δ̇ = k d δᵖ

    An impact at velocity v rebounds with the coefficient of restitution e ≈ 1 − (2/3) d v, good for e near 1
    (K. H. Hunt and F. R. E. Crossley, "Coefficient of restitution interpreted as damping in vibroimpact",
    J. Appl. Mech. 42, 1975).
    """

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
        """The law whose impacts at a given velocity rebound with a given coefficient of restitution.

        Parameters
        ----------
        stiffness : float
            k > 0 [N/mᵖ].
        restitution : float
            The coefficient of restitution e, in [0, 1] (1: no loss).
        impact_velocity : float
            The impact velocity v_impact > 0 [m/s].
        exponent : float, optional
            p ≥ 1.

        Returns
        -------
        HuntCrossley
            The law with d = 3(1 − e) / (2 v_impact) (Hunt & Crossley's approximation, good for e near 1).

        Raises
        ------
        InvalidParameterError
            ``restitution`` outside [0, 1], ``impact_velocity`` not > 0, or a value the constructor refuses.
        NonFiniteError
            A value is NaN or infinite.
        """
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
        # (a second source: armctl.sim.generated_plant.PlantExpressions.contact, the generated step's;
        # a change here is a change there: tests/sim/test_compiled_plant.py fails when they disagree)
        p = self.exponent
        dp = depth if p == 1.0 else depth**p
        damp = 1.0 + self.dissipation * rate
        if damp <= 0.0:
            return 0.0, 0.0, 0.0
        ddp = 1.0 if p == 1.0 else p * depth ** (p - 1.0)
        return self._k * dp * damp, self._k * ddp * damp, self._k * dp * self.dissipation

    def __repr__(self) -> str:
        return f"HuntCrossley(stiffness={self._k:g}, dissipation={self.dissipation:g}, exponent={self.exponent:g})"
