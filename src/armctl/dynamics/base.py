"""`Dynamics`: evaluation of the Lagrange model of an arm, behind one interface and two backends.

    M(q) q̈ + C(q, q̇) q̇ + g(q) = τ − F_v q̇ − F_c sgn(q̇) − J(q)ᵀ h_e

``armctl.Dynamics(model, backend="pinocchio")`` returns the backend's object:

* ``"pinocchio"`` (:class:`~armctl.dynamics.pinocchio_backend.PinocchioDynamics`): RNEA / CRBA / ABA /
  Coriolis matrix / joint-torque regressor of Pinocchio; rotors as reflected inertia (armature).
* ``"lagrange"`` (:class:`~armctl.dynamics.lagrange.LagrangeDynamics`): the Lagrange formulation built with
  CasADi from the kinetic and potential energies, including the rotors' gyroscopic coupling.

A backend implements a handful of private primitives (rigid-body terms, Jacobian, energies, regressor of the
rigid-body part); this base adds input checks, friction and the end-effector wrench, and
:class:`~armctl.dynamics.regressor.RegressorMethods` the regressors and the base (identifiable) parameters, so
both backends expose the same API. Every method checks shapes and finiteness and raises an
:class:`~armctl.errors.ArmctlError` subclass naming the value.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FLOAT as _FLOAT
from armctl._checks import FloatArray, boolean, vector
from armctl.dynamics.regressor import RegressorMethods
from armctl.errors import ArmctlError, InvalidParameterError, NonFiniteError, UnknownNameError
from armctl.model.robot import PARAMS_PER_JOINT, RobotModel

if TYPE_CHECKING:
    from armctl.dynamics.operational_space import DynamicManipulability, OperationalSpaceModel

BACKENDS = ("pinocchio", "lagrange")
#: the keyword options of the Lagrange backend (the Pinocchio backend takes none)
_LAGRANGE_OPTIONS = ("rotor_coupling", "compile", "cache_dir")


class Dynamics(RegressorMethods, ABC):
    """The dynamics of ``model`` evaluated by ``backend`` (``"pinocchio"`` or ``"lagrange"``).

    Calling ``Dynamics(model, backend=...)`` constructs the backend's subclass. Keyword options go to the
    backend: ``compile`` (both: generated C code, see :mod:`armctl.dynamics.compiled` for the Pinocchio
    backend's), ``cache_dir`` (both: where it is kept), ``rotor_coupling`` (Lagrange). A ``RobotModel`` is immutable,
    so a ``Dynamics`` object can be shared, but its workspace is not thread-safe: give each thread its own.
    """

    backend: str = ""
    #: the keyword options this backend takes
    _option_names: tuple[str, ...] = ()
    #: True if a NaN or inf in any entry of any input of the rigid-body primitives always reaches their result
    #: (numerical algorithms such as Pinocchio's, where NaN·0 = NaN); then the fast paths check the result
    #: instead of the inputs. Inverse dynamics checks τ₁ alone: the models are serial chains, and in the RNEA
    #: the force on the first joint sums every link's, so any non-finite input reaches it. Not so for the
    #: Lagrange backend: CasADi simplifies its expressions, and a frictionless pendulum's τ does not depend
    #: on q̇ at all.
    _nan_propagates: bool = False
    #: A view of the regressor workspace that NaN or inf in any input of the (passivity) regressor reaches
    #: (only where ``_nan_propagates``; which entries is the backend's business: Pinocchio's Y[0, the last
    #: link's ten columns] by the argument above, the compiled variant's Y[0, 10] by its carrier); None: the
    #: fast paths check the inputs.
    _regressor_probe: FloatArray | None = None

    def __new__(cls, model: RobotModel | None = None, backend: str = "pinocchio", **options: Any) -> Dynamics:
        if cls is Dynamics:
            if backend == "pinocchio":
                if boolean(options.get("compile", False), "compile"):
                    from armctl.dynamics.compiled import CompiledDynamics as sub
                else:
                    from armctl.dynamics.pinocchio_backend import PinocchioDynamics as sub
            elif backend == "lagrange":
                from armctl.dynamics.lagrange import LagrangeDynamics as sub
            else:
                raise UnknownNameError("backend", backend, BACKENDS)
            return super().__new__(sub)
        return super().__new__(cls)

    def __init__(self, model: RobotModel, backend: str | None = None, **options: Any) -> None:
        if not isinstance(model, RobotModel):
            raise InvalidParameterError(f"Dynamics needs a RobotModel, got {type(model).__name__}", value=model)
        if backend is not None and backend != self.backend:
            raise UnknownNameError("backend", backend, (self.backend,))
        if options:
            own = ", ".join(self._option_names) or "none"
            other = "" if self.backend == "lagrange" else f"; backend='lagrange' takes {', '.join(_LAGRANGE_OPTIONS)}"
            raise InvalidParameterError(
                f"unknown Dynamics option(s) {sorted(options)} for backend {self.backend!r} "
                f"(its options: {own}){other}",
                value=dict(options),
            )
        self.model = model
        self.n = model.n
        self._shape = (self.n,)
        self._zeros = np.zeros(self.n)
        self._halves = np.full(self.n, 0.5)
        fr = [j.friction for j in model.joints]
        self._fv = np.array([f.viscous for f in fr])
        fc_pos = np.array([f.coulomb for f in fr])
        fc_neg = np.array([f.coulomb_neg for f in fr])
        self._fc_mean = 0.5 * (fc_pos + fc_neg)
        self._fc_offset = 0.5 * (fc_pos - fc_neg)
        self._has_viscous = bool(self._fv.any())
        self._has_coulomb = bool(self._fc_mean.any())
        self._has_asymmetry = bool(self._fc_offset.any())
        # ρ = δ / F_c,mean (|ρ| ≤ 1 as F_c± ≥ 0; 0 without Coulomb friction): the regressor's Coulomb column
        # is sgn q̇ (1 + ρ sgn q̇), so that F_c,mean times it is F_c⁺ or −F_c⁻ (see _coulomb_column)
        self._fc_ratio = np.divide(self._fc_offset, self._fc_mean, out=np.zeros(self.n), where=self._fc_mean > 0)
        self._has_friction = self._has_viscous or self._has_coulomb
        # τ_f = [diag F_v, diag F_c,mean (, diag F_c,offset)]·[q̇; sgn q̇ (; |sgn q̇|)]: one product where the
        # term by term form takes five to seven array operations
        blocks = [np.diag(self._fv), np.diag(self._fc_mean)] + (
            [np.diag(self._fc_offset)] if self._has_asymmetry else []
        )
        self._friction_map = np.hstack(blocks)
        self._params = model.parameters()
        # flat indices of Y[i, 13 i + c] for the rotor (c = 10), viscous (11) and Coulomb (12) columns,
        # in a C-ordered (n, 13n) array
        k, rows = PARAMS_PER_JOINT, np.arange(self.n)
        self._diag_idx = np.concatenate([rows * k * self.n + k * rows + c for c in (10, 11, 12)])

    def __reduce__(self) -> tuple[Any, ...]:
        # rebuilt from the (immutable) model and options: workspaces and compiled functions are not pickled
        return (_make, (self.model, self.backend, self.options))

    @property
    def options(self) -> dict[str, Any]:
        """The backend options this object was made with."""
        return {}

    def __repr__(self) -> str:
        return f"Dynamics({self.model.name!r}, backend={self.backend!r}, n={self.n})"

    # ------------------------------------------------------------------------ backend primitives
    @abstractmethod
    def _mass(self, q: FloatArray) -> FloatArray: ...

    @abstractmethod
    def _coriolis(self, q: FloatArray, qd: FloatArray) -> FloatArray: ...

    @abstractmethod
    def _gravity(self, q: FloatArray) -> FloatArray: ...

    @abstractmethod
    def _rigid_torque(self, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> FloatArray:
        """M q̈ + C q̇ + g (rotors included, no friction)."""

    @abstractmethod
    def _rigid_regressor(
        self, q: FloatArray, qd: FloatArray, qdd: FloatArray, friction: tuple[FloatArray, FloatArray] | None = None
    ) -> FloatArray:
        """n × 13n regressor of M q̈ + C q̇ + g; the friction columns hold ``friction`` = (v, w): the viscous
        column's diagonal v and the Coulomb column's :meth:`_coulomb_column` of w (sgn w for a symmetric
        friction), or zeros."""

    @abstractmethod
    def _jacobian(self, q: FloatArray, frame: str | None) -> FloatArray: ...

    @abstractmethod
    def _kinetic(self, q: FloatArray, qd: FloatArray) -> float: ...

    @abstractmethod
    def _potential(self, q: FloatArray) -> float: ...

    @abstractmethod
    def frame_pose(self, q: ArrayLike, frame: str | None = None) -> FloatArray:
        """4×4 pose of ``frame`` (default: the tool frame) in the world."""

    def _forward(self, q: FloatArray, qd: FloatArray, tau_net: FloatArray) -> FloatArray:
        """q̈ = M⁻¹ (τ_net − C q̇ − g); backends may do better."""
        if tau_net.shape != self._shape:  # primitives refuse wrong lengths (see the public API's fast paths)
            raise ValueError(f"tau_net has shape {tau_net.shape}, not {self._shape}")
        return np.linalg.solve(self._mass(q), tau_net - self._rigid_torque(q, qd, np.zeros(self.n)))

    # ------------------------------------------------------------------------------- public API
    # Hot paths are written EAFP: the backend is called with what the caller passed; only if it refuses
    # (wrong type or size) are the inputs converted and checked, so that the error names the value. Where NaN
    # or inf in an input always reaches the result (``_nan_propagates``), only the result is checked; the slow
    # path then names the input. Otherwise the inputs are checked first.
    # So every backend primitive must raise on an input of the wrong length (Pinocchio does; the Lagrange
    # backend's evaluators check), and the fast paths only rule out what a primitive would take silently
    # (an (n, 1) column). tests/dynamics/test_input_checks.py tries every entry and shape on both backends.
    def _q(self, q: ArrayLike, name: str = "q") -> FloatArray:
        return vector(q, self.n, name)

    def _finite(self, x: Any, name: str) -> FloatArray:
        """``x`` if it is already a finite float (n,) array (the fast case), else checked by :func:`vector`."""
        try:
            if x.dtype is _FLOAT and x.shape == self._shape and math.isfinite(sum(x.tolist())):
                return x  # type: ignore[no-any-return]
        except (AttributeError, TypeError):  # not an array; a masked one (tolist gives None where masked)
            pass
        return vector(x, self.n, name)

    def _call(self, fn: Any, names: tuple[str, ...], *args: Any) -> FloatArray:
        """``fn(*args)`` → an (n,) result, on the fast path; if ``fn`` refuses the inputs or the result is not
        finite, check every input (raising a named error) and retry."""
        if self._nan_propagates:
            try:
                for a in args:  # eigenpy would take an (n, 1) column too; Pinocchio checks the lengths but
                    if a.ndim != 1 or a.dtype is not _FLOAT:  # reads a big-endian array's bytes as native
                        raise TypeError
                out = fn(*args)
                if math.isfinite(sum(out.tolist())):  # NaN/inf anywhere in the inputs shows up here
                    return out  # type: ignore[no-any-return]
            except Exception:
                pass
        return self._checked_call(fn, names, *args)

    def _checked_call(self, fn: Any, names: tuple[str, ...], *args: Any) -> FloatArray:
        """``fn(*args)`` on checked inputs (named errors), its result checked: the slow path of :meth:`_call`."""
        args = self._inputs(names, *args)
        try:
            out = fn(*args)
        except np.linalg.LinAlgError:  # the Lagrange backend's forward dynamics: M(q) singular
            raise self._nonfinite_result(args[0], None) from None
        if not np.isfinite(out).all():
            raise self._nonfinite_result(args[0], out)
        return out  # type: ignore[no-any-return]

    def _nonfinite_result(self, q: FloatArray, out: FloatArray | None) -> ArmctlError:
        """The error for a result that is not finite (or could not be computed) although every input is: a
        mass matrix that is not positive definite at q is named as such, with the joint of least inertia."""
        m = self._mass(q)
        try:
            np.linalg.cholesky(m)
        except np.linalg.LinAlgError:
            d = np.diag(m)
            k = int(np.argmin(d))
            name = self.model.joints[k].name
            return InvalidParameterError(
                f"the mass matrix of {self.model.name!r} is not positive definite at q = {q} (smallest "
                f"eigenvalue {np.linalg.eigvalsh(m).min():.3g}); joint {name!r} moves the least inertia (M_kk = "
                f"{d[k]:.3g}): give the links it carries mass and inertia, or its motor a rotor inertia",
                value=q,
            )
        return NonFiniteError(f"result is not finite although every input is: {out!r}", value=out)

    def _inputs(self, names: tuple[str, ...], *args: Any) -> tuple[FloatArray, ...]:
        """The inputs as finite (n,) arrays: one cheap test when they already are, else named errors."""
        try:
            total = 0.0
            for a in args:
                if a.shape != self._shape or a.dtype is not _FLOAT:  # e.g. an object array: converted below
                    raise TypeError
                total += sum(a.tolist())
            if math.isfinite(total):
                return args
        except (AttributeError, TypeError):
            pass
        return tuple(vector(a, self.n, nm) for a, nm in zip(args, names, strict=True))

    def _checked4(self, a: Any, b: Any, c: Any, d: Any) -> bool:
        """True if the four inputs are finite float (n,) arrays already (the fast case of :meth:`_inputs`)."""
        try:  # each sum raises TypeError unless its array is 1-D with real entries; len then fixes the length;
            # native float64 only (Pinocchio reads a big-endian array's bytes as native; float32 would be
            # combined in single precision)
            return (
                a.dtype is b.dtype is c.dtype is d.dtype is _FLOAT  # type: ignore[no-any-return]
                and math.isfinite(sum(a.tolist()) + sum(b.tolist()) + sum(c.tolist()) + sum(d.tolist()))
                and len(a) == len(b) == len(c) == len(d) == self.n
            )
        except (AttributeError, TypeError, OverflowError):  # not arrays, entries not real numbers, huge ints
            return False

    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """M(q) (n×n, symmetric positive definite) [kg·m² / kg]."""
        try:  # the fast path of _finite, inlined: this is called every control step. The sum of q.tolist()
            # raises TypeError unless q is 1-D with real entries (an (n, 1) column gives a list of lists), and
            # the backend checks the length: no shape test needed. The dtype must be native float64: Pinocchio
            # reads a big-endian array's bytes as if they were native
            if q.dtype is _FLOAT and math.isfinite(sum(q.tolist())):  # type: ignore[union-attr]
                return self._mass(q)
        except Exception:  # not an array; complex entries; a length or an object array the backend refuses
            pass
        return self._mass(vector(q, self.n, "q"))

    def coriolis_matrix(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """C(q, q̇) from the Christoffel symbols, c_ij = Σ_k ½(∂M_ij/∂q_k + ∂M_ik/∂q_j − ∂M_jk/∂q_i) q̇_k,
        so that Ṁ − 2C is skew-symmetric."""
        return self._coriolis(self._finite(q, "q"), self._finite(qd, "qd"))

    def _pd_gravity_law(self, feedback: FloatArray) -> Callable[..., FloatArray] | None:
        """The law τ = g(q) + F·[q_d; q̇_d; q; q̇] as one fused function (q, q̇, q_d, q̇_d) → τ where the backend
        has one (``compile=True``), else None: then :class:`~armctl.controllers.PDGravity` composes it."""
        return None

    def gravity_torque(self, q: ArrayLike) -> FloatArray:
        """g(q) = ∂U/∂q [N·m]."""
        try:  # inlined fast path, as in mass_matrix
            if q.dtype is _FLOAT and math.isfinite(sum(q.tolist())):  # type: ignore[union-attr]
                return self._gravity(q)
        except Exception:  # as in mass_matrix
            pass
        return self._gravity(vector(q, self.n, "q"))

    def friction_torque(self, qd: ArrayLike) -> FloatArray:
        """τ_f = F_v q̇ + F_c⁺ (q̇ > 0) or − F_c⁻ (q̇ < 0); zero Coulomb part at rest (the simulator handles
        stiction)."""
        return self._friction(self._finite(qd, "qd"))

    def _friction(self, qd: FloatArray, viscous_at: FloatArray | None = None) -> FloatArray:
        """τ_f(q̇), with the viscous part taken at ``viscous_at`` instead of q̇ if given (the Slotine–Li law
        takes it at q̇_r)."""
        v = qd if viscous_at is None else viscous_at
        if self._has_coulomb:  # [F_v, F_c,mean, F_c,offset]·[v; sgn q̇; |sgn q̇|]: one product (see __init__)
            sign = np.sign(qd)
            if self._has_asymmetry:
                return self._friction_map.dot(np.concatenate((v, sign, np.abs(sign))))  # type: ignore[no-any-return]
            return self._friction_map.dot(np.concatenate((v, sign)))  # type: ignore[no-any-return]
        return self._fv * v

    def inverse_dynamics(
        self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, wrench: ArrayLike | None = None
    ) -> FloatArray:
        """τ = M q̈ + C q̇ + g + τ_f(q̇) + J(q)ᵀ h_e, with ``wrench`` h_e = [f; μ] at the tool frame in
        world-aligned axes (the force the arm exerts on the environment)."""
        if wrench is None:
            try:  # _call's fast path, inlined: this is called every control step
                # ndim: an int, cheaper than comparing shape tuples; Pinocchio checks the lengths
                if (
                    self._nan_propagates
                    and q.ndim == qd.ndim == qdd.ndim == 1  # type: ignore[union-attr]
                    and q.dtype is qd.dtype is qdd.dtype is _FLOAT
                ):  # type: ignore[union-attr]  (as in _call)
                    out = self._rigid_torque(q, qd, qdd)
                    if math.isfinite(out.item(0)):  # NaN/inf in any input shows up in τ₁ (_nan_propagates)
                        if not self._has_friction:
                            return out  # type: ignore[no-any-return]
                        if q.__class__ is qd.__class__ is qdd.__class__ is np.ndarray:  # (masked: to the checks)
                            out += self._friction(qd)  # type: ignore[arg-type]  (finite, length n: Pinocchio took it)
                            return out  # type: ignore[no-any-return]
            except Exception:
                pass
        q, qd, qdd = self._inputs(("q", "qd", "qdd"), q, qd, qdd)  # the checked path (as _checked_call's)
        tau = self._rigid_torque(q, qd, qdd)
        if self._has_friction:
            tau += self._friction(qd)
        if wrench is not None:
            tau += self._jacobian(q, None).T @ vector(wrench, 6, "wrench")
        if not np.isfinite(tau).all():  # finite inputs too large for floats (as _checked_call says)
            raise self._nonfinite_result(q, tau)
        return tau

    def forward_dynamics(
        self, q: ArrayLike, qd: ArrayLike, tau: ArrayLike, wrench: ArrayLike | None = None
    ) -> FloatArray:
        """q̈ = M⁻¹ (τ − C q̇ − g − τ_f(q̇) − Jᵀ h_e). Coulomb friction here is the kinetic one
        (sgn q̇, zero at rest); stick–slip is the simulator's business."""
        if self._has_friction or wrench is not None:
            q, qd, tau = self._inputs(("q", "qd", "tau"), q, qd, tau)
            if self._has_friction:
                tau = tau - self._friction(qd)
            if wrench is not None:
                tau = tau - self._jacobian(q, None).T @ vector(wrench, 6, "wrench")
            return self._checked_call(self._forward, ("q", "qd", "tau"), q, qd, tau)
        return self._call(self._forward, ("q", "qd", "tau"), q, qd, tau)

    def jacobian(self, q: ArrayLike, frame: str | None = None) -> FloatArray:
        """Geometric Jacobian (6×n) of ``frame`` (default: the tool frame) at its origin, world-aligned axes,
        rows [linear; angular]."""
        if frame is not None:
            self.model.frame(frame)  # raises UnknownNameError listing the valid names
        return self._jacobian(self._q(q), frame)

    def kinetic_energy(self, q: ArrayLike, qd: ArrayLike) -> float:
        """T = ½ q̇ᵀ M(q) q̇ [J] (links and rotors)."""
        return self._kinetic(self._q(q), self._q(qd, "qd"))

    def potential_energy(self, q: ArrayLike) -> float:
        """U = −Σ m_i g₀ᵀ p_Ci [J] over the model's moving links, zero with every centre of mass at the world
        origin's height. Bodies fixed to the world are not counted, a constant: a URDF's base link, links a
        ``reduced(lock=...)`` merged into the world (MuJoCo's energy, which counts them, differs by that)."""
        return self._potential(self._q(q))

    def parameters(self) -> FloatArray:
        """π of the model these dynamics evaluate (see :meth:`RobotModel.parameters`)."""
        return self._params

    def operational_space_model(
        self,
        q: ArrayLike,
        qd: ArrayLike,
        frame: str | None = None,
        rows: str | Sequence[int | str] = "pose",
        singular_tolerance: float = 1e-6,
    ) -> OperationalSpaceModel:
        """Λ ẍ + μ + p = F of ``frame`` (default: the tool frame) at (q, q̇): ``.Lambda`` = (J M⁻¹ Jᵀ)⁻¹,
        ``.mu``, ``.p``, ``.Jbar`` = M⁻¹ Jᵀ Λ, along ``rows`` ("pose", "position", or axes such as "xz"); a
        :class:`~armctl.errors.SingularConfigurationError` where J's σ_min/σ_max < ``singular_tolerance``.
        See :func:`armctl.dynamics.operational_space.operational_space_model`."""
        from armctl.dynamics.operational_space import operational_space_model

        return operational_space_model(self, q, qd, frame, rows, singular_tolerance)

    def dynamic_manipulability(
        self,
        q: ArrayLike,
        frame: str | None = None,
        rows: str | Sequence[int | str] = "pose",
        torque_scale: ArrayLike | str | None = None,
    ) -> DynamicManipulability:
        """The dynamic manipulability ellipsoid of ``frame`` at q (Yoshikawa): ``.axes``, ``.lengths``,
        ``.measure``. See :func:`armctl.dynamics.operational_space.dynamic_manipulability`."""
        from armctl.dynamics.operational_space import dynamic_manipulability

        return dynamic_manipulability(self, q, frame, rows, torque_scale)


def _make(model: RobotModel, backend: str, options: dict[str, Any]) -> Dynamics:
    return Dynamics(model, backend=backend, **options)
