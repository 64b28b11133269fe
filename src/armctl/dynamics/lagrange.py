"""The ``"lagrange"`` backend: the Lagrange formulation itself, built symbolically with CasADi.

From the model's kinematic chain it builds, as the textbook derives it (see ``shared/references``):

* the pose of every joint frame, T_i = T_{i−1} · P_i · (rotation about / translation along the joint axis),
  its axis z_i, angular velocity ω_i = ω_{i−1} + z_i q̇_i (revolute) and origin velocity ṗ_i = J_P,i q̇;
* the kinetic energy of every augmented link, linear in its parameters (m, m·c, I_O about the joint origin),
  T_i = ½ m ṗ_iᵀṗ_i + ṗ_iᵀ(ω_i × R_i m c) + ½ ω_iᵀ R_i I_O R_iᵀ ω_i,
  and of every rotor riding on link i−1 and spinning at k_r q̇_i about z_m relative to it,
  T_m,i = ½ k_r² I_m q̇_i² + k_r I_m q̇_i z_mᵀ ω_{i−1}   (the second, gyroscopic term: ``rotor_coupling``);
* the potential energy U = −Σ g₀ᵀ (m p_i + R_i m c);
* M = ∂²T/∂q̇², g = ∂U/∂q, and C from the Christoffel symbols,
  C_ij = Σ_k ½(∂M_ij/∂q_k + ∂M_ik/∂q_j − ∂M_jk/∂q_i) q̇_k = ½(Ṁ + ∂(M q̇)/∂q − (∂(M q̇)/∂q)ᵀ)_ij;
* τ = M q̈ + C q̇ + g with the parameters π kept symbolic, so the regressor is exactly Y = ∂τ/∂π.

Evaluation runs CasADi's virtual machine, or C code generated from the same functions and compiled with the
system's C compiler (``compile=True``), cached on disk by the model's fingerprint (see :mod:`armctl.codegen`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import cached_property, partial
from typing import Any

import casadi as cs
import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean
from armctl.codegen import Fallback, compile_mode
from armctl.codegen import library as codegen
from armctl.codegen.policy import CompileMode, check_cache_dir
from armctl.dynamics.base import Dynamics
from armctl.dynamics.casadi_buffer import buffer_of, view
from armctl.dynamics.kernel import Kernel
from armctl.model.robot import PARAMS_PER_JOINT, RobotModel


def _skew(v: cs.SX | cs.DM) -> cs.SX | cs.DM:
    return cs.vertcat(cs.horzcat(0, -v[2], v[1]), cs.horzcat(v[2], 0, -v[0]), cs.horzcat(-v[1], v[0], 0))


def _axis_rotation(axis: FloatArray, angle: cs.SX) -> cs.SX:
    """Rodrigues' formula for a constant unit axis."""
    k = cs.DM(axis)
    s = _skew(k)
    return cs.DM.eye(3) + cs.sin(angle) * s + (1 - cs.cos(angle)) * (s @ s)


