"""Parallel-gripper collision model built from named dimensions.

Gripper frame: the closing point at the origin, approach along +z (the fingers point to
+z), closing direction along x (the fingers move along x), y = z x x.

The model is three boxes: two fingers and the base behind them. Fingertips are at
z = +closing_region_height / 2 so that the closing point sits in the middle of the
closing region; each finger is ``finger_depth_m`` long (z), ``finger_width_m`` wide (y),
``finger_thickness_m`` thick (x), its inner face at x = +/- width / 2 where width is the
opening width (open) or the closing width (closed). The base is ``base_width_m`` (x) by
``base_depth_m`` (y) by ``base_height_m`` (z) behind the fingers. The model is symmetric
under a half-turn about z, so both half-turn grasp/push candidates occupy the same volume.

A tool with no fingers (a suction cup alone: clearcli/settings/profiles.py ``tools``)
pushes with the cup and its body: `push_tool_model` gives the model a push uses, the
fingers' for a tool that has them (the same object `gripper_model` gives), else the cup
tool's (`cup_pusher_model`: the cup with its stem, then the body, each a box round its
cylinder), and `GripperModel.push_contact` says which part meets the object.

Another gripper is a TOML file with a [gripper] table (the keys of `GripperSettings`):
pass it with ``--settings FILE`` or load it with `load_gripper_settings`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from clearcli.errors import SettingsError
from clearcli.settings import settings_from_dict
from clearcli.settings.geometry import GripperSettings
from clearcli.settings.suction import SuctionSettings


@dataclass(frozen=True, eq=False)
class GripperBoxes:
    """Axis-aligned boxes in the gripper frame: centres (B, 3) and half sizes (B, 3)."""

    centers: np.ndarray
    half_extents: np.ndarray

    def corners(self) -> np.ndarray:
        """(B, 8, 3) box corners in the gripper frame."""
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
        return self.centers[:, None, :] + signs[None, :, :] * self.half_extents[:, None, :]

    def transformed_corners(self, T_to_gripper: np.ndarray) -> np.ndarray:
        """(B, 8, 3) corners in the frame of ``T_to_gripper``."""
        c = self.corners()
        return c @ T_to_gripper[:3, :3].T + T_to_gripper[:3, 3]


@dataclass(frozen=True)
class PushContact:
    """The part of a tool that meets an object in a push, in the gripper frame (approach
    +z): its lowest point ``tip_z_m`` past the TCP, its half sizes along x and y, and the
    height of the band it meets a face with (m)."""

    tip_z_m: float
    half_x_m: float
    half_y_m: float
    band_m: float


@dataclass(frozen=True, eq=False)
class GripperModel:
    settings: GripperSettings
    open_boxes: GripperBoxes
    closed_boxes: GripperBoxes
    # The open gripper's collision volume: its boxes and the closing region between the
    # fingers (the opening along x, a finger's width along y, the closing region's
    # height along z). Another object in there is squeezed with the target when the
    # fingers close: it blocks the grasp as surely as one the fingers hit on the way down.
    open_collision_boxes: GripperBoxes | None = None
    # What meets the object in a push; None: the closed finger pair (`push_contact`).
    push_part: PushContact | None = None

    @property
    def push_contact(self) -> PushContact:
        """The part that meets the object in a push: the closed finger pair (its
        fingertips, the pair's width along x, a finger's width along y, the closing
        region's height), unless the model says otherwise (a cup tool's cup)."""
        if self.push_part is not None:
            return self.push_part
        s = self.settings
        return PushContact(
            tip_z_m=s.closing_region_height_m / 2.0,
            half_x_m=self.finger_half_extent_along_x(closed=True),
            half_y_m=s.finger_width_m / 2.0,
            band_m=s.closing_region_height_m,
        )

    def collision_boxes(self, closed: bool) -> GripperBoxes:
        """What the collision checks use: the closed gripper, or the open one with its
        closing region."""
        if closed:
            return self.closed_boxes
        return self.open_collision_boxes if self.open_collision_boxes is not None else self.open_boxes

    @property
    def fingertip_z_m(self) -> float:
        """z of the fingertips in the gripper frame (past the closing point)."""
        return self.settings.closing_region_height_m / 2.0

    def finger_half_extent_along_x(self, closed: bool = True) -> float:
        """Half size of the finger pair along the closing direction."""
        s = self.settings
        width = s.closing_width_m if closed else s.opening_width_m
        return width / 2.0 + s.finger_thickness_m

    def boxes(self, closed: bool) -> GripperBoxes:
        return self.closed_boxes if closed else self.open_boxes

    def mesh(self, closed: bool, T: np.ndarray | None = None) -> Any:
        """trimesh.Trimesh of the gripper (open or closed), optionally moved by T."""
        import trimesh

        boxes = self.boxes(closed)
        parts = []
        for center, half in zip(boxes.centers, boxes.half_extents):
            transform = np.eye(4)
            transform[:3, 3] = center
            parts.append(trimesh.creation.box(extents=2.0 * half, transform=transform))
        mesh = trimesh.util.concatenate(parts)
        if T is not None:
            mesh.apply_transform(T)
        return mesh

    def fcl_objects(self, closed: bool, T: np.ndarray) -> list[Any]:
        """python-fcl collision objects of the gripper at pose T (frame of T)."""
        import fcl

        boxes = self.collision_boxes(closed)
        R = T[:3, :3]
        # the box shapes are shared by every pose (fcl objects only hold a reference)
        shapes = _fcl_boxes(tuple(map(tuple, boxes.half_extents.tolist())))
        return [
            fcl.CollisionObject(shape, fcl.Transform(R, R @ center + T[:3, 3]))
            for shape, center in zip(shapes, boxes.centers)
        ]


@lru_cache(maxsize=16)
def _fcl_boxes(half_extents: tuple[tuple[float, float, float], ...]) -> tuple[Any, ...]:
    import fcl

    return tuple(fcl.Box(*(2.0 * np.asarray(h))) for h in half_extents)


def _boxes(s: GripperSettings, width: float) -> GripperBoxes:
    tip = s.closing_region_height_m / 2.0
    finger_z = tip - s.finger_depth_m / 2.0
    finger_x = width / 2.0 + s.finger_thickness_m / 2.0
    base_z = tip - s.finger_depth_m - s.base_height_m / 2.0
    centers = np.array([[finger_x, 0.0, finger_z], [-finger_x, 0.0, finger_z], [0.0, 0.0, base_z]])
    finger_half = [s.finger_thickness_m / 2.0, s.finger_width_m / 2.0, s.finger_depth_m / 2.0]
    base_half = [s.base_width_m / 2.0, s.base_depth_m / 2.0, s.base_height_m / 2.0]
    half = np.array([finger_half, finger_half, base_half])
    return GripperBoxes(centers=centers, half_extents=half)


def check_gripper_settings(s: GripperSettings, where: str = "[gripper]") -> None:
    """Reject dimensions that cannot describe a gripper (one-line SettingsError)."""
    for f in dataclasses.fields(s):
        value = getattr(s, f.name)
        if f.name == "closed_gap_m":  # a gripper that closes fully has none
            if not value >= 0.0:
                raise SettingsError(f"settings: {where} {f.name} must be zero or positive, got {value!r}")
            continue
        if not value > 0.0:
            raise SettingsError(f"settings: {where} {f.name} must be positive, got {value!r}")
    if s.closing_width_m > s.opening_width_m:
        raise SettingsError(
            f"settings: {where} closing_width_m ({s.closing_width_m}) exceeds opening_width_m ({s.opening_width_m})"
        )


def push_contact_halves(
    s: GripperSettings | GripperModel, closing_dir: np.ndarray, push_dir: np.ndarray
) -> tuple[float, float]:
    """(half size along the push, half size across it) of what meets the object, the
    gripper's x axis being ``closing_dir``: for fingers (``s`` the settings, or a model
    of them) the closed pair (closing width and both fingers' thickness) along the
    closing direction, a finger's width across it; for a model with its own push part
    (`cup_pusher_model`), that part's half sizes."""
    x = np.asarray(closing_dir, dtype=float)
    d = np.asarray(push_dir, dtype=float)
    cos = abs(float(x @ d)) / max(float(np.linalg.norm(x) * np.linalg.norm(d)), 1e-12)
    if isinstance(s, GripperModel):
        part = s.push_contact
        along_x, along_y = part.half_x_m, part.half_y_m
    else:
        along_x, along_y = s.closing_width_m / 2.0 + s.finger_thickness_m, s.finger_width_m / 2.0
    if cos >= np.sqrt(0.5):  # closing along the push
        return along_x, along_y
    return along_y, along_x


def gripper_model(s: GripperSettings | None = None) -> GripperModel:
    """The open and closed gripper models for the given dimensions (default: IRI).
    One model per settings value, built once (its arrays are read-only)."""
    return _gripper_model(s or GripperSettings())


@lru_cache(maxsize=64)
def _gripper_model(s: GripperSettings) -> GripperModel:
    check_gripper_settings(s)
    open_boxes = _boxes(s, s.opening_width_m)
    region = GripperBoxes(
        centers=np.vstack([open_boxes.centers, [[0.0, 0.0, 0.0]]]),
        half_extents=np.vstack(
            [
                open_boxes.half_extents,
                [[s.opening_width_m / 2.0, s.finger_width_m / 2.0, s.closing_region_height_m / 2.0]],
            ]
        ),
    )
    model = GripperModel(
        settings=s, open_boxes=open_boxes, closed_boxes=_boxes(s, s.closing_width_m), open_collision_boxes=region
    )
    for b in (model.open_boxes, model.closed_boxes, region):
        b.centers.setflags(write=False)
        b.half_extents.setflags(write=False)
    return model


def push_tool_model(g: GripperSettings, suction: SuctionSettings, tools: tuple[str, ...]) -> GripperModel:
    """The model a push uses: the fingers' (`gripper_model`, the very same object) when
    the tool has fingers, else the cup tool's (`cup_pusher_model`)."""
    if "fingers" in tools or "cup" not in tools:
        return gripper_model(g)
    return cup_pusher_model(g, suction)


@lru_cache(maxsize=16)
def cup_pusher_model(g: GripperSettings, s: SuctionSettings) -> GripperModel:
    """A tool with a cup and no fingers (an EPick) as it pushes: pointing down, the lip
    ``[push] fingertips_above_table_m`` above the table like fingertips, the cup and its
    stem (the cup's diameter, ``stem_length_m`` long, from the lip ``lip_past_tcp_m`` past
    the TCP) meeting the object's face, the body behind (``body_radius_m``,
    ``body_length_m``) meeting what is taller. Each cylinder is the box round it, so that
    the collision checks err on the safe side as the fingers' boxes do; open and closed
    are one shape. ``g`` (the profile's [gripper], whose fingers the tool does not have)
    only rides along for what reads a model's settings."""
    check_gripper_settings(g)
    r_cup = s.cup_diameter_m / 2.0
    stem = max(s.stem_length_m, 1e-3)  # a cup right on its body still has its lip
    lip = s.lip_past_tcp_m
    centres = np.array([[0.0, 0.0, lip - stem / 2.0], [0.0, 0.0, lip - stem - s.body_length_m / 2.0]])
    half = np.array([[r_cup, r_cup, stem / 2.0], [s.body_radius_m, s.body_radius_m, s.body_length_m / 2.0]])
    boxes = GripperBoxes(centers=centres, half_extents=half)
    boxes.centers.setflags(write=False)
    boxes.half_extents.setflags(write=False)
    return GripperModel(
        settings=g,
        open_boxes=boxes,
        closed_boxes=boxes,
        open_collision_boxes=boxes,
        push_part=PushContact(tip_z_m=lip, half_x_m=r_cup, half_y_m=r_cup, band_m=stem),
    )


def load_gripper_settings(path: Path) -> GripperSettings:
    """GripperSettings from a TOML file: a [gripper] table, or the keys at top level.
    Missing keys keep the IRI defaults; unknown keys are an error."""
    import tomllib  # noqa: PLC0415  (only a gripper file needs it: ~1.5 ms of every cold plan)

    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SettingsError(f"{path}: gripper file not found") from None
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise SettingsError(f"{path}: cannot read gripper TOML ({exc})") from None
    table = data.get("gripper", data)
    if not isinstance(table, dict):
        raise SettingsError(f"{path}: [gripper] must be a table of keys")

    s = settings_from_dict({"gripper": table}).gripper
    check_gripper_settings(s, where=f"{path} [gripper]")
    return s
