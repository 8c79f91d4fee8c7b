"""The settings tree: one registered section per stage, read from TOML and `--set`.

`Settings` holds every section; `SECTIONS` (name -> class) is the registry, in the order
`clear settings` prints them. A section's defaults and ranges live in its class only
(clearcli/settings/<area>.py). Loading order: defaults, then `--settings FILE`, then each
`--set section.key=value`, then a command's own flags (aliases of `--set`); every value
is checked as its section is built (fields.py), before any frame is read. Unknown
sections or keys are an error: a typo must not be silently ignored.
"""

from __future__ import annotations

import dataclasses
import os
import stat
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from clearcli.errors import SettingsError
from clearcli.settings.fields import Section, range_of
from clearcli.settings.geometry import GripperSettings, PredicateSettings, PushSettings
from clearcli.settings.images import ImageSettings
from clearcli.settings.kinds import KIND_NAMES, REQUIRED_KINDS, default_kinds, tool_of
from clearcli.settings.plan import PlanSettings
from clearcli.settings.profiles import PROFILE_NAMES, profile_defaults, profiles_with, tools_of
from clearcli.settings.replay import MemoryParams, ReplaySettings, TrackingParams
from clearcli.settings.robot import RobotSettings
from clearcli.settings.segment import SegmentSettings
from clearcli.settings.sim import DepthNoise, PinholeCamera, WorldParams, WorldReachParams
from clearcli.settings.suction import SuctionSettings


@dataclass(frozen=True)
class Settings:
    segment: SegmentSettings = field(default_factory=SegmentSettings)
    gripper: GripperSettings = field(default_factory=GripperSettings)
    suction: SuctionSettings = field(default_factory=SuctionSettings)
    push: PushSettings = field(default_factory=PushSettings)
    predicates: PredicateSettings = field(default_factory=PredicateSettings)
    plan: PlanSettings = field(default_factory=PlanSettings)
    robot: RobotSettings = field(default_factory=RobotSettings)
    replay: ReplaySettings = field(default_factory=ReplaySettings)
    tracking: TrackingParams = field(default_factory=TrackingParams)
    memory: MemoryParams = field(default_factory=MemoryParams)
    world: WorldParams = field(default_factory=WorldParams)
    world_reach: WorldReachParams = field(default_factory=WorldReachParams)
    camera: PinholeCamera = field(default_factory=PinholeCamera)
    depth_noise: DepthNoise = field(default_factory=DepthNoise)
    images: ImageSettings = field(default_factory=ImageSettings)


def _registry() -> dict[str, type[Section]]:
    registry: dict[str, type[Section]] = {}
    for f in dataclasses.fields(Settings):
        cls = f.default_factory  # each field of `Settings` is built by its section's class
        assert isinstance(cls, type) and issubclass(cls, Section)
        registry[f.name] = cls
    return registry


# The registry: section name -> its class, in the order of `Settings`' fields.
SECTIONS = _registry()
assert all(cls.NAME == name for name, cls in SECTIONS.items())

# The sections each command reads: what its provenance digest covers.
READS: dict[str, tuple[str, ...]] = {
    "info": ("images",),
    "segment": ("images", "segment"),
    "evaluate": ("images", "segment"),
    "predicates": ("images", "segment", "gripper", "suction", "push", "predicates"),
    "plan": ("images", "segment", "gripper", "suction", "push", "predicates", "plan", "robot"),
    "replay": (
        "images",
        "segment",
        "gripper",
        "suction",
        "push",
        "predicates",
        "plan",
        "robot",
        "replay",
        "tracking",
        "memory",
    ),
    "simulate": tuple(SECTIONS),
}


def _section(name: str, base: Any, values: Mapping[str, Any]) -> Any:
    cls = SECTIONS[name]
    known = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(values) - known)
    if unknown:
        raise SettingsError(
            f"settings: unknown key(s) {', '.join(unknown)} in [{name}]; known: {', '.join(sorted(known))}"
        )
    return dataclasses.replace(base, **values)  # checked by Section.__post_init__


