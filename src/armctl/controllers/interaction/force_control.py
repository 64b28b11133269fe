"""`ForceControl`: direct force control with an inner motion loop, along chosen directions."""

from __future__ import annotations

from armctl.controllers.interaction.force_loop import ForceLoop


class ForceControl(ForceLoop):
    """Force control with an inner motion loop (Siciliano, Sciavicco, Villani & Oriolo, *Robotics: Modelling,
    Planning and Control*, 2009, §9.4): a PI law on the force error moves the commanded position along the
    force-controlled directions; the motion target rules the others and the orientation.

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model.
    force : array_like or callable
        f_d (3,) [N], the force the arm should exert (world axes; pressing down on a table: (0, 0, −f)), or
        t [s] → f_d.
    force_gain : array_like
        K_F [m/N] ≥ 0: scalar, (3,) or 3×3.
    integral_gain : array_like, optional
        K_I [m/(N·s)] ≥ 0, likewise; 0 (the default): proportional only, which leaves a force error at rest.
    frame : str, optional
        The controlled frame (None: the tool frame); the force is taken at its origin.
    directions : array_like, optional
        The force-controlled directions: a (3,) vector (a surface normal) or (k, 3) rows, world axes; None
        (the default): all three.
    force_source : "sensor" or observer, optional
        ``"sensor"`` (the default): a force/torque sensor's wrench (``reads = {"wrench"}``); or an object with
        ``update(t, q, qd, tau_applied)`` and ``wrench(q, frame)``, such as
        :class:`armctl.controllers.MomentumObserver` (``reads = {"tau_applied"}``).
    inner : {"computed_torque", "osc"}, optional
        The inner motion loop (:mod:`~armctl.controllers.interaction.inner`).
    kp, kd : array_like, optional
        Its gains K_P [1/s²] (default 400) and K_D [1/s] (None: 2 K_P^½), scalar, (6,) or 6×6.
    posture : array_like, optional
        q_n (n,) [rad] of the null-space posture; None: the joint reference ``ref.q``.
    posture_kp : array_like, optional
        K_P,n [1/s²] ≥ 0 of the posture (default 10).
    compile : bool or "auto", optional
        The inner loop as one call of generated C code: "auto" (the default) where the dynamics are Pinocchio's and
        a C compiler builds it, True (or an error), False (NumPy).
    compensate : bool, optional
        Add Jᵀ h, the measured wrench, to the torque (default True), so that the contact does not push the inner
        loop off its command.

    Raises
    ------
    InvalidParameterError
        No force source (``force_source`` neither "sensor" nor an observer), a gain that is not symmetric
        positive semi-definite, directions that are not independent.
    ShapeError
        ``force`` or a gain of the wrong size.
    UnknownNameError
        ``frame`` or ``inner`` unknown.

    Notes
    -----
    With P the projector on ``directions``, f the measured force the arm exerts and p_d, v_d, a_d the motion
    target::

        e_f = P (f_d − f),      x_F = P (K_F e_f + K_I ∫ e_f dt)
        p_c = p_d + x_F,        v_c = (I − P) v_d,     a_c = (I − P) a_d,     R_c = R_d

    and the inner loop drives the frame to (p_c, R_c). Against an environment of stiffness k_e along a force
    direction, with a stiff inner loop (x ≈ p_c), the force obeys f ≈ k_e (p_d + x_F − x_e): the loop gain is
    k_e K_F (and k_e K_I/s). At rest the integral leaves no force error. Where it fails: the loop gain grows
    with the environment's stiffness, so a gain tuned on a soft surface rings, then diverges, on a stiff one —
    sooner with a control period of delay; with K_I = 0 a force error (f_d − k_e δ_d) / (1 + k_e K_F) remains at
    rest (δ_d the depth of p_d beyond the surface); off the surface (no force to read) the command keeps moving
    towards it at the integral's rate.

    ``last_log`` holds ``"force_error"`` e_f [N], ``"offset"`` x_F [m], ``"wrench"`` h and ``"error"`` the
    inner loop's frame error [m; rad].
    """
