"""`GeneratedData`: what the generated data of the QPs with τ eliminated share
(:class:`~armctl.controllers.osc.generated.GeneratedQddData`,
:class:`~armctl.controllers.osc.generated_contact.GeneratedContactData`): the model terms they read of the
dynamics, and the binding of their generated functions to buffers of their own."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from armctl._checks import FloatArray
from armctl.dynamics.base import Dynamics
from armctl.dynamics.casadi_buffer import buffer_of, view


class GeneratedData:
    """Generated code of one QP's data on ``dynamics``: ``n`` joints, the joint ``friction`` (None on a model
    without) whose torque is an input, libraries cached in the dynamics' ``cache_dir``. The main function's
    inputs are :attr:`inp` and :attr:`par`, its outputs those a subclass gives :meth:`_bind` and then
    :attr:`targets_ok`; with constant bounds, an active-set function reads the main function's outputs
    (:meth:`_bind_active_set`). Not thread-safe."""

    #: the main function's outputs, one after the other in one buffer (made by the subclass)
    out: FloatArray

    def __init__(self, dynamics: Dynamics) -> None:
        model = dynamics.model
        self.dynamics = dynamics
        self.n = model.n
        self.friction = dynamics.friction if model.has_friction else None
        #: the folder of the cached libraries (None: the default one)
        self.cache_dir: Any = dynamics.options.get("cache_dir")

    def _bind(self, fn: Any, outputs: Sequence[FloatArray]) -> None:
        """Bind the main function ``fn`` (its ``run`` then evaluates it): its inputs :attr:`inp` and :attr:`par`,
        made here (zeros), its outputs ``outputs`` in its order and then :attr:`targets_ok`."""
        self.inp = np.zeros(fn.size1_in(0))
        self.par = np.zeros(fn.size1_in(1))
        buf, self._run = buffer_of(fn)
        for k, arr in enumerate((self.inp, self.par)):
            buf.set_arg(k, view(arr))
        for k, res in enumerate(outputs):
            buf.set_res(k, view(res))
        #: 1.0 if the frame tasks' targets passed the code's check (see target_code)
        self.targets_ok = np.zeros(1)
        buf.set_res(len(outputs), view(self.targets_ok))
        self._bound = buf  # the buffer reads inp and par and writes the outputs: kept with them

    def _bind_active_set(self, fn: Any, used: int, par: FloatArray, outputs: Sequence[FloatArray]) -> None:
        """Bind the active-set function ``fn`` (``_run_guess`` then evaluates it): its inputs the first ``used``
        entries of the main function's outputs (``out``) and its parameters ``par``, its outputs ``outputs``."""
        buf, self._run_guess = buffer_of(fn)
        buf.set_arg(0, view(self.out[:used]))
        buf.set_arg(1, view(par))
        for k, res in enumerate(outputs):
            buf.set_res(k, view(res))
        self._bound_guess = buf  # reads out and par, writes the outputs: kept with them
