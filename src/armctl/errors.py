"""The errors armctl raises.

Every error derives from :class:`ArmctlError`; each subclass also derives from the matching builtin
(``ValueError``, ``KeyError``, …) so that generic handlers keep working. Errors carry the offending value
(``.value``) and say how to fix it.
"""

from __future__ import annotations

from typing import Any


class ArmctlError(Exception):
    """Root of every error raised by armctl.

    Parameters
    ----------
    message : str
        What is wrong and how to fix it.
    value : object, optional
        The offending value, kept as ``.value``.
    """

    def __init__(self, message: str, *, value: Any = None) -> None:
        super().__init__(message)
        self.value = value


class ShapeError(ArmctlError, ValueError):
    """An array has the wrong shape."""


class NonFiniteError(ArmctlError, ValueError):
    """An array holds NaN or infinity."""


class InvalidParameterError(ArmctlError, ValueError):
    """A physical or numerical parameter is out of its allowed range (negative mass, bad inertia, …)."""


class UnknownNameError(ArmctlError, KeyError, ValueError):
    """A name (frame, joint, backend, integrator, …) is not one of the valid names, which it lists. Both a
    ``KeyError`` (a lookup that failed) and a ``ValueError`` (an argument with a bad value), so that a handler
    written for either catches it."""

    def __init__(self, kind: str, name: Any, valid: list[str] | tuple[str, ...]) -> None:
        shown = ", ".join(repr(v) for v in valid[:40]) + (" …" if len(valid) > 40 else "")
        plural = (
            kind[:-1] + "ies" if kind.endswith("y") and kind[-2:-1] not in ("a", "e", "i", "o", "u") else kind + "s"
        )
        super().__init__(f"unknown {kind} {name!r}; valid {plural}: {shown}", value=name)
        self.kind, self.valid = kind, tuple(valid)

    def __reduce__(self) -> tuple[Any, ...]:  # pickled with the arguments of __init__ (not the message), so
        # that it crosses process boundaries: a worker's error reaches a sweep's caller intact
        return type(self), (self.kind, self.value, self.valid), self.__dict__

    def __str__(self) -> str:  # KeyError would otherwise print the repr of the message
        return str(self.args[0])


class ModelLoadError(ArmctlError, OSError):
    """A robot description (URDF, DH table) cannot be read or does not describe a supported arm."""


class OptionalDependencyError(ArmctlError, ImportError):
    """A feature needs a package that is not installed (an optional extra); the message names the ``pip install``
    command that adds it."""


class BackendError(ArmctlError, RuntimeError):
    """A dynamics backend cannot evaluate what was asked (e.g. a term it cannot express)."""


class SingularConfigurationError(ArmctlError, ValueError):
    """A configuration is (near) singular for what was asked: a task Jacobian without full row rank. Carries the
    smallest singular value (``.sigma_min``) and the task direction it belongs to (``.direction``)."""

    def __init__(self, message: str, *, value: Any = None, sigma_min: float = 0.0, direction: Any = None) -> None:
        super().__init__(message, value=value)
        self.sigma_min = sigma_min
        self.direction = direction


class InfeasibleError(ArmctlError, ValueError):
    """A problem (QP, time scaling, identification) has no solution; the error says which constraint binds
    and carries the problem (``.problem``) where there is one."""

    def __init__(self, message: str, *, value: Any = None, problem: Any = None) -> None:
        super().__init__(message, value=value)
        self.problem = problem


class InverseKinematicsError(InfeasibleError):
    """No joint vector within the joint limits puts a frame at a target (``Dynamics.inverse_kinematics``); carries
    the smallest residual found (``.residual``: [position (3,) [m]; rotation (3,) [rad]], the position alone for
    a position target) and its joint vector (``.q``)."""

    def __init__(self, message: str, *, value: Any = None, residual: Any = None, q: Any = None) -> None:
        super().__init__(message, value=value)
        self.residual = residual
        self.q = q


class SolverError(ArmctlError, RuntimeError):
    """A numerical solver failed (no convergence, numerical trouble); carries the problem and the solver's
    result where there are some."""

    def __init__(self, message: str, *, value: Any = None, problem: Any = None, result: Any = None) -> None:
        super().__init__(message, value=value)
        self.problem = problem
        self.result = result


class IdentifiabilityError(ArmctlError, ValueError):
    """Data do not excite the parameters enough; carries the unidentifiable directions (``.directions``)."""

    def __init__(self, message: str, *, value: Any = None, directions: Any = None) -> None:
        super().__init__(message, value=value)
        self.directions = directions


class SimulationWarning(UserWarning):
    """A simulation ran, but part of its result is not to be trusted (e.g. an explicit integrator beyond its
    stability limit on a stiff contact); the result's ``info`` says which part and how to fix it."""


class CacheWarning(UserWarning):
    """A compiled library found in the cache failed its checks (truncated, altered, built for another model)
    and was rebuilt; the message names the file and what was wrong with it. Nothing to fix: the rebuilt
    library is used and cached."""


class IdentificationWarning(UserWarning):
    """An identification input or result is not to be trusted in part (e.g. the kept samples still hold a
    filter's start-up transient); the message says which part and how to fix it."""


class WorkerDiedError(ArmctlError, RuntimeError):
    """The process running a sweep case died (a signal such as SIGKILL, ``os._exit``, a crash in compiled
    code), also on its retry. ``.value`` is the case."""


class RunTimeoutError(ArmctlError, TimeoutError):
    """A sweep case ran longer than the sweep's ``timeout``; its process was stopped. ``.value`` is the
    case."""


class SweepWarning(UserWarning):
    """Some cases of a sweep failed; the sweep's result holds a ``CaseFailure`` for each (type, message,
    traceback and the case)."""


class SolverWarning(UserWarning):
    """A solver needed help during a run (a fallback, a lower priority level kept from the level above) but the
    run went on; the warning says what happened and how often, once per run."""


class PerformanceWarning(UserWarning):
    """Generated code could not be used (no C compiler, a build that failed): a slower path gives the same results;
    the warning says why and how to get a compiler, once per process and cause."""


class SingularityWarning(UserWarning):
    """A controller met (near) singular configurations during a run and went on with a damped inverse there;
    the warning says on how many steps and how much damping, once per run."""