class _Symbols:
    """The symbolic model: kinematics, energies, M, C, g, τ, all as CasADi SX expressions."""

    def __init__(self, model: RobotModel, rotor_coupling: bool) -> None:
        n = model.n
        k = PARAMS_PER_JOINT
        self.q, self.qd, self.qdd = cs.SX.sym("q", n), cs.SX.sym("qd", n), cs.SX.sym("qdd", n)
        self.pi = cs.SX.sym("pi", k * n)
        q, qd, pi = self.q, self.qd, self.pi
        g0 = cs.DM(model.gravity)
        rot: list[cs.SX] = [cs.SX.eye(3)]  # index 0: the world
        pos: list[cs.SX] = [cs.SX.zeros(3)]
        omega: list[cs.SX] = [cs.SX.zeros(3)]
        self.axes: list[cs.SX] = []  # world axis of each joint
        kinetic = cs.SX(0)
        potential = cs.SX(0)
        for i, joint in enumerate(model.joints):
            pl = joint.placement
            r = rot[i] @ cs.DM(pl[:3, :3])
            p = pos[i] + rot[i] @ cs.DM(pl[:3, 3])
            z = r @ cs.DM(joint.axis)
            if joint.kind == "revolute":
                r = r @ _axis_rotation(joint.axis, q[i])
                w = omega[i] + z * qd[i]
            else:
                p = p + z * q[i]
                w = omega[i]
            rot.append(r)
            pos.append(p)
            omega.append(w)
            self.axes.append(z)
            v = cs.jtimes(p, q, qd)  # ṗ = J_P q̇
            m, mc = pi[k * i], pi[k * i + 1 : k * i + 4]
            ixx, ixy, iyy, ixz, iyz, izz = (pi[k * i + 4 + j] for j in range(6))
            inertia = cs.vertcat(cs.horzcat(ixx, ixy, ixz), cs.horzcat(ixy, iyy, iyz), cs.horzcat(ixz, iyz, izz))
            w_local = r.T @ w
            kinetic += (
                0.5 * m * cs.dot(v, v) + cs.dot(v, cs.cross(w, r @ mc)) + 0.5 * cs.dot(w_local, inertia @ w_local)
            )
            potential -= cs.dot(g0, m * p + r @ mc)
            rotor = pi[k * i + 10]  # k_r² I_m (a parameter of every joint; zero without a motor)
            kinetic += 0.5 * rotor * qd[i] ** 2
            if joint.motor is not None and joint.motor.gyroscopic:
                if rotor_coupling and i > 0:
                    z_m = rot[i] @ cs.DM(joint.motor_axis)  # rotor axis, carried by link i−1
                    kinetic += rotor / joint.motor.gear_ratio * qd[i] * cs.dot(z_m, omega[i])
        self.rot, self.pos = rot, pos
        self.kinetic, self.potential = kinetic, potential
        momentum = cs.gradient(kinetic, qd)  # ∂T/∂q̇ = M q̇
        self.mass = cs.jacobian(momentum, qd)  # ∂²T/∂q̇²
        self.gravity = cs.gradient(potential, q)
        jac = cs.jacobian(momentum, q)  # ∂(M q̇)/∂q
        mdot = cs.jtimes(self.mass, q, qd)  # Ṁ = Σ_k ∂M/∂q_k q̇_k
        self.coriolis = 0.5 * (mdot + jac - jac.T)
        # τ = d/dt ∂L/∂q̇ − ∂L/∂q, with the time derivative as directional derivatives (forward mode): the
        # same τ as M q̈ + C q̇ + g, but an expression several times smaller than going through C
        self.tau = (
            cs.jtimes(momentum, qd, self.qdd) + cs.jtimes(momentum, q, qd) - cs.gradient(kinetic, q) + self.gravity
        )
        self.regressor = cs.jacobian(self.tau, pi)

    def frame(self, model: RobotModel, name: str | None) -> tuple[cs.SX, cs.SX]:
        """Pose (4×4) and geometric Jacobian (6×n, world-aligned, at the frame origin) of a frame."""
        f = model.frame(name)
        r = self.rot[f.joint] @ cs.DM(f.placement[:3, :3])
        p = self.pos[f.joint] + self.rot[f.joint] @ cs.DM(f.placement[:3, 3])
        pose = cs.vertcat(cs.horzcat(r, p), cs.DM([[0, 0, 0, 1]]))
        cols = []
        for j, joint in enumerate(model.joints):
            ang = self.axes[j] if (joint.kind == "revolute" and j < f.joint) else cs.SX.zeros(3)
            cols.append(ang)
        jac = cs.vertcat(cs.jacobian(p, self.q), cs.horzcat(*cols))
        return pose, jac


#: what ``compile="auto"`` runs without a C compiler
FALLBACK = Fallback("the Lagrange model's generated C code", "CasADi's virtual machine", "several times slower")
_FUNCTION_NAMES = ("M", "C", "g", "tau", "Y", "T", "U", "tool_J", "tool_pose")


def _cache_tag(model: RobotModel, rotor_coupling: bool) -> str:
    # π is an input of every function, so the code depends on the kinematics only: payload and perturbed
    # variants of an arm share one compiled library
    return f"{model.fingerprint(inertial=False)}-{'rc' if rotor_coupling else 'nc'}"


