"""`Controller`: the base of every controller, built-in or written by a user.

A controller maps ``(t, q, q̇, reference) → τ``. It is a plain object: call it from ``armctl.simulate`` or
from your own 1 kHz loop. Subclasses implement :meth:`Controller.compute`; ``__call__`` checks the inputs
once and hands them on. Per-step values worth logging (parameter estimates, a Lyapunov function, …) go in
``self.last_log``, a dict the simulator records after every control step.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Any, ClassVar, NoReturn

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FLOAT, FloatArray, all_finite, scalar, vector, whole_number
from armctl.controllers.measurement import Measurement
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError, NonFiniteError, ShapeError
from armctl.references import Reference


class Controller(ABC):
    """Base class of the controllers: ``tau = controller(t, q, qd, ref)`` checks its inputs, then calls
    :meth:`compute`, the control law.

    Parameters
    ----------
    dynamics : Dynamics, optional
        The controller's own model (it may be reduced or wrong on purpose), or None for a model-free controller.
    n : int, optional
        The number of joints, required without ``dynamics``.

    Raises
    ------
    InvalidParameterError
        ``dynamics`` is not a Dynamics, or neither it nor ``n`` is given.
    """

    def __init__(self, dynamics: Dynamics | None = None, n: int | None = None) -> None:
        if dynamics is not None and not isinstance(dynamics, Dynamics):
            raise InvalidParameterError(
                f"dynamics must be an armctl.Dynamics, got {type(dynamics).__name__}", value=dynamics
            )
        if dynamics is None and n is None:
            raise InvalidParameterError("a controller without dynamics needs n (the number of joints)", value=n)
        self.dynamics = dynamics
        self.n = dynamics.n if dynamics is not None else whole_number(n, "n (the number of joints)", 1)
        self._shape = (self.n,)
        self.last_log: dict[str, Any] = {}
        #: the measurement of the last call (:class:`~armctl.controllers.measurement.Measurement`), or None
        self.measurement: Measurement | None = None

    #: the signals this controller reads besides q and q̇ (names of
    #: :data:`armctl.controllers.measurement.SIGNALS`): ``simulate`` feeds them through its measurement chain,
    #: and a call without them raises. Empty: the controller reads q and q̇ only. A class attribute, which an
    #: instance may set for itself (a force controller reads what its force source needs).
    reads: frozenset[str] = frozenset()

    def measured(self, name: str) -> FloatArray:
        """The signal ``name`` of the current measurement (see :mod:`armctl.controllers.measurement`).

        Parameters
        ----------
        name : str
            A name of :data:`armctl.controllers.measurement.SIGNALS` (``"wrench"``, ``"tau_applied"``, ...).

        Returns
        -------
        ndarray
            Its value in the measurement of the current call.

        Raises
        ------
        InvalidParameterError
            The controller was called without a measurement that carries it.
        """
        m = self.measurement
        value = getattr(m, name, None) if m is not None else None
        if value is None:
            raise InvalidParameterError(
                f"{type(self).__name__} reads {name!r}, and it was called without it: in simulate give the signal's "
                f"source (a ForceSensor in Sensing(sensors=...) for 'wrench'); in your own loop call "
                f"controller(t, q, qd, ref, measurement=Measurement({name}=...))",
                value=m,
            )
        return value

    #: Declared by a class whose ``compute`` keeps no state between calls and gives a NaN or inf τ whenever an
    #: entry of q or q̇ is one (the built-in PD, computed torque and passivity laws): then only τ is checked for
    #: finiteness (one check instead of two), and the inputs only when τ is not finite (to name the culprit).
    #: Otherwise (False: users' controllers, laws with state) the inputs are checked before ``compute`` and τ
    #: after it. Either way a non-finite τ from a finite state raises a NonFiniteError naming both. A class that
    #: defines its own ``compute`` declares this itself: without a declaration in its body it is False, so a
    #: subclass that overrides ``compute`` (and may keep state a NaN must never reach) gets its inputs checked
    #: first, and one that keeps its parent's ``compute`` keeps its parent's checking. (An inf input meets zeros
    #: in the law's matrix product, so NumPy may print an "invalid value" RuntimeWarning before the
    #: NonFiniteError that names the input.)
    result_check: ClassVar[bool] = False
    #: this object's reading of :attr:`result_check` (False while the law holds state, e.g. an integral term)
    _checks_result: bool = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "compute" in vars(cls) and "result_check" not in vars(cls):
            cls.result_check = False
        if "_checks_result" not in vars(cls):
            cls._checks_result = cls.result_check

    def __call__(
        self, t: float, q: ArrayLike, qd: ArrayLike, ref: Reference, measurement: Measurement | None = None
    ) -> FloatArray:
        """τ [N·m] for the measured state (q [rad], q̇ [rad/s]) at time t [s] and the reference ``ref``.

        The inputs are checked here, once (named errors), and handed to :meth:`compute`; a non-finite τ from a
        finite state raises :class:`~armctl.errors.NonFiniteError`. ``measurement`` carries the signals the
        controller declares in :attr:`reads` (kept in :attr:`measurement` for ``compute``); a controller that
        reads nothing ignores it."""
        if measurement is not None or self.reads:
            self._take_measurement(measurement)
        if type(ref) is not Reference or len(ref.q) != self.n:  # a Reference's arrays are 1-D
            self.check_reference(ref)  # raises, unless ref is a subclass of the right size
        if type(t) is not float:
            t = scalar(t, "t")
        if not (
            type(q) is np.ndarray
            and type(qd) is np.ndarray
            and q.dtype is FLOAT  # the one float64 dtype NumPy makes (an equal one takes the careful path)
            and qd.dtype is FLOAT
            and q.shape == qd.shape == self._shape
        ):
            q, qd = self._checked(t, q, qd)
        elif self._checks_result:  # NaN or inf in q or q̇ reaches τ: one check, of τ
            try:
                tau = self.compute(t, q, qd, ref)
            except (RuntimeWarning, FloatingPointError):  # NumPy's warnings made errors: name the input
                self._checked(t, q, qd)
                raise  # the inputs were finite: the law's own
            if all_finite(tau) and math.isfinite(t):
                return tau
            self._checked(t, q, qd)  # NonFiniteError if an input is the cause
            self._nonfinite_torque(tau, q, qd)
        elif not math.isfinite(sum(q.tolist()) + sum(qd.tolist()) + t):  # finite unless NaN, inf or overflow
            q, qd = self._checked(t, q, qd)  # raises, unless finite entries overflowed the sum
        tau = self.compute(t, q, qd, ref)
        if type(tau) is np.ndarray and tau.ndim == 1 and math.isfinite(sum(tau.tolist())):
            return tau  # the usual case; anything else (or an overflowing sum): the checks below
        try:
            if all_finite(tau):
                return tau
        except (AttributeError, TypeError):  # not a float array: a user's law may return a list
            return tau
        self._nonfinite_torque(tau, q, qd)

    def _take_measurement(self, measurement: Measurement | None) -> None:
        if measurement is not None and not isinstance(measurement, Measurement):
            raise InvalidParameterError(
                f"measurement must be an armctl.controllers.Measurement, got {type(measurement).__name__}",
                value=measurement,
            )
        missing = self.reads - (measurement.available() if measurement is not None else frozenset())
        if missing:
            raise InvalidParameterError(
                f"{type(self).__name__} reads {sorted(missing)} and was called without: pass "
                f"measurement=Measurement(...) with them (simulate does, given their sources)",
                value=measurement,
            )
        if (
            measurement is not None
            and measurement.tau_applied is not None
            and measurement.tau_applied.shape != self._shape
        ):
            raise ShapeError(
                f"measurement.tau_applied has {measurement.tau_applied.shape[0]} joints, the controller {self.n}",
                value=measurement.tau_applied,
            )
        self.measurement = measurement

    def _nonfinite_torque(self, tau: Any, q: Any, qd: Any) -> NoReturn:
        raise NonFiniteError(
            f"{type(self).__name__} gave a non-finite torque {tau} from a finite state (q = {q}, "
            f"qd = {qd}): its gains, its estimates or the state are too large for floats",
            value=tau,
        )

    def _checked(self, t: float, q: ArrayLike, qd: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """(q, q̇) as finite float (n,) arrays; a named error if t, q or q̇ is not what it should be."""
        if not math.isfinite(t):
            raise NonFiniteError(f"t must be finite, got {t}", value=t)
        return vector(q, self.n, "q"), vector(qd, self.n, "qd")

    def check_reference(self, ref: Reference) -> None:
        """Check a reference against this controller.

        Parameters
        ----------
        ref : Reference
            The reference.

        Raises
        ------
        InvalidParameterError
            ``ref`` is not a :class:`~armctl.Reference`.
        ShapeError
            It has another number of joints than the controller.
        """
        if not isinstance(ref, Reference):
            raise InvalidParameterError(f"ref must be an armctl.Reference, got {type(ref).__name__}", value=ref)
        if ref.q.shape != self._shape:
            raise ShapeError(f"reference has {ref.n} joints, the controller {self.n}", value=ref)

    @abstractmethod
    def compute(self, t: float, q: FloatArray, qd: FloatArray, ref: Reference) -> FloatArray:
        """The control law, on checked inputs.

        In :func:`armctl.simulate`, q and q̇ are read-only views of the run's record: work on new arrays
        (e = q − ref.q) or on a copy.

        Parameters
        ----------
        t : float
            Time [s].
        q, qd : ndarray, shape (n,)
            Measured joint positions and velocities [rad, rad/s or m, m/s], float64, finite.
        ref : Reference
            The reference at t.

        Returns
        -------
        ndarray, shape (n,)
            The joint torques τ [N·m or N].
        """

    def reset(self) -> None:
        """Forget any internal state (integrators, estimates) before a new run."""
        self.last_log = {}
        self.measurement = None
