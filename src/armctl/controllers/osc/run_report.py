"""`RunReport`: a controller that counts what went wrong over a run and reports it once, at the run's end."""

from __future__ import annotations

import warnings
from abc import ABC, abstractmethod
from typing import ClassVar


class RunReport(ABC):
    """What :class:`~armctl.controllers.OperationalSpaceQP` and :class:`~armctl.controllers.ClosedFormOSC` share:
    counts kept over a run, a summary of them in words (:meth:`run_summary`), and :meth:`end_run`, which warns
    once with it and starts counting afresh. A subclass names its warning (``run_warning``) and implements
    :meth:`run_summary` and :meth:`_forget_run`."""

    #: the warning :meth:`end_run` gives the summary with
    run_warning: ClassVar[type[Warning]]

    @abstractmethod
    def run_summary(self) -> str | None:
        """What the controller had to do since :meth:`reset` (or the last :meth:`end_run`), in words.

        Returns
        -------
        str or None
            The summary; None if there is nothing to report.
        """

    @abstractmethod
    def _forget_run(self) -> None:
        """Start counting afresh (what :meth:`end_run` and ``reset`` forget)."""

    def end_run(self) -> str | None:
        """End of a run: warn once with :meth:`run_summary` if there is anything to report, and start counting
        afresh. :func:`armctl.sim.simulate` calls it after the last step; call it after a loop of your own.

        Returns
        -------
        str or None
            The summary (None if there was nothing to report).

        Warns
        -----
        SolverWarning, SingularityWarning
            With the summary, if it is not None: the controller's ``run_warning`` (SolverWarning from
            :class:`~armctl.controllers.OperationalSpaceQP`, SingularityWarning from
            :class:`~armctl.controllers.ClosedFormOSC`).
        """
        msg = self.run_summary()
        if msg is not None:
            warnings.warn(msg, self.run_warning, stacklevel=2)
        self._forget_run()
        return msg