def settings_from_dict(data: Mapping[str, Any], base: Settings | None = None) -> Settings:
    """``base`` (defaults when None) with the sections and keys of ``data`` replaced.

    A ``[robot] name`` that changes the profile first resets [robot], [gripper],
    [suction] and [plan] grasps to that profile's defaults (clearcli/settings/profiles.py); the other keys of ``data``
    then override them. Within one call, then, a user's values always win; across calls
    (a file, then --set robot.name=...), give the profile no later than its overrides."""
    base = base or Settings()
    unknown = sorted(set(data) - set(SECTIONS))
    if unknown:
        raise SettingsError(f"settings: unknown section(s) {', '.join(unknown)}; known: {', '.join(SECTIONS)}")
    robot_values = data.get("robot")
    if isinstance(robot_values, Mapping) and "name" in robot_values and robot_values["name"] != base.robot.name:
        base = with_profile(base, robot_values["name"])
    changes: dict[str, Any] = {}
    for name, values in data.items():
        if not isinstance(values, Mapping):
            raise SettingsError(f"settings: [{name}] must be a table of keys")
        if values:
            changes[name] = _section(name, getattr(base, name), values)
    return dataclasses.replace(base, **changes) if changes else base


def with_profile(settings: Settings, name: Any) -> Settings:
    """``settings`` with [robot], [gripper] and [suction] at the defaults of profile
    ``name``, and [plan] grasps at its default (the kinds its tool takes)."""
    if not isinstance(name, str) or name not in PROFILE_NAMES:
        raise SettingsError(
            f"settings: [robot] name = {name!r} is not a robot profile; known: {', '.join(PROFILE_NAMES)} "
            "(`clear robots` lists them)"
        )
    defaults = profile_defaults(name)
    return dataclasses.replace(
        settings,
        robot=_section("robot", RobotSettings(), {**defaults.get("robot", {}), "name": name}),
        gripper=_section("gripper", GripperSettings(), dict(defaults.get("gripper", {}))),
        suction=_section("suction", SuctionSettings(), dict(defaults.get("suction", {}))),
        plan=_section("plan", settings.plan, {"grasps": defaults.get("plan", {}).get("grasps", default_kinds())}),
    )


def parse_set(text: str) -> tuple[str, str, Any]:
    """``section.key=value`` -> (section, key, value). The value is read as TOML (numbers,
    true/false, [lists], "strings", nan, inf); bare words (with commas too: pinch,rim)
    are a string."""
    import tomllib  # noqa: PLC0415  (~4 ms: only --set and --settings read TOML)

    name, sep, raw = text.partition("=")
    section, dot, key = name.strip().partition(".")
    if not sep or not dot or not section or not key:
        raise SettingsError(f"--set {text!r}: expected SECTION.KEY=VALUE, e.g. --set segment.voxel_m=0.005")
    raw = raw.strip()
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        # a bare word, or bare words with commas ("pinch,rim": a set of names), is text
        if not raw or any(c in raw for c in "[]{}\"'="):
            raise SettingsError(
                f"--set {text!r}: {raw!r} is not a value (a number, true/false, a [list] or a word)"
            ) from None
        value = raw
    return section.strip(), key.strip(), value


def apply_sets(settings: Settings, sets: Iterable[str]) -> Settings:
    data: dict[str, dict[str, Any]] = {}
    for text in sets:
        section, key, value = parse_set(text)
        data.setdefault(section, {})[key] = value
    return settings_from_dict(data, base=settings) if data else settings


