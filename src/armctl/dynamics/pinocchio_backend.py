"""The ``"pinocchio"`` backend: Pinocchio's RNEA, CRBA, ABA, Coriolis matrix and joint-torque regressor.

Rotors enter as reflected inertia k_r²·I_m on the diagonal (Pinocchio's armature); their gyroscopic coupling
with the previous link, k_r I_m q̇_i z_mᵀω_{i−1}, is not expressed (the ``"lagrange"`` backend has it).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from functools import partial
from typing import Any, cast

from armctl.codegen.policy import CompileMode, check_cache_dir, compile_mode
from armctl.dynamics.base import Dynamics
from armctl.dynamics.pinocchio_kernel import PinocchioKernel
from armctl.model.robot import RobotModel


class PinocchioDynamics(Dynamics):
    """Dynamics evaluated by Pinocchio (see :class:`~armctl.dynamics.base.Dynamics` for the API).

    ``pin_model`` is the Pinocchio model (read it, do not change it); each thread's kernel has its own
    ``pin.Data`` (``dyn.kernel.pin_data``).

    Parameters
    ----------
    model : RobotModel
        The arm.
    compile : {False, True, "auto"}, optional
        Gravity, forward dynamics, the passivity torque and the regressors as generated C code
        (:mod:`armctl.dynamics.compiled`), under the compile policy of :mod:`armctl.codegen.policy`: True (or a
        BackendError), False (Pinocchio's algorithms), ``"auto"`` (generated where it can be built).
    cache_dir : str or path, optional
        Where compiled code is kept (default ``$ARMCTL_CACHE`` or ``~/.cache/armctl``); not with compile=False.
    """

    backend = "pinocchio"
    option_names = ("compile", "cache_dir")

    def __init__(
        self,
        model: RobotModel,
        backend: str | None = None,
        compile: CompileMode = False,
        cache_dir: str | os.PathLike[str] | None = None,
        **options: Any,
    ) -> None:
        self._compile = compile_mode(compile)
        check_cache_dir(cache_dir, self._compile)
        self._cache_dir = cache_dir
        self.pin_model = model.to_pinocchio()
        self._functions = None
        if self._compile is not False:
            from armctl.dynamics import compiled  # CasADi, imported on use

            self._functions = compiled.FALLBACK.attempt(lambda: compiled.library(model, cache_dir), self._compile)
        #: whether the hot terms run as generated C code (``compile=True``, or ``"auto"`` where it could be built)
        self.compiled = self._functions is not None
        super().__init__(model, backend, **options)

    def kernel_factory(self) -> Callable[[], PinocchioKernel]:
        if self._functions is not None:
            from armctl.dynamics.compiled import CompiledKernel

            return partial(CompiledKernel, self.model, self.pin_model, self._functions)
        return partial(PinocchioKernel, self.model, self.pin_model)

    @property
    def options(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        if self._compile is not False:
            out["compile"] = self._compile
        if self._cache_dir is not None:
            out["cache_dir"] = self._cache_dir
        return out

    def __repr__(self) -> str:
        compiled = ", compile=True" if self.compiled else ""
        return f"Dynamics({self.model.name!r}, backend={self.backend!r}{compiled}, n={self.n})"

    @property
    def pin_data(self) -> Any:
        """This thread's kernel's ``pin.Data`` workspace (its contents after a call are unspecified)."""
        return cast(PinocchioKernel, self.kernel).pin_data
