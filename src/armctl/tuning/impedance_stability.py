"""Sampled-data stability of Cartesian impedance against a compliant environment: the environment stiffness k_e*
beyond which the contact chatters.

In the controller's m task axes (m = 1: the contact normal alone; 3: position; 6: [translation; rotation]), with x
the frame's displacement from its resting pose, the arm under :class:`~armctl.controllers.CartesianImpedance`
(exact model, no inertia shaping) obeys

    Λ ẍ = F − k_e n nᵀ x − d_e n nᵀ ẋ,      F = −K x_m − D ẋ_m

where Λ = (J M⁻¹ Jᵀ)⁻¹ is the frame's inertia at the pose, K and D the impedance's stiffness and damping, n the
contact normal (a unit vector of the task axes), and (x_m, ẋ_m) are measured at the samples t_k = kT, ``delay``
periods old, while the force F is held over each period (zero-order hold). The null-space spring acts in the
dynamically consistent null space and leaves these axes alone. The plant ẋ = A x + B F, x = (x, ẋ),

    A = [[0, I], [−Λ⁻¹ k_e n nᵀ, −Λ⁻¹ d_e n nᵀ]],      B = [[0], [Λ⁻¹]],

is discretised exactly with python-control (ZOH), and the loop closed on the state augmented with the ``delay``
past samples. The contact mode √(k_e/Λ_n) rises with k_e; once its period is a few sample periods the held, delayed
damping pushes instead of braking, and the mode grows: the critical k_e* (spectral radius 1). The axes the contact
does not load still matter: their inertia and damping couple to the normal through Λ's off-diagonal terms, so the
model takes the controller's whole Λ, K and D (:func:`impedance_model`) rather than the normal's alone.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from armctl._checks import scalar, vector, whole_number
from armctl.controllers.interaction.gains import critical_damping, damping_ratio, symmetric_psd
from armctl.errors import InvalidParameterError
from armctl.tuning.sampled import delayed_loop_matrix

if TYPE_CHECKING:
    from armctl.controllers import CartesianImpedance


def _task_matrix(value: Any, m: int, name: str, unit: str, definite: bool = False) -> np.ndarray:
    """A scalar (times I), an (m,) diagonal or an m×m matrix, symmetric positive (semi-)definite."""
    return symmetric_psd(value, (m,), name, unit, definite)


def _normal(normal: Any, m: int) -> np.ndarray:
    """The unit contact normal in the m task axes: None is the only axis (m = 1) or z (m ≥ 3); a (3,) direction
    for 6 axes is the translation's."""
    if normal is None:
        if m == 1:
            return np.ones(1)
        if m < 3:
            raise InvalidParameterError(f"give the contact normal in the {m} task axes", value=normal)
        n = np.zeros(m)
        n[2] = 1.0
        return n
    n = np.asarray(normal, dtype=float)
    if m == 6 and n.shape == (3,):
        n = np.concatenate([n, np.zeros(3)])
    n = vector(n, m, "normal")
    size = float(np.linalg.norm(n))
    if size == 0.0:
        raise InvalidParameterError("the contact normal must not be zero", value=normal)
    return n / size


def impedance_loop_matrix(
    stiffness: float,
    impedance_stiffness: Any,
    inertia: Any,
    period: float,
    delay: int = 0,
    damping: float = 0.0,
    zeta: float = 1.0,
    impedance_damping: Any = None,
    normal: Any = None,
) -> np.ndarray:
    """The transition matrix of Cartesian impedance against the environment (see the module): the held, delayed
    force F = −K x_m − D ẋ_m on the plant Λ ẍ = F − k_e n nᵀ x − d_e n nᵀ ẋ.

    Parameters
    ----------
    stiffness : float
        k_e [N/m], > 0.
    impedance_stiffness : float or array_like
        K [N/m; N·m/rad]: k_d along the normal (one axis), or the controller's (m,) diagonal or m×m matrix.
    inertia : float or array_like
        Λ [kg; kg·m²], positive definite: Λ_n along the normal (one axis), or the frame's m×m inertia
        (:func:`impedance_model`); its size sets the axes m.
    period : float
        T [s], > 0.
    delay : int, optional
        Periods of measurement delay (default 0).
    damping : float, optional
        d_e [N·s/m] ≥ 0 of the environment.
    zeta : float, optional
        ζ ≥ 0 of the default impedance damping.
    impedance_damping : float or array_like, optional
        D [N·s/m; N·m·s/rad]; None (the default): :class:`~armctl.controllers.CartesianImpedance`'s default,
        D = 2ζ (k_d Λ)^½ on one axis and the double diagonalisation of Λ and K on m
        (:func:`~armctl.controllers.interaction.gains.critical_damping`).
    normal : array_like, optional
        n, the contact normal in the task axes ((m,), or (3,) for the translation of 6 axes; normalised). None:
        the one axis, or z.

    Returns
    -------
    ndarray, shape (2m(d+1), 2m(d+1))
        On z_k = (x_k, ẋ_k, x_{k−1}, ẋ_{k−1}, …, x_{k−d}, ẋ_{k−d}).
    """
    import control

    k_e = scalar(stiffness, "stiffness", positive=True)
    m = 1 if np.ndim(inertia) == 0 else int(np.shape(inertia)[0])
    lam = _task_matrix(inertia, m, "inertia", "kg; kg·m²", definite=True)
    k = _task_matrix(impedance_stiffness, m, "impedance_stiffness", "N/m; N·m/rad")
    d_imp = (
        critical_damping(lam, k, damping_ratio(zeta))
        if impedance_damping is None
        else _task_matrix(impedance_damping, m, "impedance_damping", "N·s/m; N·m·s/rad")
    )
    d = whole_number(delay, "delay (in periods)")
    t = scalar(period, "period", positive=True)
    n = _normal(normal, m)
    nn = np.outer(n, n)
    lam_inv = np.linalg.inv(lam)
    zero, eye = np.zeros((m, m)), np.eye(m)
    a = np.block([[zero, eye], [-k_e * lam_inv @ nn, -scalar(damping, "damping", nonnegative=True) * lam_inv @ nn]])
    b = np.vstack([zero, lam_inv])
    sys = control.c2d(control.ss(a, b, np.eye(2 * m), np.zeros((2 * m, m))), t, method="zoh")
    return delayed_loop_matrix(np.asarray(sys.A), np.asarray(sys.B) @ -np.hstack([k, d_imp]), d)