class _Evaluator:
    """Calls a CasADi function through its zero-copy buffer (``Function.buffer``): ~10× less overhead than
    ``f(*args)``, which converts every argument to a DM. Results are fresh arrays (column-major for
    matrices, as CasADi stores them). Not thread-safe (one buffer per function)."""

    def __init__(self, fn: cs.Function, fixed: dict[int, FloatArray] | None = None) -> None:
        self.fn = fn
        self._buf, self._eval = buffer_of(fn)
        self._shape = (fn.size1_out(0), fn.size2_out(0))
        self._fixed = {i: np.ascontiguousarray(a, dtype=float) for i, a in (fixed or {}).items()}
        for i, a in self._fixed.items():  # kept alive by self._fixed: the buffer holds a pointer to it
            self._buf.set_arg(i, view(a))
        self._free = [i for i in range(fn.n_in()) if i not in self._fixed]
        self._sizes = [fn.numel_in(i) for i in self._free]

    def __call__(self, *args: FloatArray) -> FloatArray:
        held = [np.ascontiguousarray(a, dtype=float) for a in args]  # alive until evaluation is done
        for i, a, size in zip(self._free, held, self._sizes, strict=True):
            if a.size != size:  # the buffer would read past a short array and ignore the tail of a long one
                raise ValueError(f"argument {i} of {self.fn.name()} has {a.size} entries, not {size}")
            self._buf.set_arg(i, view(a))
        out = np.empty(self._shape, order="F")
        self._buf.set_res(0, view(out.reshape(-1, order="A")))
        self._eval()
        return out


class LagrangeKernel(Kernel):
    """The primitives on the CasADi functions ``functions`` (by name) of :class:`LagrangeDynamics`, each
    evaluated through buffers of this kernel's own, with the model's π bound where a function takes it."""

    def __init__(self, model: RobotModel, functions: dict[str, cs.Function], symbols: _Symbols) -> None:
        super().__init__(model)
        params = model.parameters()
        with_pi = {"M": 1, "C": 2, "g": 1, "tau": 3, "T": 2, "U": 1}
        ev = {
            name: _Evaluator(f, {with_pi[name]: params} if name in with_pi else None) for name, f in functions.items()
        }
        self._ev, self._sym = ev, symbols
        self._frame_fns: dict[str, tuple[_Evaluator, _Evaluator]] = {}
        self.mass = ev["M"]
        self.coriolis = ev["C"]
        g, tau, energy, potential = ev["g"], ev["tau"], ev["T"], ev["U"]
        self.gravity = lambda q: g(q).reshape(-1)
        self.rnea = lambda q, qd, qdd: tau(q, qd, qdd).reshape(-1)
        self.aba = self.solve_aba
        self._energy = energy
        self.potential = lambda q: float(potential(q)[0, 0])

    def kinetic(self, q: FloatArray, qd: FloatArray) -> float:
        return float(self._energy(q, qd)[0, 0])

    def regressor(
        self, q: FloatArray, qd: FloatArray, qdd: FloatArray, friction: tuple[FloatArray, FloatArray] | None = None
    ) -> FloatArray:
        y = self._ev["Y"](q, qd, qdd)
        if friction is not None:
            y.put(self._diag_idx[self.n :], np.concatenate((friction[0], self.friction.coulomb_column(friction[1]))))
        return y

    def _frame_functions(self, frame: str | None) -> tuple[_Evaluator, _Evaluator]:
        if frame is None:
            return self._ev["tool_pose"], self._ev["tool_J"]
        if frame not in self._frame_fns:
            pose, jac = self._sym.frame(self.model, frame)
            self._frame_fns[frame] = (
                _Evaluator(cs.Function("pose", [self._sym.q], [cs.densify(pose)])),
                _Evaluator(cs.Function("J", [self._sym.q], [cs.densify(jac)])),
            )
        return self._frame_fns[frame]

    def jacobian(self, q: FloatArray, frame: str | None = None) -> FloatArray:
        return self._frame_functions(frame)[1](q)

    def frame_pose(self, q: FloatArray, frame: str | None = None) -> FloatArray:
        return np.ascontiguousarray(self._frame_functions(frame)[0](q))


