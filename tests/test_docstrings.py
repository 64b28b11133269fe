"""Every parameter of the public API is documented: for each name in the ``__all__`` of a public module (and
each public method of a public class), the numpydoc ``Parameters`` section (or ``Other Parameters``, or for a
class ``Attributes``) names every parameter of its signature, and names none it does not have. Read with
numpydoc's own parser, as python-control's docstring test does.

Classes are checked on their constructor (the class docstring or ``__init__``'s; a class that inherits its
constructor may leave its parameters to the docstring of the class that defines it) and on the methods they define
or inherit from armctl's own bases; ``*args`` / ``**kwargs`` must be documented under their starred names. A
function that returns something has a ``Returns`` section."""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import warnings
from collections.abc import Callable, Iterator
from typing import Any

import pytest

numpydoc = pytest.importorskip("numpydoc.docscrape", reason="numpydoc is in the test extra")

import armctl  # noqa: E402

#: old import paths kept for one release (they re-export documented names)
DEPRECATED_MODULES = {"armctl.reference", "armctl.dynamics.codegen", "armctl.dynamics.library_cache"}


def _public_modules() -> Iterator[Any]:
    yield armctl
    for info in pkgutil.walk_packages(armctl.__path__, "armctl."):
        if any(part.startswith("_") for part in info.name.split(".")) or info.name in DEPRECATED_MODULES:
            continue
        yield importlib.import_module(info.name)


def _public_names() -> dict[str, Any]:
    """Qualified name → object, for every name in a public module's ``__all__`` defined in armctl (each object
    once, under the first module that lists it)."""
    out: dict[str, Any] = {}
    seen: set[int] = set()
    for module in _public_modules():
        for name in getattr(module, "__all__", ()):
            obj = getattr(module, name)
            if id(obj) in seen or not (getattr(obj, "__module__", None) or "").startswith("armctl"):
                continue
            if not (inspect.isclass(obj) or inspect.isfunction(obj)):
                continue
            seen.add(id(obj))
            out[f"{module.__name__}.{name}"] = obj
    return out


def _cases() -> list[tuple[str, Callable[..., Any], list[Any]]]:
    """(name, callable, docstring owners): each public function, each class's constructor, and each public method
    a class defines or inherits from armctl's own bases (mixins included), each function once."""
    cases: list[tuple[str, Callable[..., Any], list[Any]]] = []
    seen: set[int] = set()

    def add(qual: str, fn: Callable[..., Any], owners: list[Any]) -> None:
        if id(fn) not in seen:
            seen.add(id(fn))
            cases.append((qual, fn, owners))

    for qual, obj in _public_names().items():
        if inspect.isfunction(obj):
            add(qual, obj, [obj])
            continue
        init = obj.__init__
        if init is not object.__init__ and inspect.isfunction(init):
            definer = next(base for base in obj.__mro__ if vars(base).get("__init__") is init)
            cases.append((f"{qual}()", init, [obj, init] + ([definer] if definer is not obj else [])))
        for base in obj.__mro__:
            if not base.__module__.startswith("armctl"):
                continue
            for name, member in vars(base).items():
                fn = member.__func__ if isinstance(member, staticmethod | classmethod) else member
                if not name.startswith("_") and inspect.isfunction(fn):
                    add(f"{qual}.{name}", fn, [fn])
    return cases


def _documented(owner: Any, sections: tuple[str, ...]) -> set[str]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # numpydoc warns about sections it does not know
        doc = numpydoc.NumpyDocString(inspect.getdoc(owner) or "")
    return {n.strip() for section in sections for p in doc[section] for n in p.name.split(",") if n.strip()}


def _signature_names(fn: Callable[..., Any]) -> list[str]:
    names = []
    for p in inspect.signature(fn).parameters.values():
        if p.name in ("self", "cls") or p.name.startswith("_"):
            continue
        stars = {p.VAR_POSITIONAL: "*", p.VAR_KEYWORD: "**"}.get(p.kind, "")
        names.append(stars + p.name)
    return names


CASES = _cases()


def test_the_public_api_is_found() -> None:
    names = {q for q, _, _ in CASES}
    assert {"armctl.Dynamics()", "armctl.simulate", "armctl.RobotModel.from_urdf", "armctl.Dynamics.regressor"} <= names
    assert len(CASES) > 300


def test_an_inherited_constructor_is_read_from_the_class_that_defines_it() -> None:
    """PressScene inherits Scene's constructor: its parameters are read from PressScene's docstring and Scene's."""
    owners = {q: o for q, _, o in CASES}["armctl.scenes.PressScene()"]
    assert owners[0] is armctl.scenes.PressScene and armctl.scenes.Scene in owners
    assert _problems(armctl.scenes.Scene.__init__, owners[:2]) != []  # without Scene's docstring: undocumented


def _problems(fn: Callable[..., Any], owners: list[Any]) -> list[str]:
    """What is wrong with the docstrings of ``fn`` (read from ``owners``): undocumented parameters, documented
    ones it does not have, a missing Returns section."""
    wanted = _signature_names(fn)
    params: set[str] = set()
    for owner in owners:
        params |= _documented(owner, ("Parameters", "Other Parameters"))
    is_class = inspect.isclass(owners[0])
    attributes = set().union(*(_documented(o, ("Attributes",)) for o in owners)) if is_class else set()
    out = []
    missing = [name for name in wanted if name not in params and name not in attributes]
    if missing:
        out.append(f"parameters not documented: {missing}")
    unknown = sorted(params - set(wanted))
    if unknown:
        out.append(f"documents parameters it does not have: {unknown}")
    if not is_class and inspect.signature(fn).return_annotation not in (None, "None", inspect.Signature.empty):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            doc = numpydoc.NumpyDocString(inspect.getdoc(fn) or "")
        if not (doc["Returns"] or doc["Yields"]):
            out.append("returns a value but has no Returns section")
    return out


def _documented_well(x: float, *, scale: float = 1.0) -> float:
    """A function documented as the test wants.

    Parameters
    ----------
    x : float
        A length [m].
    scale : float, optional
        A factor.

    Returns
    -------
    float
        x · scale [m].
    """
    return x * scale


def _documented_badly(x: float, y: float) -> float:
    """Scales x [m].

    Parameters
    ----------
    x : float
        A length [m].
    z : float
        Not a parameter.
    """
    return x * y


def test_the_check_finds_what_is_missing() -> None:
    assert _problems(_documented_well, [_documented_well]) == []
    assert _problems(_documented_badly, [_documented_badly]) == [
        "parameters not documented: ['y']",
        "documents parameters it does not have: ['z']",
        "returns a value but has no Returns section",
    ]


@pytest.mark.parametrize(("qual", "fn", "owners"), [pytest.param(q, f, o, id=q) for q, f, o in CASES])
def test_every_parameter_is_documented(qual: str, fn: Callable[..., Any], owners: list[Any]) -> None:
    problems = _problems(fn, owners)
    assert not problems, f"{qual}: {'; '.join(problems)}"