def read_settings_file(path: Path) -> dict[str, Any]:
    import tomllib  # noqa: PLC0415  (~4 ms: only --set and --settings read TOML)

    try:
        if not stat.S_ISREG(os.stat(path).st_mode):  # a FIFO would be waited on for ever
            raise SettingsError(f"{path}: not a regular file; give a TOML settings file")
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SettingsError(f"{path}: settings file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SettingsError(f"{path}: cannot read settings file ({exc})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SettingsError(f"{path}: not valid TOML ({exc})") from None
    except RecursionError:
        raise SettingsError(f"{path}: not valid TOML (nested too deeply to read)") from None


def load_settings(path: Path | None = None, sets: Iterable[str] = ()) -> Settings:
    """Defaults, updated by the TOML file at ``path`` when given, then by each ``--set``."""
    settings = Settings()
    data: dict[str, Any] = {}
    if path is not None:
        data = read_settings_file(path)
        try:
            settings = settings_from_dict(data)
        except SettingsError as exc:
            if str(path) in str(exc):
                raise
            raise SettingsError(f"{path}: {exc}") from None
    sets = list(sets)
    names = [value for section, key, value in map(parse_set, sets) if (section, key) == ("robot", "name")]
    if names:
        # a profile given by --set: the file's [robot], [gripper], [suction] and [plan]
        # grasps values still win
        # over the profile's defaults, as a file's values win over the tree's
        name = names[-1]
        plan_grasps = dict(data.get("plan", {}))
        own = {
            "robot": {k: v for k, v in dict(data.get("robot", {})).items() if k != "name"},
            "gripper": data.get("gripper", {}),
            "suction": data.get("suction", {}),
            "plan": {"grasps": plan_grasps["grasps"]} if "grasps" in plan_grasps else {},
        }
        settings = settings_from_dict(own, base=with_profile(settings, name))
    return apply_sets(settings, sets)


def override(settings: Settings, section: str, **values: Any) -> Settings:
    """Settings with the non-None ``values`` replaced in ``section`` (a command's flags)."""
    given = {k: v for k, v in values.items() if v is not None}
    if not given:
        return settings
    return settings_from_dict({section: given}, base=settings)


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {value!r} as TOML")


def settings_to_toml(settings: Settings, sections: Iterable[str] | None = None, ranges: bool = False) -> str:
    """The tree (or the named sections) as TOML that `--settings FILE` reads back; with
    ``ranges``, each key's accepted values as a comment."""
    lines = ["# clear settings; pass with --settings FILE. Lengths in metres, angles in degrees."]
    for name in SECTIONS if sections is None else sections:
        section = getattr(settings, name)
        lines.append("")
        lines.append(f"[{name}]")
        for f in dataclasses.fields(section):
            text = f"{f.name} = {_toml_value(getattr(section, f.name))}"
            if ranges and not isinstance(getattr(section, f.name), bool):
                text += f"  # {range_of(type(section), f.name).describe()}"
            lines.append(text)
    return "\n".join(lines) + "\n"


def digest(settings: Settings, sections: Iterable[str]) -> str:
    """A short hash of the named sections' resolved values: two results with the same
    digest were made with the same settings for what that command reads."""
    # OpenSSL's hashlib is ~4-10 ms to import, and only --json's provenance asks for this
    import hashlib  # noqa: PLC0415  (~4-10 ms: --json only)

    text = settings_to_toml(settings, tuple(sections))
    return "sha256:" + hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def check_tools(settings: Settings) -> None:
    """One line (SettingsError) when [plan] grasps names a kind the robot's tool cannot
    take (a suction grasp asked of fingers alone), naming the profiles whose tool can."""
    tools = tools_of(settings.robot.name)
    for name in str(settings.plan.grasps).split(","):
        name = name.strip()
        part = tool_of(name) if name in KIND_NAMES else "fingers"
        if part not in tools and name not in REQUIRED_KINDS:
            raise SettingsError(
                f"settings: [plan] grasps = {settings.plan.grasps!r}: {name} needs a {part}, and the "
                f"{settings.robot.name} profile's tool has none; profiles with one: {', '.join(profiles_with(part))} "
                "(--robot NAME; `clear robots`)"
            )
