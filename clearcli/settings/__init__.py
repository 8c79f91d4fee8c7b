"""Every tunable parameter of `clear`, one registered section per stage (see tree.py).

Sections are plain frozen dataclasses; each value's default and range is declared once,
in its section's class. This package sits at the bottom of the layers: it imports
nothing from clearcli but `errors`.

The package's API (`Settings`, `load_settings`, ...) is tree.py's, imported when first
asked for: a module that reads only a registry of this package (profiles.py, the robot
profiles' names, which the CLI's help text lists) does not pay for building every
section's class.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from clearcli.settings.tree import (  # noqa: F401  (the package's API)
        READS,
        SECTIONS,
        Settings,
        apply_sets,
        check_tools,
        digest,
        load_settings,
        override,
        parse_set,
        read_settings_file,
        settings_from_dict,
        settings_to_toml,
    )

__all__ = [
    "READS",
    "SECTIONS",
    "Settings",
    "apply_sets",
    "check_tools",
    "digest",
    "load_settings",
    "override",
    "parse_set",
    "read_settings_file",
    "settings_from_dict",
    "settings_to_toml",
]


def __getattr__(name: str) -> Any:
    if name in __all__:
        # imported when first asked for: every `--help` reads only profiles.py and
        # kinds.py, and tree.py's section classes would cost it ~50 ms (measured)
        from clearcli.settings import tree  # noqa: PLC0415

        return getattr(tree, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
