"""Every tunable parameter of `clear`, one registered section per stage (see tree.py).

Sections are plain frozen dataclasses; each value's default and range is declared once,
in its section's class. This package sits at the bottom of the layers: it imports
nothing from clearcli but `errors`.
"""

from clearcli.settings.tree import (  # noqa: F401  (the package's API)
    READS,
    SECTIONS,
    Settings,
    apply_sets,
    digest,
    load_settings,
    override,
    parse_set,
    read_settings_file,
    settings_from_dict,
    settings_to_toml,
)
