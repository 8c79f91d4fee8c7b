"""The movable joints of a URDF in chain order, read with the standard library (no
Pinocchio: the plan's robot block names them without loading a model)."""

from __future__ import annotations

import functools
from pathlib import Path


@functools.cache
def joint_names(urdf: Path) -> tuple[str, ...]:
    """Names of the revolute/continuous/prismatic joints, from the root down the chain."""
    import xml.etree.ElementTree as ET

    root = ET.parse(urdf).getroot()
    joints = [j for j in root.iter("joint") if j.get("type") in ("revolute", "continuous", "prismatic")]
    by_parent = {}
    for j in root.iter("joint"):
        by_parent.setdefault(j.find("parent").get("link"), []).append(j)  # type: ignore[union-attr]
    children = {j.find("child").get("link") for j in root.iter("joint")}  # type: ignore[union-attr]
    roots = [link.get("name") for link in root.iter("link") if link.get("name") not in children]
    order: list[str] = []
    stack = list(roots)
    while stack:  # depth first along the chain
        link = stack.pop()
        for j in by_parent.get(link, []):
            if j in joints:
                order.append(str(j.get("name")))
            stack.append(j.find("child").get("link"))  # type: ignore[union-attr]
    return tuple(order)