class LagrangeDynamics(Dynamics):
    """Dynamics from the Lagrange formulation in CasADi.

    Parameters
    ----------
    model : RobotModel
        The arm.
    rotor_coupling : bool
        Include the rotors' gyroscopic coupling k_r I_m q̇_i z_mᵀω_{i−1} (default True; with False the model is
        exactly what the ``"pinocchio"`` backend expresses).
    compile : {False, True, "auto"}
        Generate C code and compile it (cached on disk; see :func:`armctl.codegen.library.compiled`), under the
        compile policy of :mod:`armctl.codegen.policy`: True (or a BackendError), False (CasADi's virtual
        machine), ``"auto"`` (generated where it can be built).
    cache_dir : str or path, optional
        Where compiled code is cached (default ``$ARMCTL_CACHE`` or ``~/.cache/armctl``).
    """

    backend = "lagrange"
    option_names = ("rotor_coupling", "compile", "cache_dir")

    def __init__(
        self,
        model: RobotModel,
        backend: str | None = None,
        *,
        rotor_coupling: bool = True,
        compile: CompileMode = False,
        cache_dir: str | None = None,
        **options: Any,
    ) -> None:
        self.rotor_coupling = boolean(rotor_coupling, "rotor_coupling")  # bool("False") would be True
        self._compile = compile_mode(compile)  # checked before the build: "False" would compile
        check_cache_dir(cache_dir, self._compile)
        t0 = time.perf_counter()
        s = _Symbols(model, self.rotor_coupling)
        self._sym = s
        q, qd, qdd, pi = s.q, s.qd, s.qdd, s.pi
        tool_pose, tool_jac = s.frame(model, None)
        # outputs dense: the zero-copy evaluator writes every entry, structural zeros included
        fns = [
            cs.Function(name, args, [cs.densify(out)])
            for name, args, out in (
                ("M", [q, pi], s.mass),
                ("C", [q, qd, pi], s.coriolis),
                ("g", [q, pi], s.gravity),
                ("tau", [q, qd, qdd, pi], s.tau),
                ("Y", [q, qd, qdd], s.regressor),
                ("T", [q, qd, pi], s.kinetic),
                ("U", [q, pi], s.potential),
                ("tool_J", [q], tool_jac),
                ("tool_pose", [q], tool_pose),
            )
        ]
        self.build_seconds = time.perf_counter() - t0
        self._cache_dir = cache_dir
        #: whether the functions run as generated C code (``compile=True``, or ``"auto"`` where it could be built)
        tag = _cache_tag(model, self.rotor_coupling)
        built = FALLBACK.attempt(lambda: codegen.compiled(fns, tag, cache_dir), self._compile)
        self.compiled = built is not None
        fns = built or fns
        self.functions: dict[str, cs.Function] = {f.name(): f for f in fns}
        super().__init__(model, backend, **options)

    def kernel_factory(self) -> Callable[[], LagrangeKernel]:
        return partial(LagrangeKernel, self.model, self.functions, self._sym)

    @staticmethod
    def is_compiled_cached(model: RobotModel, rotor_coupling: bool = True, cache_dir: str | None = None) -> bool:
        """Whether ``compile=True`` would load a cached library (instead of compiling it)."""
        return codegen.is_cached(
            list(_FUNCTION_NAMES), _cache_tag(model, boolean(rotor_coupling, "rotor_coupling")), cache_dir
        )

    @property
    def options(self) -> dict[str, Any]:
        return {"rotor_coupling": self.rotor_coupling, "compile": self._compile, "cache_dir": self._cache_dir}

    @cached_property
    def symbols(self) -> _Symbols:
        """The symbolic model (CasADi SX expressions: ``mass``, ``coriolis``, ``gravity``, ``tau``,
        ``regressor``, ``kinetic``, ``potential``, and the symbols ``q``, ``qd``, ``qdd``, ``pi``)."""
        return self._sym

    def rotor_coupling_matrix(self, q: ArrayLike) -> FloatArray:
        """The rotors' gyroscopic contribution to M (n×n, symmetric): entry (i, j) = (j, i) =
        k_r,i I_m,i z_m,iᵀ J_O,j^(i−1) for j < i, where J_O^(i−1) is the angular Jacobian of link i−1 — the
        difference between the model's M with and without the coupling. It describes the model, whatever this
        object's ``rotor_coupling`` (with False its M leaves this term out).

        Parameters
        ----------
        q : (n,) array_like
            Joint positions [rad or m].
        """
        qv = self._vector(q, "q")
        k = self.kernel
        out = np.zeros((self.n, self.n))
        for i, joint in enumerate(self.model.joints):
            if joint.motor is None or not joint.motor.gyroscopic or i == 0:
                continue
            previous = self.model.joints[i - 1].name
            z_m = k.frame_pose(qv, previous)[:3, :3] @ joint.motor_axis
            jw = k.jacobian(qv, previous)[3:]
            row = joint.motor.gear_ratio * joint.motor.inertia * (z_m @ jw)
            out[i, :i] += row[:i]
            out[:i, i] += row[:i]
        return out
