"""The option groups of :func:`armctl.sim.simulate`: what the controller measures (:class:`Sensing`), the forces
the plant feels besides its own dynamics (:class:`Forces`) and when a run stops as diverged (:class:`StopRules`).

Each group can be passed to ``simulate`` as one object, or its fields as keywords of ``simulate``
(``simulate(..., noise_q=0.01)`` is ``simulate(..., sensing=Sensing(noise_q=0.01))``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

from numpy.typing import ArrayLike

from armctl.errors import InvalidParameterError

if TYPE_CHECKING:
    from armctl.sim.contact import Environment, ForceSensor
    from armctl.sim.friction import FrictionModel


@dataclass(frozen=True)
class Sensing:
    """What the controller measures, and how.

    Parameters
    ----------
    noise_q, noise_qd : float or (n,) array_like
        Standard deviations of Gaussian measurement noise on q [rad or m] and q̇ [rad/s or m/s] (scalar or per
        joint); 0: exact measurements.
    seed : int, optional
        Seed of the noise (None: a fresh seed, kept in ``res.info["seed"]`` to repeat the run).
    delay : int
        The controller sees the measurement of ``delay`` control periods earlier (the first one before that).
    sensors : ForceSensor or sequence of ForceSensor
        Force sensors, recorded in ``res.sensor``; the first one feeds a controller that reads ``"wrench"``
        (:mod:`armctl.controllers.measurement`).
    noise_wrench : float or (6,) array_like
        Standard deviation of the noise on the wrench a controller reads [N, N·m] (the recorded ``res.sensor`` is
        the true reading).
    noise_tau : float or (n,) array_like
        Standard deviation of the noise on the joint torques a controller reads as ``"tau_measured"`` [N·m].
    cutoff : float, optional
        Cut-off frequency [Hz] of a first-order low-pass filter on the wrench and the measured torques a
        controller reads (None: unfiltered). See :class:`~armctl.sim.signal_chain.SignalChain`.

    Notes
    -----
    A controller that declares signals in ``reads`` is given them at every sample, each through its chain: noise,
    the filter, and ``delay`` periods of delay. ``"tau_applied"`` is τ_{k−1} after saturation, exact.
    """

    noise_q: ArrayLike = 0.0
    noise_qd: ArrayLike = 0.0
    seed: int | None = None
    delay: int = 0
    sensors: ForceSensor | Sequence[ForceSensor] = ()
    noise_wrench: ArrayLike = 0.0
    noise_tau: ArrayLike = 0.0
    cutoff: float | None = None


@dataclass(frozen=True)
class Forces:
    """The forces on the plant besides its rigid-body dynamics and the actuators.

    Parameters
    ----------
    friction : {"stick-slip", "smooth"} or FrictionModel
        The model applied to the plant model's joint friction: ``"stick-slip"`` (Karnopp, exact sticking,
        breakaway at the static level), ``"smooth"`` (tanh) or a :class:`~armctl.sim.friction.FrictionModel`.
    environment : Environment or sequence of Environment, optional
        Contact environments (planes, walls) with their contact points.
    disturbance : callable, optional
        t [s] → h_d (6,) [N, N·m], a wrench at the tool frame with the sign of Dynamics' ``wrench`` (what the arm
        exerts: a push F on the arm is −F).
    """

    friction: str | FrictionModel = "stick-slip"
    environment: Environment | Sequence[Environment] | None = None
    disturbance: Callable[[float], ArrayLike] | None = None


@dataclass(frozen=True)
class StopRules:
    """When a run stops as diverged (it also stops on a non-finite state or torque, and on a mass matrix that is no
    longer positive definite).

    Parameters
    ----------
    max_velocity : float
        Largest |q̇_i| [rad/s or m/s] (inf: no bound).
    max_position : float
        Largest |q_i| [rad or m] (inf: no bound).
    """

    max_velocity: float = 1e3
    max_position: float = math.inf


#: the option groups and the ``simulate`` keywords that are their fields
GROUPS: dict[str, type] = {"sensing": Sensing, "forces": Forces, "stop": StopRules}


def grouped(groups: dict[str, Any], keywords: dict[str, Any]) -> tuple[Sensing, Forces, StopRules]:
    """The three groups from ``groups`` (name → an object of its class or None) and the flat ``keywords`` that
    were given (field name → value); a field given both ways is refused by name."""
    out: list[Any] = []
    for name, cls in GROUPS.items():
        given = groups.get(name)
        if given is not None and not isinstance(given, cls):
            raise InvalidParameterError(f"{name} must be an armctl.sim.{cls.__name__}, got {given!r}", value=given)
        own = {f.name: keywords[f.name] for f in fields(cls) if f.name in keywords}
        if given is not None and own:
            raise InvalidParameterError(
                f"{', '.join(own)} given both as keyword(s) and in {name}={given!r}: give each option once",
                value=own,
            )
        out.append(given if given is not None else cls(**own))
    return out[0], out[1], out[2]
