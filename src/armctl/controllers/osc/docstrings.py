"""Docstring sections that several functions and classes of the package share, written once.

A docstring holds a mark, a line of its own; :func:`fill` replaces that line with the section, indented as the
mark, when the function or class is defined (:func:`shared_section` for a function, at its definition; a class,
from ``__init_subclass__``). ``help()``, ``inspect.getdoc`` and the API pages read the filled docstring.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

F = TypeVar("F", bound=Callable[..., Any])

#: the mark of :data:`STEP_PARAMETERS` in a docstring
STEP_MARK = "(the Parameters section of a control step's state, t, ref)"

#: the parameters of a function evaluated at one control step: (state, t, ref)
STEP_PARAMETERS = """Parameters
----------
state : ModelState
    The model terms at the measured (q, q̇).
t : float
    Time [s].
ref : Reference
    The controller's joint reference at t."""


def fill(doc: str | None, mark: str, section: str) -> str | None:
    """``doc`` with its line ``mark`` replaced by ``section`` (lines indented as the mark's); ``doc`` unchanged
    if it has no such line (or is None: docstrings stripped by ``python -OO``).

    Parameters
    ----------
    doc : str or None
        A docstring.
    mark : str
        The text of the line to replace.
    section : str
        What replaces it, its lines not indented.

    Returns
    -------
    str or None
        The docstring.
    """
    if doc is None or mark not in doc:
        return doc
    indent = doc[: doc.index(mark)].rsplit("\n", 1)[-1]
    return doc.replace(mark, section.replace("\n", "\n" + indent))


def shared_section(mark: str, section: str) -> Callable[[F], F]:
    """A decorator that fills the line ``mark`` of a function's docstring with ``section`` (see :func:`fill`); it
    returns the function itself.

    Parameters
    ----------
    mark : str
        The text of the line to replace.
    section : str
        What replaces it.

    Returns
    -------
    callable
        The decorator.
    """

    def decorate(fn: F) -> F:
        fn.__doc__ = fill(fn.__doc__, mark, section)
        return fn

    return decorate


#: fills :data:`STEP_MARK` with :data:`STEP_PARAMETERS`
step_parameters = shared_section(STEP_MARK, STEP_PARAMETERS)
