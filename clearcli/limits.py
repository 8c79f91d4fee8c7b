"""The process's memory limit, checked before anything heavy loads.

Under an address-space limit (``ulimit -v``, RLIMIT_AS) or a data limit (``ulimit -d``,
RLIMIT_DATA) too small for NumPy and SciPy, loading them does not fail cleanly: the
OpenBLAS that SciPy bundles retries its 32 MB buffer at load time for ever (a process
that never ends and ignores Ctrl-C and SIGTERM), a compiled library fails to map
("ImportError: failed to map segment"), or Python raises MemoryError somewhere in an
import. Measured on x86-64 Linux (Python 3.11, NumPy 2, SciPy 1.x): `clear plan` of a
640x480 frame hangs at 200-220 MB and fails to import at 240 MB, runs at 260 MB, and a
1280x720 frame and a two-worker batch run at 300 MB and 400 MB. The floor, 384 MiB, is
that with a margin, so that a limit under it is refused at once, in one line, with exit
12, and a limit over it lets every command start (an allocation that fails later is
exit 12 too: the CLI maps MemoryError to it).
"""

from __future__ import annotations

import resource

MIN_MEMORY_LIMIT_BYTES = 384 * 1024 * 1024


def memory_limit_bytes() -> int | None:
    """The smaller of the soft address-space and data limits, None when neither is set."""
    limits = []
    for which in (resource.RLIMIT_AS, resource.RLIMIT_DATA):
        soft, _hard = resource.getrlimit(which)
        if soft != resource.RLIM_INFINITY:
            limits.append(soft)
    return min(limits) if limits else None


def too_little_memory() -> str | None:
    """The one-line reason the limit is too small to start, None when it is not."""
    limit = memory_limit_bytes()
    if limit is None or limit >= MIN_MEMORY_LIMIT_BYTES:
        return None
    return (
        f"the process may use only {limit / 2**20:.0f} MiB of memory (ulimit -v / ulimit -d), under the "
        f"{MIN_MEMORY_LIMIT_BYTES // 2**20} MiB clear needs to load its numeric libraries; raise the limit"
    )
