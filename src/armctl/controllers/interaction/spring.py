"""`SpringLaw`: what the laws that make the arm a spring and damper share — a model (never None), and a
stiffness K and a damping D checked as symmetric positive semi-definite matrices of the law's size."""

from __future__ import annotations

from numpy.typing import ArrayLike

from armctl._checks import FloatArray
from armctl.controllers.base import Controller
from armctl.controllers.interaction.gains import symmetric_psd
from armctl.dynamics.base import Dynamics

#: the sizes a frame's K and D may have (6: a pose, rows [translation; rotation]; 3: the position), and their units
FRAME_SIZES = (6, 3)
FRAME_UNITS = ("N/m; N·m/rad", "N·s/m; N·m·s/rad")


class SpringLaw(Controller):
    """The base of :class:`~armctl.controllers.JointImpedance` (K and D on the joints),
    :class:`~armctl.controllers.CartesianImpedance` and :class:`~armctl.controllers.Admittance` (K and D on a
    frame's 6 or 3 axes): it checks K, then D of K's size, and leaves a D of None (a damping the law derives)
    to the law.

    Parameters
    ----------
    dynamics : Dynamics
        The controller's model.
    stiffness : array_like
        K: a (m,) diagonal or an m×m matrix (a scalar where m has one size), m one of ``sizes``, symmetric
        positive semi-definite.
    damping : array_like or None
        D, likewise, of K's size; None: ``self.damping`` is None.
    sizes : tuple of int, optional
        The sizes K may have; None: the number of joints.
    units : tuple of str, optional
        K's and D's units, for the error messages.

    Raises
    ------
    InvalidParameterError, ShapeError
        K or D not symmetric positive semi-definite (D: a negative damping), or of the wrong size.
    """

    dynamics: Dynamics  # given to __init__, never None

    def __init__(
        self,
        dynamics: Dynamics,
        stiffness: ArrayLike,
        damping: ArrayLike | None,
        sizes: tuple[int, ...] | None = None,
        units: tuple[str, str] = ("N·m/rad", "N·m·s/rad"),
    ) -> None:
        super().__init__(dynamics)
        self.stiffness = symmetric_psd(stiffness, (self.n,) if sizes is None else sizes, "stiffness", units[0])
        m = self.stiffness.shape[0]
        self.damping: FloatArray | None = None if damping is None else symmetric_psd(damping, (m,), "damping", units[1])
