"""Generated C code: the compile policy, the C compiler, and the on-disk cache of compiled libraries.

The layer under :mod:`armctl.dynamics` that every user of generated code shares (the compiled dynamics, the
simulator's generated step, the OSC's generated QP data); it imports nothing of armctl but its errors.

* :mod:`armctl.codegen.policy`: ``compile="auto" | True | False``, one check (:func:`compile_mode`) and one
  fallback warning (:class:`Fallback`);
* :mod:`armctl.codegen.toolchain`: which C compiler builds the code (``$CC``, ``cc``, ``gcc``);
* :mod:`armctl.codegen.library`: CasADi functions compiled once and cached on disk, then loaded (imports CasADi);
* :mod:`armctl.codegen.library_cache`: why a cached library can be trusted (its record, key, build lock).
"""

from armctl.codegen.policy import COMPILE_OPTIONS, CompileMode, Fallback, compile_mode
from armctl.codegen.toolchain import compiler

__all__ = ["COMPILE_OPTIONS", "CompileMode", "Fallback", "compile_mode", "compiler"]