def critical_environment_stiffness(impedance_stiffness: Any, rtol: float = 1e-4, **loop: Any) -> float:
    """k_e* [N/m]: the environment stiffness beyond which Cartesian impedance chatters on it (the sampled contact
    mode is unstable), from :func:`impedance_loop_matrix`.

    Parameters
    ----------
    impedance_stiffness : float or array_like
        K [N/m; N·m/rad] (:func:`impedance_loop_matrix`).
    rtol : float, optional
        Relative tolerance of the bisection (on log k_e).
    **loop
        ``inertia``, ``period`` and optionally ``delay``, ``damping``, ``zeta``, ``impedance_damping``, ``normal``
        (:func:`impedance_loop_matrix`; :func:`impedance_model` gives a controller's ``inertia``,
        ``impedance_stiffness`` and ``impedance_damping``).

    Returns
    -------
    float

    Raises
    ------
    InvalidParameterError
        Stable at every k_e up to 10¹⁰ N/m, or already unstable at 1 N/m.
    """

    def radius(k_e: float) -> float:
        return float(np.abs(np.linalg.eigvals(impedance_loop_matrix(k_e, impedance_stiffness, **loop))).max())

    grid = np.logspace(0.0, 10.0, 201)  # the first crossing: beyond ω T ≈ π the sampled mode aliases
    unstable = [k for k in grid if radius(float(k)) >= 1.0]
    if not unstable or unstable[0] == grid[0]:
        raise InvalidParameterError(
            f"impedance K = {impedance_stiffness!r}: no stability border in k_e between 1 and 1e10 N/m",
            value=loop,
        )
    hi = float(unstable[0])
    lo = float(grid[np.searchsorted(grid, hi) - 1])
    while np.log(hi / lo) > rtol:
        mid = float(np.sqrt(lo * hi))
        if radius(mid) < 1.0:
            lo = mid
        else:
            hi = mid
    return float(np.sqrt(lo * hi))


def impedance_model(controller: CartesianImpedance, q: Any) -> dict[str, Any]:
    """What a Cartesian impedance controller puts in its task axes at q: the frame's inertia Λ(q) = (J M⁻¹ Jᵀ)⁻¹
    from the controller's model, its stiffness K and the damping D it applies there (its own, or its default
    from Λ(q) and ζ), as the keyword arguments of :func:`impedance_loop_matrix` and
    :func:`critical_environment_stiffness`.

    Parameters
    ----------
    controller : CartesianImpedance
        Without inertia shaping (with it, the loop closes through the measured wrench, which this model leaves out).
    q : array_like
        The configuration [rad] about which the contact is linearised.

    Returns
    -------
    dict
        ``inertia`` Λ [kg; kg·m²], ``impedance_stiffness`` K and ``impedance_damping`` D, each m×m.

    Raises
    ------
    InvalidParameterError
        Not a :class:`~armctl.controllers.CartesianImpedance`, or one with inertia shaping.
    SingularConfigurationError
        Λ does not exist at q.
    """
    from armctl.controllers import CartesianImpedance
    from armctl.controllers.interaction.task_space import task_inertia

    if not isinstance(controller, CartesianImpedance):
        raise InvalidParameterError(f"impedance_model needs a CartesianImpedance, got {controller!r}", value=controller)
    if controller.inertia is not None:
        raise InvalidParameterError(
            "impedance_model: this controller shapes the inertia from the measured wrench, a loop the model "
            "leaves out; give the controller without `inertia`",
            value=controller,
        )
    dyn = controller.dynamics
    q = vector(q, controller.n, "q")
    lam, _ = task_inertia(dyn.mass_matrix(q), dyn.jacobian(q, controller.frame)[: controller.axes], q)
    given = controller.damping
    damping = critical_damping(lam, controller.stiffness, controller.zeta) if given is None else given
    return {
        "inertia": lam,
        "impedance_stiffness": np.array(controller.stiffness),
        "impedance_damping": np.array(damping),
    }
