"""One typed settings object, a section per stage, loaded from TOML and overridden by flags.

`clear settings` prints the defaults in the same TOML form that `--settings FILE` reads.
Unknown sections or keys are an error (a typo must not be silently ignored).
"""

from __future__ import annotations

import dataclasses
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, get_type_hints

from clearcli.errors import SettingsError
from clearcli.geometry.settings import GripperSettings, PredicateSettings, PushSettings
from clearcli.perception.settings import SegmentSettings
from clearcli.planning.settings import PlanSettings
from clearcli.robot.settings import RobotSettings


@dataclass(frozen=True)
class Settings:
    segment: SegmentSettings = field(default_factory=SegmentSettings)
    gripper: GripperSettings = field(default_factory=GripperSettings)
    push: PushSettings = field(default_factory=PushSettings)
    predicates: PredicateSettings = field(default_factory=PredicateSettings)
    plan: PlanSettings = field(default_factory=PlanSettings)
    robot: RobotSettings = field(default_factory=RobotSettings)


def _coerce(value: Any, typ: Any, where: str) -> Any:
    origin = getattr(typ, "__origin__", None)
    if typ is bool:
        if not isinstance(value, bool):
            raise SettingsError(f"settings: {where} must be true or false, got {value!r}")
        return value
    if typ is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise SettingsError(f"settings: {where} must be an integer, got {value!r}")
        return value
    if typ is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SettingsError(f"settings: {where} must be a number, got {value!r}")
        return float(value)
    if typ is str:
        if not isinstance(value, str):
            raise SettingsError(f"settings: {where} must be a string, got {value!r}")
        return value
    if origin is tuple:
        if not isinstance(value, (list, tuple)):
            raise SettingsError(f"settings: {where} must be a list, got {value!r}")
        return tuple(_coerce(v, float, where) for v in value)
    return value


def _section_from_dict(cls: type, data: dict[str, Any], name: str) -> Any:
    hints = get_type_hints(cls)
    known = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - known)
    if unknown:
        raise SettingsError(
            f"settings: unknown key(s) {', '.join(unknown)} in [{name}]; "
            f"known: {', '.join(sorted(known))}"
        )
    kwargs = {k: _coerce(v, hints[k], f"[{name}] {k}") for k, v in data.items()}
    return cls(**kwargs)


def settings_from_dict(data: dict[str, Any], base: Settings | None = None) -> Settings:
    base = base or Settings()
    hints = get_type_hints(Settings)
    unknown = sorted(set(data) - set(hints))
    if unknown:
        raise SettingsError(
            f"settings: unknown section(s) {', '.join(unknown)}; known: {', '.join(hints)}"
        )
    changes: dict[str, Any] = {}
    for name, section in data.items():
        if not isinstance(section, dict):
            raise SettingsError(f"settings: [{name}] must be a table of keys")
        current = dataclasses.asdict(getattr(base, name))
        current.update(section)
        changes[name] = _section_from_dict(hints[name], current, name)
    return dataclasses.replace(base, **changes)


def load_settings(path: Path | None) -> Settings:
    """Defaults, updated by the TOML file at ``path`` when given."""
    if path is None:
        return Settings()
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SettingsError(f"{path}: settings file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SettingsError(f"{path}: cannot read settings file ({exc})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SettingsError(f"{path}: not valid TOML ({exc})") from None
    return settings_from_dict(data)


def override(settings: Settings, section: str, **values: Any) -> Settings:
    """Settings with the non-None ``values`` replaced in ``section`` (for CLI flags)."""
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


def settings_to_toml(settings: Settings) -> str:
    lines = ["# clear settings; pass with --settings FILE. Lengths in metres, angles in degrees."]
    for f in dataclasses.fields(settings):
        section = getattr(settings, f.name)
        lines.append("")
        lines.append(f"[{f.name}]")
        for key, value in dataclasses.asdict(section).items():
            lines.append(f"{key} = {_toml_value(value)}")
    return "\n".join(lines) + "\n"
