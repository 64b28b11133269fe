"""The compile policy: whether generated C code is used, read the same way by every user of it.

``compile`` takes three values, with one meaning wherever it appears (``Dynamics(compile=)``,
``simulate(compile=)``, ``OperationalSpaceQP(compile=)``):

* ``True``: the generated code, or a :class:`~armctl.errors.BackendError` saying why it cannot be built;
* ``False``: no generated code (the NumPy / Pinocchio / Python path, with the same results);
* ``"auto"``: the generated code wherever it can be built (or is cached); where it cannot, the slower path,
  with one :class:`~armctl.errors.PerformanceWarning` per process and cause saying why and how to get it.

A NumPy boolean (``np.True_``) is read as the bool it holds; anything else (``"yes"``, ``1``, ``None``) is
refused by :func:`compile_mode` with an :class:`~armctl.errors.InvalidParameterError` listing the three values.
Each user of generated code declares once what it falls back to (a :class:`Fallback`), and warns through it.
"""

from __future__ import annotations

import threading
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal, TypeVar

import numpy as np

from armctl.codegen.toolchain import INSTALL_A_COMPILER, compiler, missing
from armctl.errors import BackendError, InvalidParameterError, PerformanceWarning

T = TypeVar("T")
#: a value of ``compile``
CompileMode = bool | Literal["auto"]
#: the values of ``compile``
COMPILE_OPTIONS: tuple[CompileMode, ...] = ("auto", True, False)


def compile_mode(value: object) -> CompileMode:
    """``value`` checked as a value of ``compile``: ``"auto"``, True or False (a NumPy boolean as its bool).

    Parameters
    ----------
    value : object
        What was given as ``compile``.

    Returns
    -------
    bool or "auto"

    Raises
    ------
    InvalidParameterError
        ``value`` is anything else (text such as ``"False"`` or ``"yes"``, 1, None), naming the valid values.
    """
    if isinstance(value, bool | np.bool_):
        return bool(value)
    if isinstance(value, str) and value == "auto":
        return "auto"
    raise InvalidParameterError(
        f"compile must be True (generated code, or an error), False (no generated code) or 'auto' (generated code "
        f"where it can be built, else the slower path with a PerformanceWarning), got {value!r}",
        value=value,
    )


def check_cache_dir(cache_dir: object, mode: CompileMode) -> None:
    """Refuse a ``cache_dir`` given with ``compile=False`` (it would be ignored: nothing is compiled).

    Raises
    ------
    InvalidParameterError
        ``cache_dir`` is not None and ``mode`` is False.
    """
    if cache_dir is not None and mode is False:
        raise InvalidParameterError(
            f"cache_dir={cache_dir!r} is where compiled code is kept: pass compile=True or 'auto' too, or no cache_dir",
            value=cache_dir,
        )


@dataclass(frozen=True)
class Fallback:
    """What one user of generated code runs without it, declared once by that user.

    Parameters
    ----------
    code : str
        The generated code, as the warning names it (``"the simulator's generated step"``).
    instead : str
        What runs in its place, with the same results (``"the Python step"``).
    cost : str
        How much slower that is (``"several times slower"``).
    """

    code: str
    instead: str
    cost: str
    #: the causes warned about in this process (one warning each)
    _warned: set[str] = field(default_factory=set, init=False, repr=False, compare=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, init=False, repr=False, compare=False)

    def warn(self, exc: BaseException, stacklevel: int = 2) -> str:
        """Warn (:class:`~armctl.errors.PerformanceWarning`, once per process and cause) that the generated code
        could not be used because of ``exc``, and what runs instead. The cause is the missing compiler when
        there is none, else ``exc`` itself.

        Parameters
        ----------
        exc : BaseException
            Why the generated code could not be built or loaded.
        stacklevel : int
            As for :func:`warnings.warn`, counted from the caller of this method.

        Returns
        -------
        str
            ``exc`` in words (for a result's ``info``).
        """
        reason = str(exc) if isinstance(exc, BackendError) else f"{type(exc).__name__}: {exc}"
        if compiler() is None:
            cause = "no compiler"
            text = (
                f"no C compiler was found ({missing()}): {self.code} cannot be built, so {self.instead} runs "
                f"instead, {self.cost}. To get it, {INSTALL_A_COMPILER}; compile=False chooses {self.instead} "
                "without this warning"
            )
        else:
            cause = reason
            text = f"{self.code} could not be built ({reason}); {self.instead} runs instead, {self.cost}"
        with self._lock:
            first = cause not in self._warned
            self._warned.add(cause)
        if first:
            warnings.warn(text, PerformanceWarning, stacklevel=stacklevel + 1)
        return reason

    def attempt(self, make: Callable[[], T], mode: CompileMode, stacklevel: int = 2) -> T | None:
        """``make()`` (what builds or loads the generated code) under the compile policy ``mode``.

        Parameters
        ----------
        make : callable
            () → the generated code; it raises if the code cannot be built.
        mode : bool or "auto"
            The checked value of ``compile`` (see :func:`compile_mode`).
        stacklevel : int
            As for :func:`warnings.warn`, counted from the caller of this method.

        Returns
        -------
        object or None
            What ``make`` returned; None with ``mode`` False (nothing is built), or with ``"auto"`` where it
            raised (after :meth:`warn`).

        Raises
        ------
        Exception
            What ``make`` raised, with ``mode`` True.
        """
        if mode is False:
            return None
        try:
            return make()
        except Exception as exc:  # "auto" falls back on any failure to build: the slower path gives the same results
            if mode is True:
                raise
            self.warn(exc, stacklevel + 1)
            return None

    def reset(self) -> None:
        """Forget the causes warned about: the next one warns again (a test's fresh process)."""
        with self._lock:
            self._warned.clear()
