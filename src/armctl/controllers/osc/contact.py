"""`Contact`: a declared point contact, its force variables, its kinematic rows and its friction cone (the
equations are given with the class).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from armctl._checks import FloatArray, boolean, scalar, vector, whole_number
from armctl.controllers.osc.state import ModelState
from armctl.errors import InvalidParameterError, UnknownNameError

MODES = ("fixed", "sliding")


class Contact:
    """A declared point contact of a frame's origin with a surface: three force variables f in the QP, its
    kinematic rows and its friction cone. An inactive contact (``active = False``) adds no variables and no rows:
    switch it on when the point touches.

    Parameters
    ----------
    frame : str, optional
        The frame whose origin touches (a name of the model's ``frame_names``); None (the default): the tool frame.
    normal : array_like, shape (3,), optional
        The surface normal n (world axes), pointing from the surface towards the robot; normalised here.
    mu : float, optional
        The friction coefficient μ ≥ 0.
    mode : {"fixed", "sliding"}, optional
        ``"fixed"``: the point stays put, f in the friction cone; ``"sliding"``: the point slides on the surface
        with Coulomb's kinetic friction (see Notes).
    facets : int, optional
        The number of faces (≥ 3) of the pyramid inscribed in the friction cone (fixed mode).
    kd : float, optional
        k_d ≥ 0 [1/s]: damps the contact point's velocity along the constrained directions.
    min_force : float, optional
        f_min ≥ 0 [N]: the smallest normal force, which keeps the contact pressed.
    slip_velocity : float, optional
        v_ε > 0 [m/s]: smooths the sliding direction near rest.
    name : str, optional
        The contact's name, unique in a controller; None (the default): ``"contact[FRAME]"``.
    active : bool, optional
        Whether the contact is on; may be switched between control periods.

    Raises
    ------
    UnknownNameError
        ``mode`` is not "fixed" or "sliding"; (when given to a controller) the model has no such frame.
    InvalidParameterError, ShapeError, NonFiniteError
        A zero or malformed normal, ``facets`` below 3, ``mu``, ``kd`` or ``min_force`` negative,
        ``slip_velocity`` not > 0, ``active`` not a bool.

    Notes
    -----
    The force f (3,) [N], world axes, is the force the environment exerts on the robot at the origin of
    ``frame`` (f = −h_e for the wrench h_e the arm exerts, see ``armctl.Dynamics.inverse_dynamics``): in a
    simulated run, compare it with ``SimResult.contact_force_on_robot`` (same sense), not with
    ``SimResult.wrench`` or the force sensors (the arm's force, the opposite sense); it enters
    the equation of motion as  M q̈ + C q̇ + g + τ_f − J_cᵀ f = τ,  with J_c the linear rows of the frame
    Jacobian. The two modes:

    * ``"fixed"`` — the point stays put:  J_c q̈ + J̇_c q̇ = −k_d v_c  (3 rows; k_d damps any residual
      velocity), and f lies in the friction cone, linearised as an inscribed pyramid of ``facets`` faces:
      nᵀf ≥ f_min,  (d_iᵀ − μ cos(π/facets) nᵀ) f ≤ 0 for the facet directions d_i in the tangent plane.
    * ``"sliding"`` — the point slides on the surface:  nᵀ(J_c q̈ + J̇_c q̇) = −k_d nᵀv_c  (1 row), the
      tangential force is Coulomb's kinetic friction against the sliding direction
      ŝ = v_t / √(‖v_t‖² + v_ε²), f_t = −μ (nᵀf) ŝ (2 rows, on the cone's boundary, so no pyramid is
      imposed), and nᵀf ≥ f_min.
    """

    dim = 3

    def __init__(
        self,
        frame: str | None = None,
        normal: ArrayLike = (0.0, 0.0, 1.0),
        mu: float = 0.5,
        mode: str = "fixed",
        facets: int = 4,
        kd: float = 50.0,
        min_force: float = 0.0,
        slip_velocity: float = 1e-3,
        name: str | None = None,
        active: bool = True,
    ) -> None:
        if mode not in MODES:
            raise UnknownNameError("contact mode", mode, MODES)
        nrm = vector(normal, 3, "normal")
        length = float(np.linalg.norm(nrm))
        if length < 1e-9:
            raise InvalidParameterError("contact normal must be a non-zero vector", value=normal)
        facets = whole_number(facets, "facets", minimum=3)
        self.frame = frame
        self.name = name or f"contact[{frame or 'tool'}]"
        self.mode = mode
        self.normal = nrm / length
        self.mu = scalar(mu, "mu", nonnegative=True)
        self.kd = scalar(kd, "kd", nonnegative=True)
        self.min_force = scalar(min_force, "min_force", nonnegative=True)
        self.slip_velocity = scalar(slip_velocity, "slip_velocity", positive=True)
        self.facets = int(facets)
        self.active = boolean(active, "active")  # bool("False") would be True
        # tangent basis (t1, t2) and the pyramid's facet directions
        a = np.eye(3)[int(np.argmin(np.abs(self.normal)))]
        t1 = np.cross(self.normal, a)
        t1 /= np.linalg.norm(t1)
        self.tangents = np.array([t1, np.cross(self.normal, t1)])
        ang = 2 * np.pi * np.arange(self.facets) / self.facets
        dirs = np.cos(ang)[:, None] * t1 + np.sin(ang)[:, None] * self.tangents[1]
        mu_in = self.mu * math.cos(math.pi / self.facets)
        if mode == "fixed":
            self._cone = np.vstack([self.normal, dirs - mu_in * self.normal])
            self._cone_l = np.r_[self.min_force, np.full(self.facets, -np.inf)]
            self._cone_u = np.r_[np.inf, np.zeros(self.facets)]
            self._cone_names = [f"unilateral[{self.name}]"] + [
                f"friction_cone[{self.name},{i}]" for i in range(self.facets)
            ]
            self.eq_names = [f"{self.name}.acceleration[{c}]" for c in "xyz"]
        else:
            self._cone = self.normal[None, :].copy()
            self._cone_l = np.array([self.min_force])
            self._cone_u = np.array([np.inf])
            self._cone_names = [f"unilateral[{self.name}]"]
            self.eq_names = [
                f"{self.name}.normal_acceleration",
                f"{self.name}.friction[t1]",
                f"{self.name}.friction[t2]",
            ]

    def equality_rows(self, state: ModelState) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The contact's equality rows G_q q̈ + G_f f = rhs at this step (see the class's Notes).

        Parameters
        ----------
        state : ModelState
            The model terms at the measured (q, q̇), with the frame's kinematics.

        Returns
        -------
        G_q : ndarray, shape (3, n)
            The rows' coefficients of q̈.
        G_f : ndarray, shape (3, 3)
            Their coefficients of f (zero in fixed mode).
        rhs : ndarray, shape (3,)
            Their right-hand side [m/s² for the kinematic rows, N for the friction rows].
        """
        fk = state.frame(self.frame)
        jv, drift, vel = fk.jacobian[:3], fk.drift[:3], fk.velocity[:3]
        n = state.q.shape[0]
        if self.mode == "fixed":
            return jv, np.zeros((3, 3)), -drift - self.kd * vel
        nrm = self.normal
        gq = np.zeros((3, n))
        gq[0] = nrm @ jv
        vt = self.tangents @ vel  # tangential velocity in (t1, t2)
        s = vt / math.sqrt(float(vt @ vt) + self.slip_velocity**2)
        gf = np.zeros((3, 3))
        gf[1:] = self.tangents + self.mu * s[:, None] * nrm[None, :]
        rhs = np.zeros(3)
        rhs[0] = -(nrm @ drift) - self.kd * (nrm @ vel)
        return gq, gf, rhs

    def cone_rows(self) -> tuple[FloatArray, FloatArray, FloatArray, list[str]]:
        """The contact's inequality rows l ≤ C_f f ≤ u (constant): the unilateral row and, in fixed mode, the
        friction pyramid's ``facets`` rows.

        Returns
        -------
        C_f : ndarray, shape (m, 3)
            The rows on f (m = 1 + facets in fixed mode, 1 when sliding).
        l, u : ndarray, shape (m,)
            Their bounds [N]; ±inf: no bound.
        names : list of str
            The rows' names, ``unilateral[NAME]`` and ``friction_cone[NAME,i]``.
        """
        return self._cone, self._cone_l, self._cone_u, self._cone_names

    def __repr__(self) -> str:
        return f"Contact({self.name!r}, mode={self.mode!r}, mu={self.mu}, active={self.active})"
