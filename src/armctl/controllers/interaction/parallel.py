"""`ParallelForcePosition`: a force loop with integral action in parallel with a position loop."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from armctl.controllers.interaction.force_loop import ForceLoop
from armctl.controllers.interaction.gains import symmetric_psd
from armctl.dynamics.base import Dynamics
from armctl.errors import InvalidParameterError


class ParallelForcePosition(ForceLoop):
    """Parallel force/position control (Chiaverini & Sciavicco 1993; Siciliano et al., *Robotics: Modelling,
    Planning and Control*, 2009, §9.6): the force loop and the position loop act on all three translational
    axes; the integral action on the force error makes the force loop prevail along the directions the
    environment constrains, and the position target is reached along the others.

    Parameters
    ----------
    dynamics, force, force_gain, frame
        As for :class:`~armctl.controllers.ForceControl`.
    integral_gain : array_like
        K_I [m/(N·s)]: scalar, (3,) or 3×3, symmetric positive definite (the integral action is what makes the
        force prevail).
    force_source, inner, kp, kd, posture, posture_kp, compile, compensate : optional
        The force source, the inner motion loop and its gains, the null-space posture, code generation and the
        compensation of the measured wrench, as in :class:`~armctl.controllers.ForceControl`.

    Raises
    ------
    InvalidParameterError, ShapeError, UnknownNameError
        As for :class:`~armctl.controllers.ForceControl`; InvalidParameterError also for a K_I that is not
        positive definite.

    Notes
    -----
    With f the measured force the arm exerts and the motion target p_d, v_d, a_d, R_d::

        e_f = f_d − f,     x_F = K_F e_f + K_I ∫ e_f dt,     p_c = p_d + x_F,     v_c = v_d,  a_c = a_d

    and the inner loop drives the frame to (p_c, R_d). At rest against a surface (f_d along its normal), the
    integral leaves e_f = 0: the force is f_d exactly, and the frame sits at p_d along the surface, wherever the
    surface is along the normal (it need not be known). Where it fails: f_d with a component along the surface
    has nothing to push against, so the integral winds up and the frame drifts along the surface; so does
    surface friction while sliding (a tangential force the loop reads as an error), which costs tangential
    tracking; the force loop's gain grows with the environment's stiffness as in force control.

    ``last_log`` holds ``"force_error"`` e_f [N], ``"offset"`` x_F [m], ``"wrench"`` h and ``"error"`` the
    inner loop's frame error [m; rad].
    """

    def __init__(
        self,
        dynamics: Dynamics,
        force: Any,
        force_gain: ArrayLike,
        integral_gain: ArrayLike,
        frame: str | None = None,
        *,
        force_source: Any = "sensor",
        inner: str = "computed_torque",
        kp: ArrayLike = 400.0,
        kd: ArrayLike | None = None,
        posture: ArrayLike | None = None,
        posture_kp: ArrayLike = 10.0,
        compensate: bool = True,
        compile: bool | str = "auto",
    ) -> None:
        ki = symmetric_psd(integral_gain, (3,), "integral_gain", "m/(N·s)")
        if not np.linalg.eigvalsh(ki)[0] > 0.0:
            raise InvalidParameterError(
                f"integral_gain [m/(N·s)] of parallel force/position control must be positive definite (the integral "
                f"action makes the force loop prevail); got {integral_gain!r}",
                value=integral_gain,
            )
        super().__init__(
            dynamics,
            force,
            force_gain,
            ki,
            frame,
            force_source=force_source,
            inner=inner,
            kp=kp,
            kd=kd,
            posture=posture,
            posture_kp=posture_kp,
            compensate=compensate,
            compile=compile,
        )
