"""Evaluating a CasADi function in place: its ``buffer()`` reads its inputs from, and writes its outputs into,
NumPy arrays bound once by their memory, with no copies at each call.

Typed here once: CasADi's stubs give ``FunctionBuffer.set_arg`` / ``set_res`` the C++ (pointer, size) pair where
Python passes one memoryview, and NumPy declares its arrays' buffer protocol to type checkers only from Python
3.12 on.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

#: ``memoryview`` of a contiguous float64 array, to bind with ``buf.set_arg(i, view(a))`` (the array must outlive
#: the binding: the buffer keeps its address, not the array)
view: Callable[[Any], memoryview] = memoryview


def buffer_of(fn: Any) -> tuple[Any, Callable[[], None]]:
    """``fn.buffer()``: the function's buffer (``set_arg(i, view(a))``, ``set_res(i, view(out))``) and the call
    that evaluates it."""
    buf, run = fn.buffer()
    return buf, run
