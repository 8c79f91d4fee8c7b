"""clear: from point clouds of a cluttered table to a plan to clear it."""

__version__ = "0.1.0"
