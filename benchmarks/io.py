"""Frame reading speed and memory: one 640x480 binary_compressed PCD, and every shared MCAP.

Run: .venv/bin/python benchmarks/io.py [--repeat N]

Times are the median of N warm runs (one untimed run first loads libraries and fills the
page cache). Peak memory is what tracemalloc sees Python and NumPy allocate during one
more run (so it counts decoded arrays and read buffers, not the interpreter), and the
process's max RSS at the end is printed for scale.
"""

from __future__ import annotations

import argparse
import resource
import statistics
import sys
import time
import tracemalloc
from collections.abc import Callable
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from clearcli.io.read import iter_frames, read_frame  # noqa: E402

DATA = REPO.parent / "shared" / "data"


def _measure(fn: Callable[[], int], repeat: int) -> tuple[float, float, int]:
    """(median seconds, peak traced MiB, frames) of fn, which returns how many frames it read."""
    frames = fn()  # warm-up
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    tracemalloc.start()
    fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return statistics.median(times), peak / 2**20, frames


def _read_one(path: Path) -> Callable[[], int]:
    def run() -> int:
        read_frame(path)
        return 1

    return run


def _stream(path: Path) -> Callable[[], int]:
    def run() -> int:
        n = 0
        for _frame in iter_frames(path):  # one frame alive at a time
            n += 1
        return n

    return run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    args = parser.parse_args()
    cases: list[tuple[str, Path, Callable[[Path], Callable[[], int]]]] = [
        ("read mosd/test/test57.pcd (binary_compressed)", DATA / "mosd/test/test57.pcd", _read_one),
        ("read pcd_formats/mosd_test57_binary.pcd", DATA / "pcd_formats/mosd_test57_binary.pcd", _read_one),
        ("read pcd_formats/mosd_test57_ascii.pcd", DATA / "pcd_formats/mosd_test57_ascii.pcd", _read_one),
    ]
    for log in sorted((DATA / "mcap").glob("*.mcap")):
        cases.append((f"stream mcap/{log.name}", log, _stream))
    rows = []
    for label, path, make in cases:
        if not path.exists():
            rows.append((label, "missing", "", "", ""))
            continue
        seconds, peak_mib, frames = _measure(make(path), args.repeat)
        size_mib = path.stat().st_size / 2**20
        rows.append((label, str(frames), f"{size_mib:.1f}", f"{seconds * 1000:.1f}", f"{peak_mib:.1f}"))
    header = ("case", "frames", "file MiB", "median ms", "peak MiB")
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    print(f"frame reading, median of {args.repeat} warm runs; peak = tracemalloc during one run")
    for row in [header, *rows]:
        print("  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(row, widths))))
    print(f"process max RSS: {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")


if __name__ == "__main__":
    main()
