"""The same batch on a Ray cluster (`pip install 'clear-table[ray]'`).

Ray is the scheduler beyond one machine; `clear` only hands it one task per frame and
reads the lines back. Each task runs `work.run_job`, as a local worker does; Ray keeps
its worker processes, so each imports `clear`'s libraries once. A task whose worker dies
is not retried (the frame may be what kills it): its frame gets an internal-error line.
"""

from __future__ import annotations

import socket
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from clearcli.batch.work import Job, frame_line, run_job
from clearcli.errors import InputError

LOCAL = "local"


def connect(address: str) -> float:
    """ray.init on ``address`` ("local": a cluster of this machine alone); the seconds it
    took. An address that cannot be reached is a one-line error before any work."""
    try:
        import ray
    except ImportError:
        raise InputError(
            "--ray needs Ray: install the extra with `pip install 'clear-table[ray]'` "
            "(or `pip install ray`) into clear's environment"
        ) from None
    t0 = time.perf_counter()
    if ray.is_initialized():
        return 0.0
    if address not in (LOCAL, "auto"):
        _probe(address)
    kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False, "logging_level": "ERROR"}
    try:
        if address == LOCAL:
            ray.init(**kwargs)
        else:
            ray.init(address=address, **kwargs)
    except Exception as exc:  # ConnectionError, RuntimeError, ValueError by Ray version
        raise InputError(
            f"--ray {address}: cannot connect to a Ray cluster there ({type(exc).__name__}: {exc})"
        ) from None
    return time.perf_counter() - t0


def _probe(address: str, timeout_s: float = 5.0) -> None:
    """A TCP connection to the address's host and port, so that an address nobody
    answers at is reported at once (ray.init would retry for minutes)."""
    hostport = address.split("://", 1)[-1].rstrip("/")
    host, sep, port = hostport.rpartition(":")
    if not sep or not port.isdecimal():  # what int() reads (isdigit also takes "²")
        raise InputError(f"--ray {address}: expected HOST:PORT, ray://HOST:PORT, 'auto' or nothing (a local cluster)")
    if not 0 < int(port) < 65536:  # the socket refuses others, some with OverflowError
        raise InputError(f"--ray {address}: the port must be 1 to 65535, not {port}")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s):
            pass
    except OSError as exc:
        raise InputError(f"--ray {address}: cannot reach a Ray cluster there ({exc.strerror or exc})") from None


def _remote() -> Any:
    import ray

    return ray.remote(max_retries=0)(run_job)


def run(jobs: Sequence[Job], stop: Callable[[], bool] = lambda: False) -> Iterator[tuple[int, dict[str, Any]]]:
    """(index, line) per job in completion order; ``stop()`` true: no new task."""
    import ray

    task = _remote()
    # Enough tasks in flight to keep every CPU busy, no more: stopping (fail-fast,
    # Ctrl-C) then leaves little running.
    resources = ray.cluster_resources()  # type: ignore[no-untyped-call]  # Ray ships py.typed, this one unannotated
    width = max(1, int(resources.get("CPU", 1)) * 2)
    pending = list(range(len(jobs)))[::-1]
    running: dict[Any, int] = {}
    try:
        while pending or running:
            while pending and len(running) < width and not stop():
                i = pending.pop()
                running[task.remote(jobs[i])] = i
            if not running:
                break
            done, _ = ray.wait(list(running), num_returns=1)
            for ref in done:
                i = running.pop(ref)
                try:
                    line = ray.get(ref)
                except ray.exceptions.RayError as exc:
                    line = frame_line(jobs[i], None, (f"internal error: the Ray task failed ({type(exc).__name__})", 1))
                yield i, line
    finally:
        for ref in running:
            ray.cancel(ref, force=True)
