"""The C compiler that builds generated code: ``$CC`` if it is set, else ``cc`` or ``gcc`` on the PATH."""

from __future__ import annotations

import os
import shutil

from armctl.errors import BackendError

#: how to get a C compiler, for the messages of what falls back or fails without one
INSTALL_A_COMPILER = (
    "install a C compiler (Debian/Ubuntu: sudo apt install gcc; Fedora: sudo dnf install gcc; macOS: "
    "xcode-select --install; conda: conda install -c conda-forge c-compiler) or point $CC at one"
)


def compiler() -> str | None:
    """The C compiler that builds generated code.

    Returns
    -------
    str or None
        The path of ``$CC`` if it is set (None if it is not found), else of ``cc`` or ``gcc`` on the PATH (None if
        neither is).
    """
    cc = os.environ.get("CC")
    if cc:
        return shutil.which(cc)
    return shutil.which("cc") or shutil.which("gcc")


def missing() -> str:
    """Why no compiler was found, in words: ``$CC`` names no program, or there is no cc or gcc on the PATH."""
    asked = os.environ.get("CC")
    return f"$CC = {asked!r} is not a program on the PATH" if asked else "no cc or gcc on the PATH"


def required() -> str:
    """The compiler's path; raises :class:`~armctl.errors.BackendError` (naming ``$CC`` and the way out) if there
    is none."""
    cc = compiler()
    if cc is None:
        asked = os.environ.get("CC")
        raise BackendError(
            (f"$CC = {asked!r} is not a program on the PATH: " if asked else "")
            + "compiling generated code needs a C compiler (cc or gcc on PATH, or $CC): "
            + INSTALL_A_COMPILER
            + ", or do without compiled code (compile=False)",
            value=asked,
        )
    return cc
