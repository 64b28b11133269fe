"""Checking a URDF file before Pinocchio's parser (urdfdom) reads it.

urdfdom reports what it cannot read on the standard error stream only, and then either loads the model without
the part it could not read (an ``<inertial>`` with ``mass value="heavy"`` or ``ixx="nan"`` leaves its link
massless) or refuses the whole file with "does not contain a valid URDF model" (duplicate joint names, a number
it cannot parse in a joint). These checks read the XML first and name the link or joint and the attribute:

* the XML is well formed and its root is ``<robot>``;
* link and joint names are present and unique, and none is ``universe`` (Pinocchio's name for its world frame:
  a link of that name is dropped from the frames);
* joints have a known type and name parent and child links that exist; a revolute or prismatic joint has a
  ``<limit>`` with ``effort`` and ``velocity``;
* every number urdfdom reads from a link's ``<inertial>`` and a joint's ``<origin>``, ``<axis>``, ``<limit>``,
  ``<dynamics>``, ``<mimic>``, ``<calibration>`` and ``<safety_controller>`` is a finite decimal number as
  urdfdom parses it (C++ stream extraction: leading blanks, no trailing ones; no ``nan``, ``inf`` or ``1_000``),
  three of them where a vector is meant; an ``<inertial>`` has a ``<mass>`` and an ``<inertia>`` with all six
  entries.

``<mimic>`` joints are returned (joint → the joint it follows): the loader refuses those it is not told to lock.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from collections import Counter

from armctl.errors import ModelLoadError

#: urdfdom's joint types
JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
#: a number as C++ stream extraction (urdfdom's strToDouble) reads it whole
_NUMBER = re.compile(r"\s*[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")
_INERTIA = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
#: the numeric attributes of a joint's elements: element → (attributes holding one number, holding three)
_JOINT_NUMBERS = {
    "origin": ((), ("xyz", "rpy")),
    "axis": ((), ("xyz",)),
    "limit": (("lower", "upper", "effort", "velocity"), ()),
    "dynamics": (("damping", "friction"), ()),
    "mimic": (("multiplier", "offset"), ()),
    "calibration": (("rising", "falling"), ()),
    "safety_controller": (("soft_lower_limit", "soft_upper_limit", "k_position", "k_velocity"), ()),
}


def _number(text: str) -> bool:
    if _NUMBER.fullmatch(text) is None:
        return False
    return math.isfinite(float(text))


def _numbers(owner: str, element: ET.Element, single: tuple[str, ...], triple: tuple[str, ...]) -> list[str]:
    """The problems of an element's numeric attributes (absent ones are urdfdom's defaults)."""
    out = []
    for attr in single:
        text = element.get(attr)
        if text is not None and not _number(text):
            out.append(f"{owner}: <{element.tag} {attr}={text!r}> is not a finite number")
    for attr in triple:
        text = element.get(attr)
        if text is not None and (len(text.split()) != 3 or not all(map(_number, text.split()))):
            out.append(f"{owner}: <{element.tag} {attr}={text!r}> is not three finite numbers")
    return out


def _inertial(owner: str, inertial: ET.Element) -> list[str]:
    out = []
    for origin in inertial.findall("origin"):
        out += _numbers(owner, origin, (), ("xyz", "rpy"))
    mass = inertial.find("mass")
    if mass is None or mass.get("value") is None:
        out.append(f'{owner}: its <inertial> has no <mass value="..."/>')
    else:
        out += _numbers(owner, mass, ("value",), ())
    inertia = inertial.find("inertia")
    missing = _INERTIA if inertia is None else tuple(a for a in _INERTIA if inertia.get(a) is None)
    if missing:
        out.append(f"{owner}: its <inertial> has no <inertia> entries {', '.join(missing)}")
    if inertia is not None:
        out += _numbers(owner, inertia, tuple(a for a in _INERTIA if a not in missing), ())
    return out


def _names(kind: str, elements: list[ET.Element]) -> tuple[list[str], list[str]]:
    """(names, problems) of the links or joints."""
    names = [e.get("name") for e in elements]
    problems = [f"a <{kind}> without a name" for n in names if not n]
    named = [n for n in names if n]
    problems += [
        f"{kind} name {n!r} is used by {c} {kind}s: {kind} names must be unique"
        for n, c in Counter(named).items()
        if c > 1
    ]
    if "universe" in named:
        problems.append(
            f"{kind} {'universe'!r}: 'universe' is Pinocchio's name for its world frame (armctl calls it 'world'), "
            f"so this {kind} would be lost; rename it"
        )
    return named, problems


def check_urdf(path: str) -> dict[str, str]:
    """Check the URDF file at ``path`` (see the module); return its ``<mimic>`` joints (joint → followed joint).
    Raises :class:`~armctl.errors.ModelLoadError` listing every problem found, each naming its link or joint."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise ModelLoadError(f"cannot read URDF {path!r}: not well-formed XML ({e})", value=path) from None
    if root.tag != "robot":
        raise ModelLoadError(f"cannot read URDF {path!r}: the root element is <{root.tag}>, not <robot>", value=path)
    links, joints = root.findall("link"), root.findall("joint")
    link_names, problems = _names("link", links)
    _, joint_problems = _names("joint", joints)
    problems += joint_problems
    for link in links:
        owner = f"link {link.get('name')!r}"
        for inertial in link.findall("inertial"):
            problems += _inertial(owner, inertial)
    known = set(link_names)
    mimic: dict[str, str] = {}
    for joint in joints:
        name = joint.get("name")
        owner = f"joint {name!r}"
        kind = joint.get("type")
        if kind not in JOINT_TYPES:
            problems.append(f"{owner}: type {kind!r} is not one of {', '.join(JOINT_TYPES)}")
        for end in ("parent", "child"):
            element = joint.find(end)
            linked = None if element is None else element.get("link")
            if linked is None:
                problems.append(f'{owner}: no <{end} link="..."/>')
            elif linked not in known:
                problems.append(f"{owner}: its {end} link {linked!r} is not a link of the file")
        for tag, (single, triple) in _JOINT_NUMBERS.items():
            for element in joint.findall(tag):
                problems += _numbers(owner, element, single, triple)
        limit = joint.find("limit")
        if kind in ("revolute", "prismatic") and (
            limit is None or limit.get("effort") is None or limit.get("velocity") is None
        ):
            problems.append(f'{owner}: a {kind} joint needs <limit effort="..." velocity="..."/>')
        follows = joint.find("mimic")
        if follows is not None and name:
            mimic[name] = str(follows.get("joint"))
    if problems:
        shown = "; ".join(problems[:20]) + (f"; … ({len(problems) - 20} more)" if len(problems) > 20 else "")
        raise ModelLoadError(f"cannot read URDF {path!r}: {shown}", value=path)
    return mimic
