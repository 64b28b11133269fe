"""`Dynamics`: the checked evaluation of the Lagrange model of an arm, behind one interface and two backends.

    M(q) q̈ + C(q, q̇) q̇ + g(q) = τ − F_v q̇ − F_c sgn(q̇) − J(q)ᵀ h_e

``armctl.Dynamics(model, backend="pinocchio")`` makes the backend's object, looked up in a registry of
backends (:func:`register_backend`):

* ``"pinocchio"`` (:class:`~armctl.dynamics.pinocchio_backend.PinocchioDynamics`): RNEA / CRBA / ABA / Coriolis
  matrix / joint-torque regressor of Pinocchio; rotors as reflected inertia (armature). With ``compile=True``
  (or ``"auto"``, :mod:`armctl.codegen.policy`) its hot terms run as generated C code
  (:mod:`armctl.dynamics.compiled`).
* ``"lagrange"`` (:class:`~armctl.dynamics.lagrange.LagrangeDynamics`): the Lagrange formulation built with
  CasADi from the kinetic and potential energies, including the rotors' gyroscopic coupling.

Every public method checks its inputs (shapes, finiteness, real numbers) and raises an
:class:`~armctl.errors.ArmctlError` subclass naming the value, then evaluates on the backend's
:class:`~armctl.dynamics.kernel.Kernel` (``dyn.kernel``), the unchecked primitives that code with checked
inputs calls directly. Each thread gets a kernel of its own, so one ``Dynamics`` can be shared between threads.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FLOAT, FloatArray, all_finite, vector
from armctl.dynamics.friction_terms import FrictionTerms
from armctl.dynamics.inverse_kinematics import inverse_kinematics
from armctl.dynamics.kernel import Kernel
from armctl.dynamics.regressor import RegressorMethods
from armctl.errors import InvalidParameterError, NonFiniteError, UnknownNameError
from armctl.model.robot import RobotModel

if TYPE_CHECKING:
    from armctl.dynamics.operational_space import DynamicManipulability, OperationalSpaceModel

#: backend name → function of the options giving the class that implements it (see :func:`register_backend`)
_BACKENDS: dict[str, Callable[[dict[str, Any]], type[Dynamics]]] = {}


def register_backend(name: str, resolve: Callable[[dict[str, Any]], type[Dynamics]]) -> None:
    """Make ``armctl.Dynamics(model, backend=name, **options)`` build ``resolve(options)(model, **options)``.

    Parameters
    ----------
    name : str
        The backend's name.
    resolve : callable
        Options (a dict) → the :class:`Dynamics` subclass to instantiate; it may import lazily.
    """
    _BACKENDS[name] = resolve


def backend_names() -> tuple[str, ...]:
    """The names of the registered backends."""
    return tuple(_BACKENDS)


def _pinocchio(options: dict[str, Any]) -> type[Dynamics]:
    from armctl.dynamics.pinocchio_backend import PinocchioDynamics

    return PinocchioDynamics


def _lagrange(options: dict[str, Any]) -> type[Dynamics]:
    from armctl.dynamics.lagrange import LagrangeDynamics

    return LagrangeDynamics


register_backend("pinocchio", _pinocchio)
register_backend("lagrange", _lagrange)
#: The names of the dynamics backends registered at import: ``"pinocchio"`` and ``"lagrange"``.
BACKENDS = backend_names()


class Dynamics(RegressorMethods):
    """The dynamics of ``model`` evaluated by ``backend``.

    Parameters
    ----------
    model : RobotModel
        The arm (immutable).
    backend : {"pinocchio", "lagrange"}
        Which evaluation (see the module).
    **options
        The backend's options: ``compile`` (both: generated C code; False by default, True or ``"auto"``:
        see :mod:`armctl.codegen.policy`), ``cache_dir`` (both: where it is kept), ``rotor_coupling`` (Lagrange).

    Notes
    -----
    One object can be shared between threads: each thread evaluates on a kernel (workspace) of its own.
    """

    #: the backend's name
    backend: str = ""
    #: the keyword options the backend takes
    option_names: tuple[str, ...] = ()
    #: whether the backend's terms run as generated C code (``compile=True``, or ``"auto"`` where it was built)
    compiled: bool = False

    def __new__(cls, model: RobotModel | None = None, backend: str = "pinocchio", **options: Any) -> Dynamics:
        if not isinstance(model, RobotModel):  # before a backend reads it
            raise InvalidParameterError(f"Dynamics needs a RobotModel, got {type(model).__name__}", value=model)
        if cls is Dynamics:
            resolve = _BACKENDS.get(backend) if isinstance(backend, str) else None
            if resolve is None:
                raise UnknownNameError("backend", backend, backend_names())
            return super().__new__(resolve(options))
        return super().__new__(cls)

    def __init__(self, model: RobotModel, backend: str | None = None, **options: Any) -> None:
        if not isinstance(model, RobotModel):
            raise InvalidParameterError(f"Dynamics needs a RobotModel, got {type(model).__name__}", value=model)
        if backend is not None and backend != self.backend:
            raise UnknownNameError("backend", backend, (self.backend,))
        if options:
            own = ", ".join(self.option_names) or "none"
            raise InvalidParameterError(
                f"unknown Dynamics option(s) {sorted(options)} for backend {self.backend!r} (its options: {own})",
                value=dict(options),
            )
        self.model = model
        self.n = model.n
        self._shape = (self.n,)
        self.friction = FrictionTerms(model)
        self._params = model.parameters()
        # this thread's kernel is made now (a backend that cannot be built fails here); the factory holds the
        # model's parts, not this object, so that a Dynamics no one refers to is freed at once
        self._local = _PerThread(self.kernel_factory())
        #: NaN or inf in an input always reaches the result (the kernel's nan_propagates): checking the result of
        #: a call suffices on the path that takes native float64 vectors as they are (see _evaluate)
        self._propagates = self._local.kernel.nan_propagates
        #: every joint revolute: M(q), g(q) and U(q) depend on q through sines and cosines alone, so they are finite
        #: for every finite q and their results need no check (a prismatic position can make them overflow)
        self._trigonometric = all(j.kind != "prismatic" for j in model.joints)

    def kernel_factory(self) -> Callable[[], Kernel]:
        """What makes a new kernel (workspace) of this object's backend, without referring to this object.

        Returns
        -------
        callable
            () → :class:`~armctl.dynamics.kernel.Kernel`: what :attr:`kernel` calls once in each thread.
        """
        raise NotImplementedError(f"{type(self).__name__} has no kernel: make Dynamics objects by armctl.Dynamics")

    def new_kernel(self) -> Kernel:
        """A new kernel (workspace) of this object's backend: what :attr:`kernel` gives each thread.

        Returns
        -------
        Kernel
        """
        return self.kernel_factory()()

    @property
    def kernel(self) -> Kernel:
        """This thread's :class:`~armctl.dynamics.kernel.Kernel`: the unchecked primitives, for code whose
        inputs are checked already (made on first use in each thread)."""
        return self._local.kernel

    def __reduce__(self) -> tuple[Any, ...]:
        # rebuilt from the (immutable) model and options: workspaces and compiled functions are not pickled
        return (_make, (self.model, self.backend, self.options))

    @property
    def options(self) -> dict[str, Any]:
        """The backend options this object was made with."""
        return {}

    def __repr__(self) -> str:
        return f"Dynamics({self.model.name!r}, backend={self.backend!r}, n={self.n})"

    # ---------------------------------------------------------------------------- input checks
    # The public methods are the boundary: they check what they are given and evaluate on the kernel. An input
    # that already is a finite native float64 (n,) vector passes with one test; anything else goes through
    # vector(), which converts it or raises a named error.
    def _vector(self, x: Any, name: str) -> FloatArray:
        """``x`` as a finite float (n,) array: ``x`` itself if it is one, else converted or a named error."""
        if type(x) is np.ndarray and x.dtype == FLOAT and x.shape == self._shape and math.isfinite(sum(x.tolist())):
            return x
        return vector(x, self.n, name)

    def _of_q(self, fn: Callable[[FloatArray], Any], q: Any) -> Any:
        """``fn(q)`` (a kernel primitive of q alone, which refuses a wrong length) on a checked q, its result
        checked where it can overflow (a prismatic joint's huge position)."""
        if type(q) is np.ndarray and q.dtype is FLOAT and q.ndim == 1 and math.isfinite(sum(q.tolist())):
            if self._trigonometric:
                try:
                    return fn(q)
                except ValueError:  # a wrong length: vector() names it
                    q = vector(q, self.n, "q")
        else:
            q = vector(q, self.n, "q")
        try:
            out = fn(q)
        except ValueError:  # a wrong length: vector() names it
            q = vector(q, self.n, "q")
            out = fn(q)
        if not all_finite(np.asarray(out)) and not np.isfinite(out).all():
            raise self._overflow(np.asarray(out), ("q",), (q,), q)
        return out

    def _evaluate(self, fn: Callable[..., Any], names: tuple[str, ...], *args: Any) -> Any:
        """``fn(*args)`` (a kernel primitive) on checked inputs, its result checked: a non-finite result from
        finite inputs is an overflow (named) or a mass matrix that is not positive definite (named).

        On a kernel where NaN propagates, native float64 vectors are passed as they are and only the result is
        checked (one check instead of one per input); the inputs are checked when it is not finite."""
        if self._propagates and _same_shape(args, self._shape):
            try:
                out = fn(*args)
            except Exception:  # a length the kernel refuses, a singular M: the careful path names it
                out = None
            if out is not None and all_finite(out):
                return out
        args = tuple(self._vector(a, nm) for a, nm in zip(args, names, strict=True))
        try:
            out = fn(*args)
        except np.linalg.LinAlgError:  # the Lagrange backend's forward dynamics: M(q) singular
            raise self._local.kernel.nonfinite_error(args[0], None) from None
        if np.isfinite(out).all():
            return out
        raise self._overflow(out, names, args, args[0])

    def _overflow(self, out: Any, names: tuple[str, ...], args: tuple[FloatArray, ...], q: FloatArray) -> Exception:
        """The error for a non-finite result ``out`` at configuration q from finite inputs ``args``: a mass matrix
        that is not positive definite at q, or the largest input named."""
        error = self._local.kernel.nonfinite_error(q, out)
        if not isinstance(error, NonFiniteError):  # a mass matrix that is not positive definite
            return error
        big = max(range(len(args)), key=lambda i: float(np.abs(args[i]).max(initial=0.0)))
        x = args[big]
        j = int(np.argmax(np.abs(x)))
        return NonFiniteError(
            f"the result overflowed (is not finite) although every input is finite: {names[big]}[{j}] = "
            f"{x[j]:.3g} is too large (quadratic terms of it exceed the range of floats, ~1.8e308); check its "
            "units and scale",
            value=x,
        )

    def check_mass_matrix(self, q: ArrayLike) -> None:
        """Check that M(q) is positive definite.

        Parameters
        ----------
        q : array_like, shape (n,)
            Joint positions [rad or m].

        Raises
        ------
        InvalidParameterError
            M(q) is not positive definite (naming the joint of least inertia and what to give it).
        """
        qv = self._vector(q, "q")
        mass = self.mass_matrix(qv)  # finite, or a named overflow
        try:
            np.linalg.cholesky(mass)
        except np.linalg.LinAlgError:
            raise self._local.kernel.nonfinite_error(qv, None) from None

    # ------------------------------------------------------------------------------- public API
    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """M(q) (n×n, symmetric positive definite) [kg·m² / kg].

        Parameters
        ----------
        q : (n,) array_like
            Joint positions [rad or m].

        Returns
        -------
        ndarray, shape (n, n)
            M(q) [kg·m² or kg].
        """
        try:  # the usual call, inlined (M is finite, see _trigonometric): a native float64 vector of finite
            # entries (the sum of a matrix's or a scalar's tolist() raises TypeError), of the length the kernel takes
            if self._trigonometric and q.dtype is FLOAT and math.isfinite(sum(q.tolist())):  # type: ignore[union-attr]
                return self._local.kernel.mass(q)
        except (AttributeError, TypeError, ValueError):  # not an array; a matrix; a wrong length: _of_q names it
            pass
        return self._of_q(self._local.kernel.mass, q)

    def coriolis_matrix(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """C(q, q̇) (n×n) from the Christoffel symbols, c_ij = Σ_k ½(∂M_ij/∂q_k + ∂M_ik/∂q_j − ∂M_jk/∂q_i) q̇_k,
        so that Ṁ − 2C is skew-symmetric.

        Parameters
        ----------
        q, qd : (n,) array_like
            Joint positions [rad or m] and velocities [rad/s or m/s].

        Returns
        -------
        ndarray, shape (n, n)
            C(q, q̇) [kg·m²/s or kg/s].
        """
        return self._evaluate(self._local.kernel.coriolis, ("q", "qd"), q, qd)

    def gravity_torque(self, q: ArrayLike) -> FloatArray:
        """g(q) = ∂U/∂q [N·m or N].

        Parameters
        ----------
        q : (n,) array_like
            Joint positions [rad or m].

        Returns
        -------
        ndarray, shape (n,)
            g(q) [N·m or N].
        """
        try:  # the usual call, inlined (g is finite, see _trigonometric): a native float64 vector of finite
            # entries (the sum of a matrix's or a scalar's tolist() raises TypeError), of the length the kernel takes
            if self._trigonometric and q.dtype is FLOAT and math.isfinite(sum(q.tolist())):  # type: ignore[union-attr]
                return self._local.kernel.gravity(q)
        except (AttributeError, TypeError, ValueError):  # not an array; a matrix; a wrong length: _of_q names it
            pass
        return self._of_q(self._local.kernel.gravity, q)

    def friction_torque(self, qd: ArrayLike) -> FloatArray:
        """τ_f = F_v q̇ + F_c⁺ (q̇ > 0) or − F_c⁻ (q̇ < 0) [N·m or N]; zero Coulomb part at rest (the simulator
        handles stiction).

        Parameters
        ----------
        qd : (n,) array_like
            Joint velocities [rad/s or m/s].

        Returns
        -------
        ndarray, shape (n,)
            τ_f [N·m or N].
        """
        return self._evaluate(self.friction.torque, ("qd",), qd)

    def inverse_dynamics(
        self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, wrench: ArrayLike | None = None
    ) -> FloatArray:
        """τ = M q̈ + C q̇ + g + τ_f(q̇) + J(q)ᵀ h_e [N·m or N].

        Parameters
        ----------
        q, qd, qdd : (n,) array_like
            Joint positions, velocities and accelerations [rad, rad/s, rad/s²; m, m/s, m/s² for prismatic].
        wrench : (6,) array_like, optional
            h_e = [f; μ] at the tool frame in world-aligned axes [N, N·m]: the wrench the arm exerts on the
            environment.

        Returns
        -------
        ndarray, shape (n,)
            τ [N·m or N].
        """
        k = self._local.kernel
        if (
            wrench is None
            and self._propagates
            and type(q) is type(qd) is type(qdd) is np.ndarray
            and q.dtype is qd.dtype is qdd.dtype is FLOAT
            and q.ndim == qd.ndim == qdd.ndim == 1
        ):  # (float_vectors inlined)
            try:  # rnea refuses a wrong length: then the careful path names it
                tau = k.rnea(q, qd, qdd)
            except ValueError:
                tau = None
            if tau is not None:
                if self.friction.any:
                    tau += self.friction.torque(cast(FloatArray, qd))  # (checked above: float vectors)
                if math.isfinite(sum(tau.tolist())):  # (every entry: an overflow can show in any one)
                    return tau
        tau = self._evaluate(k.inverse_dynamics, ("q", "qd", "qdd"), q, qd, qdd)
        if wrench is not None:
            qv, h = self._vector(q, "q"), vector(wrench, 6, "wrench")
            with np.errstate(over="ignore", invalid="ignore"):
                tau = tau + k.jacobian(qv, None).T @ h
            if not np.isfinite(tau).all():
                raise self._overflow(tau, ("wrench",), (h,), qv)
        return tau

    def forward_dynamics(
        self, q: ArrayLike, qd: ArrayLike, tau: ArrayLike, wrench: ArrayLike | None = None
    ) -> FloatArray:
        """q̈ = M⁻¹ (τ − C q̇ − g − τ_f(q̇) − Jᵀ h_e) [rad/s² or m/s²]. Coulomb friction here is the kinetic one
        (sgn q̇, zero at rest); stick–slip is the simulator's business.

        Parameters
        ----------
        q, qd : (n,) array_like
            Joint positions [rad or m] and velocities [rad/s or m/s].
        tau : (n,) array_like
            Joint torques [N·m or N].
        wrench : (6,) array_like, optional
            h_e at the tool frame (see :meth:`inverse_dynamics`).

        Returns
        -------
        ndarray, shape (n,)
            q̈ [rad/s² or m/s²].
        """
        k = self._local.kernel
        if not self.friction.any and wrench is None:
            return self._evaluate(k.aba, ("q", "qd", "tau"), q, qd, tau)
        q, qd, tau = (self._vector(x, nm) for x, nm in ((q, "q"), (qd, "qd"), (tau, "tau")))
        with np.errstate(over="ignore", invalid="ignore"):
            net = tau - self.friction.torque(qd) if self.friction.any else tau
            if wrench is not None:
                h = vector(wrench, 6, "wrench")
                net = net - k.jacobian(q, None).T @ h
        names, args = (("tau", "qd", "wrench"), (tau, qd, h)) if wrench is not None else (("tau", "qd"), (tau, qd))
        if not np.isfinite(net).all():  # τ − τ_f − Jᵀh beyond the range of floats: name the largest input
            raise self._overflow(net, names, args, q)
        try:
            return self._evaluate(k.aba, ("q", "qd", "tau"), q, qd, net)
        except NonFiniteError:  # q̈ overflowed from finite inputs: name the largest of the caller's, not the sum
            raise self._overflow(None, ("q", *names), (q, *args), q) from None

    def jacobian(self, q: ArrayLike, frame: str | None = None) -> FloatArray:
        """Geometric Jacobian (6×n) of ``frame`` at its origin, world-aligned axes, rows [linear; angular].

        Parameters
        ----------
        q : (n,) array_like
            Joint positions [rad or m].
        frame : str, optional
            A frame of the model (default: the tool frame).

        Returns
        -------
        ndarray, shape (6, n)
            J, rows [linear; angular]: J q̇ = [v [m/s]; ω [rad/s]] of the frame.

        Raises
        ------
        UnknownNameError
            ``frame`` is not a frame of the model (the error lists them).
        """
        if frame is not None:
            self.model.frame(frame)
        return self._local.kernel.jacobian(self._vector(q, "q"), frame)

    def frame_pose(self, q: ArrayLike, frame: str | None = None) -> FloatArray:
        """4×4 homogeneous pose of ``frame`` (default: the tool frame) in the world [m].

        Parameters
        ----------
        q, frame
            As for :meth:`jacobian`.

        Returns
        -------
        ndarray, shape (4, 4)
            The homogeneous pose [m].

        Raises
        ------
        UnknownNameError
            As for :meth:`jacobian`.
        """
        if frame is not None:
            self.model.frame(frame)
        return self._local.kernel.frame_pose(self._vector(q, "q"), frame)

    # dyn.inverse_kinematics(target_pose, ...) is the function itself, with this object as its ``dyn``
    inverse_kinematics = inverse_kinematics

    def kinetic_energy(self, q: ArrayLike, qd: ArrayLike) -> float:
        """T = ½ q̇ᵀ M q̇ [J] (links and rotors).

        Parameters
        ----------
        q, qd : (n,) array_like
            Joint positions [rad or m] and velocities [rad/s or m/s].

        Returns
        -------
        float
            T [J].
        """
        q, qd = self._vector(q, "q"), self._vector(qd, "qd")  # checked: M(q) does not read every entry of q
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow is named below
            energy = self._local.kernel.kinetic(q, qd)
        if not math.isfinite(energy):
            raise self._overflow(np.array(energy), ("q", "qd"), (q, qd), q)
        return energy

    def potential_energy(self, q: ArrayLike) -> float:
        """U = −Σ m_i g₀ᵀ p_Ci [J] over the model's moving links, zero with every centre of mass at the world
        origin's height. Bodies fixed to the world are not counted, a constant: a URDF's base link, links a
        ``reduced(lock=...)`` merged into the world (MuJoCo's energy, which counts them, differs by that).

        Parameters
        ----------
        q : (n,) array_like
            Joint positions [rad or m].

        Returns
        -------
        float
            U [J].
        """
        return float(self._of_q(self._local.kernel.potential, q))

    def parameters(self) -> FloatArray:
        """π of the model these dynamics evaluate (see :meth:`RobotModel.parameters`).

        Returns
        -------
        ndarray, shape (13 n,)
            π.
        """
        return self._params

    def operational_space_model(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        frame: str | None = None,
        rows: str | Sequence[int | str] = "pose",
        singular_tolerance: float = 1e-6,
    ) -> OperationalSpaceModel:
        """The operational-space model Λ ẍ + μ + p = F of ``frame`` at (q, q̇) (see
        :func:`armctl.dynamics.operational_space.operational_space_model`).

        Parameters
        ----------
        q, qd : array_like, shape (n,)
            Joint positions and velocities [rad, rad/s or m, m/s].
        frame : str, optional
            The frame (None: the tool frame).
        rows : str or sequence of int or str, optional
            The task rows: ``"pose"`` (6), ``"position"`` (3), or axes such as ``"xz"``.
        singular_tolerance : float, optional
            The smallest σ_min/σ_max of J accepted.

        Returns
        -------
        OperationalSpaceModel
            ``.Lambda`` = (J M⁻¹ Jᵀ)⁻¹ [kg or kg·m²], ``.mu``, ``.p`` [N, N·m], ``.Jbar`` = M⁻¹ Jᵀ Λ.

        Raises
        ------
        SingularConfigurationError
            J's σ_min/σ_max < ``singular_tolerance``.
        """
        from armctl.dynamics.operational_space import operational_space_model

        return operational_space_model(self, q, qd, frame, rows, singular_tolerance)

    def dynamic_manipulability(
        self,
        q: ArrayLike,
        frame: str | None = None,
        rows: str | Sequence[int | str] = "pose",
        torque_scale: ArrayLike | str | None = None,
    ) -> DynamicManipulability:
        """The dynamic manipulability ellipsoid of ``frame`` at q (Yoshikawa; see
        :func:`armctl.dynamics.operational_space.dynamic_manipulability`).

        Parameters
        ----------
        q : array_like, shape (n,)
            Joint positions [rad or m].
        frame : str, optional
            The frame (None: the tool frame).
        rows : str or sequence of int or str, optional
            The task rows, as for :meth:`operational_space_model`.
        torque_scale : array_like or str, optional
            None: unit-norm torques (as Siciliano); ``"limits"``: normalised by the joints' effort limits; or
            positive scales (n,) [N·m].

        Returns
        -------
        DynamicManipulability
            ``.axes``, ``.lengths``, ``.measure``.
        """
        from armctl.dynamics.operational_space import dynamic_manipulability

        return dynamic_manipulability(self, q, frame, rows, torque_scale)


class _PerThread(threading.local):
    """Each thread's kernel of one :class:`Dynamics`, made by ``factory`` on the thread's first use."""

    def __init__(self, factory: Callable[[], Kernel]) -> None:
        self.kernel = factory()


def _same_shape(args: tuple[Any, ...], shape: tuple[int]) -> bool:
    """True if every one of ``args`` is a native float64 ndarray of ``shape`` (finite or not)."""
    for x in args:
        if type(x) is not np.ndarray or x.dtype != FLOAT or x.shape != shape:
            return False
    return True


def _make(model: RobotModel, backend: str, options: dict[str, Any]) -> Dynamics:
    return Dynamics(model, backend=backend, **options)
