"""`EliminatedQP`: what the QPs with τ eliminated share (:class:`~armctl.controllers.osc.reduced.QddQP` on q̈,
:class:`~armctl.controllers.osc.contact_qp.ContactQP` on [q̈; f]): a control step from their generated data where
they have them, else from NumPy; the NumPy path also takes over a step whose generated rows are out of scale, so
that the error names the task (:mod:`~armctl.controllers.osc.scale`)."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Generic, Protocol, TypeVar

from armctl._checks import FloatArray
from armctl.controllers.osc.chain import SolverChain
from armctl.controllers.osc.state import ModelState
from armctl.references import Reference


class GeneratedData(Protocol):
    """Generated data of a QP (GeneratedQddData, GeneratedContactData): its outputs at (q, q̇) after :meth:`run`."""

    def run(self, q: FloatArray, qd: FloatArray, t: float, ref: Reference) -> None: ...


#: the generated data of a QP
G = TypeVar("G", bound=GeneratedData)
#: what a step leaves (QddStep, ContactStep)
S = TypeVar("S")


class EliminatedQP(ABC, Generic[G, S]):
    """A QP of the controller with τ eliminated, made once per layout. Subclasses implement :meth:`step` (NumPy)
    and :meth:`_from_generated`."""

    #: the QP's data from generated code, or None: from NumPy (set by the controller)
    generated: G | None

    def run(
        self,
        q: FloatArray,
        qd: FloatArray,
        t: float,
        ref: Reference,
        chain: SolverChain,
        evaluate: Callable[[FloatArray, FloatArray], ModelState],
    ) -> S:
        """The verified optimum at (q, q̇): from the generated data if there are (the code run on (q, q̇) and the
        tasks' targets at t), else, or if the code's rows are out of scale, from ``evaluate(q, qd)``, the
        :class:`ModelState` of the NumPy path. Raises InvalidParameterError for rows out of scale; if the chain
        finds no verified optimum, InfeasibleError naming the conflicting rows or SolverError."""
        gen = self.generated
        if gen is not None:
            gen.run(q, qd, t, ref)
            result = self._from_generated(gen, q, qd, chain)
            if result is not None:
                return result
        return self.step(evaluate(q, qd), t, ref, chain)

    @abstractmethod
    def step(self, state: ModelState, t: float, ref: Reference, chain: SolverChain) -> S:
        """The verified optimum at ``state``, from NumPy."""

    @abstractmethod
    def _from_generated(self, gen: G, q: FloatArray, qd: FloatArray, chain: SolverChain) -> S | None:
        """The verified optimum from the outputs of ``gen``'s last run at (q, q̇); None if its rows are out of
        scale (the NumPy path then takes the step, to name the task)."""
