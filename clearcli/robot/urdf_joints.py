"""The movable joints of a URDF in chain order, read with the standard library (no
Pinocchio: the plan's robot block names them without loading a model), and a user's
URDF checked the same way before Pinocchio reads it (`checked_urdf`)."""

from __future__ import annotations

import functools
import math
import xml.etree.ElementTree as ET
from pathlib import Path

from clearcli.errors import SettingsError


def _end_link(joint: ET.Element, end: str) -> str | None:
    """The link a joint's <parent> or <child> names (a URDF joint has both)."""
    element = joint.find(end)
    assert element is not None, f"joint {joint.get('name')!r} has no <{end}>"
    return element.get("link")


@functools.cache
def joint_names(urdf: Path) -> tuple[str, ...]:
    """Names of the revolute/continuous/prismatic joints, from the root down the chain."""
    root = ET.parse(urdf).getroot()
    joints = [j for j in root.iter("joint") if j.get("type") in ("revolute", "continuous", "prismatic")]
    by_parent: dict[str | None, list[ET.Element]] = {}
    for j in root.iter("joint"):
        by_parent.setdefault(_end_link(j, "parent"), []).append(j)
    children = {_end_link(j, "child") for j in root.iter("joint")}
    roots = [link.get("name") for link in root.iter("link") if link.get("name") not in children]
    order: list[str] = []
    stack = list(roots)
    while stack:  # depth first along the chain
        link = stack.pop()
        for j in by_parent.get(link, []):
            if j in joints:
                order.append(str(j.get("name")))
            stack.append(_end_link(j, "child"))
    return tuple(order)


# A continuous joint (a URDF gives it no limits) is read as a revolute one over this
# range (rad): two turns, as the UR arms' own descriptions limit theirs, so that a motion
# can cross +-pi without turning back a whole turn; every angle of the joint lies in it.
CONTINUOUS_RANGE_RAD = (-2.0 * math.pi, 2.0 * math.pi)
# an axis shorter than this has no direction (Pinocchio divides by its length: NaN poses)
_MIN_AXIS_LENGTH = 1e-9
# an origin farther than this from its parent link is a unit mistake (millimetres given
# as metres) or a corrupt file: the largest industrial arms reach about 4 m
_MAX_OFFSET_M = 100.0
# The numbers a link's or a joint's elements carry (attribute, how many): urdfdom refuses
# NaN and infinities there with its reason on stderr only, and takes lower > upper and a
# zero axis silently; each is named here instead.
_NUMBERS: dict[str, tuple[tuple[str, int], ...]] = {
    "origin": (("xyz", 3), ("rpy", 3)),
    "axis": (("xyz", 3),),
    "limit": (("lower", 1), ("upper", 1), ("effort", 1), ("velocity", 1)),
    "mass": (("value", 1),),
    "box": (("size", 3),),
    "cylinder": (("radius", 1), ("length", 1)),
    "capsule": (("radius", 1), ("length", 1)),
    "sphere": (("radius", 1),),
    "mesh": (("scale", 3),),
}


def checked_urdf(urdf: Path) -> str:
    """The URDF's text for Pinocchio (``buildModelFromXML``), checked with the standard
    library first: a file that cannot be read, is not XML or not a <robot>; a number of a
    link or a joint (origins, axes, limits, shapes) that is not finite or not as many as
    it should be; a zero axis; a revolute or prismatic joint without limits or with its
    lower limit above its upper. Each is a SettingsError naming the file and the joint or
    link (one line, exit 3, before any frame is read). Continuous joints come back as
    revolute ones over CONTINUOUS_RANGE_RAD (the generic IK needs bounds to draw its
    starts from and to clip to)."""
    try:
        is_dir, is_file = urdf.is_dir(), urdf.is_file()
    except OSError as exc:  # a name too long for the file system, a permission on the way
        raise SettingsError(f"{urdf}: URDF file cannot be read ({exc.strerror or exc}; [robot] urdf)") from None
    if is_dir:
        raise SettingsError(f"{urdf}: a folder, not a URDF file ([robot] urdf)")
    if not is_file:
        raise SettingsError(f"{urdf}: URDF file not found ([robot] urdf)")
    try:
        data = urdf.read_bytes()
    except OSError as exc:
        raise SettingsError(f"{urdf}: URDF file cannot be read ({exc.strerror or exc})") from None
    try:
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        raise SettingsError(f"{urdf}: not a URDF (not well-formed XML: {exc})") from None
    if root.tag != "robot":
        raise SettingsError(f"{urdf}: not a URDF (its root element is <{root.tag}>, not <robot>)")

    def numbers(owner: ET.Element, element: ET.Element, attribute: str, count: int) -> list[float] | None:
        """The attribute's numbers (None when absent); not finite or not ``count`` of them
        is one line naming the link or joint."""
        raw = element.get(attribute)
        if raw is None:
            return None
        try:
            values = [float(v) for v in raw.split()]
        except ValueError:
            values = []
        if len(values) != count or not all(math.isfinite(v) for v in values):
            what = "a finite number" if count == 1 else f"{count} finite numbers"
            raise SettingsError(
                f'{urdf}: {owner.tag} {owner.get("name")!r}: <{element.tag} {attribute}="{raw}"> must be {what}'
            )
        return values

    rewritten = False
    for owner in root:  # a <transmission>'s <joint> names one; only the robot's own are read
        if owner.tag not in ("link", "joint"):
            continue
        for element in owner.iter():
            for attribute, count in _NUMBERS.get(element.tag, ()):
                values = numbers(owner, element, attribute, count)
                if element.tag == "origin" and attribute == "xyz" and values and max(map(abs, values)) > _MAX_OFFSET_M:
                    # no arm has such a link, and its squares overflow the kinematics' floats
                    raise SettingsError(
                        f'{urdf}: {owner.tag} {owner.get("name")!r}: <origin xyz="{element.get("xyz")}"> is more than '
                        f"{_MAX_OFFSET_M:g} m from its parent; give the offset in metres"
                    )
        if owner.tag != "joint":
            continue
        name, kind = owner.get("name"), owner.get("type")
        axis = owner.find("axis")
        xyz = numbers(owner, axis, "xyz", 3) if axis is not None else None
        if kind in ("revolute", "continuous", "prismatic") and xyz is not None and math.hypot(*xyz) < _MIN_AXIS_LENGTH:
            assert axis is not None  # xyz was read from it
            raise SettingsError(
                f'{urdf}: joint {name!r}: <axis xyz="{axis.get("xyz")}"> has no direction; give the joint\'s axis'
            )
        limit = owner.find("limit")
        if kind in ("revolute", "prismatic"):
            unit = "rad" if kind == "revolute" else "m"
            if limit is None:
                raise SettingsError(
                    f"{urdf}: joint {name!r} ({kind}) has no <limit>; give its lower and upper limits ({unit})"
                    + (", or make it continuous" if kind == "revolute" else "")
                )
            # URDF's defaults for an absent bound
            lower, upper = (
                (numbers(owner, limit, "lower", 1) or [0.0])[0],
                (numbers(owner, limit, "upper", 1) or [0.0])[0],
            )
            if lower > upper:
                raise SettingsError(
                    f"{urdf}: joint {name!r}: its lower limit {lower:g} is above its upper limit {upper:g} ({unit}); "
                    "swap them"
                )
        elif kind == "continuous":
            owner.set("type", "revolute")
            if limit is None:
                limit = ET.SubElement(owner, "limit")
            limit.set("lower", repr(CONTINUOUS_RANGE_RAD[0]))
            limit.set("upper", repr(CONTINUOUS_RANGE_RAD[1]))
            for required in ("effort", "velocity"):  # urdfdom wants both on a revolute's limit
                limit.set(required, limit.get(required, "0"))
            rewritten = True
    if not rewritten:
        try:
            return data.decode("utf-8")
        except UnicodeDecodeError:  # another encoding, declared in the file: ElementTree read it
            pass
    return ET.tostring(root, encoding="unicode")
