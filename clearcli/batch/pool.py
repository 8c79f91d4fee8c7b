"""Frames on every core: worker processes that each import once and run many frames.

The standard library's pools cannot say which frame a dead worker was running (a
`ProcessPoolExecutor` fails every pending future when one worker dies), so this is a
small pool over `multiprocessing` pipes: one job at a time per worker, so a worker that
dies (killed, out of memory) fails exactly its frame with an internal-error line, and a
new worker takes its place. Workers ignore SIGINT (Ctrl-C reaches the whole process
group); the parent stops them with SIGTERM, which they turn into an exit that runs the
writers' clean-up, so no half-written file is left.
"""

from __future__ import annotations

import ctypes
import multiprocessing as mp
import os
import signal
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from multiprocessing.connection import Connection, wait
from typing import Any

from clearcli import interrupts, startup
from clearcli.batch.work import Job, frame_line, run_job


def _die_with(parent_pid: int) -> None:
    """End this worker when the batch that started it ends, however it ends (SIGKILL
    included): Linux's parent-death signal, SIGTERM so that writes clean up; elsewhere a
    thread that watches the parent. Nothing a killed batch started outlives it long
    enough to race a --resume."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        PR_SET_PDEATHSIG = 1
        libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
    except (OSError, AttributeError):
        pass
    if os.getppid() != parent_pid:  # the parent died before the line above
        os._exit(143)

    def watch() -> None:
        while True:
            time.sleep(0.2)
            if os.getppid() != parent_pid:
                os.kill(os.getpid(), signal.SIGTERM)
                return

    threading.Thread(target=watch, daemon=True).start()


def _worker(conn: Connection, parent_pid: int) -> None:
    # A worker is a fresh interpreter that does not run the CLI's main: it does here what
    # main does before NumPy loads (clearcli/startup.py). One BLAS thread per worker: the
    # workers already fill the cores, and BLAS threads on top only burn CPU (measured:
    # 0.3 s more CPU per segmented frame, same wall time). The lighter imports: without
    # them a worker's first frame paid SciPy's docstring parsing and unused modules
    # (issue 39: scipy.spatial 1.0 s of a worker's start on a loaded machine).
    startup.single_threaded_numerics()
    startup.lighten_imports()
    startup.cache_dataclass_code()  # dataclasses is imported by now: patched here
    # no cyclic collection while the first frame loads the libraries, as in a single call
    # (startup.pause_collection); on again at the frame's read, or after the job at most
    startup.pause_collection()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _stop_worker)
    _die_with(parent_pid)
    try:
        _serve(conn)
    finally:
        # done: a SIGTERM while the interpreter exits ends it at once, raising nothing
        # (a SystemExit raised in its teardown prints "Exception ignored" and a traceback)
        signal.signal(signal.SIGTERM, lambda *_: os._exit(143))
    # No more work (the batch ended, or its pipe closed): out at once, as a `clear` call
    # ends (the batch waited ~40 ms for each worker's teardown in `WorkerPool.close`)
    interrupts.end_process(0)


def _stop_worker(signum: int, frame: Any) -> None:
    """The first SIGTERM: exit through the writers' clean-up. A second one (the parent's
    terminate() and its death signal both) is ignored, so it cannot cut that clean-up
    short; the parent kills a worker that does not end in 5 s."""
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    sys.exit(143)


def _serve(conn: Connection) -> None:
    while True:
        try:
            msg = conn.recv()
        except Exception:  # the pipe closed, or a message cut by its sender's stop: no more work
            return
        if msg is None:
            return
        i, job = msg
        try:
            line = run_job(job)
        finally:
            startup.resume_collection()  # (pipeline.read resumes it; a job that never reached it, here)
        line["_rss_mb"] = _rss_mb()
        line["_pid"] = os.getpid()
        conn.send((i, line))


def _rss_mb() -> float:
    try:
        with open("/proc/self/status", encoding="ascii") as fp:
            for row in fp:
                if row.startswith("VmRSS:"):
                    return int(row.split()[1]) / 1024.0
    except OSError:
        pass
    return 0.0


@dataclass
class _Slot:
    proc: Any
    conn: Connection
    job: int | None = None


class WorkerPool:
    """``n`` worker processes (spawned: a clean interpreter each, no state inherited)."""

    def __init__(self, n: int) -> None:
        self.n = max(1, int(n))
        self._ctx = mp.get_context("spawn")
        self._slots: list[_Slot] = []

    def _start(self) -> _Slot:
        parent, child = self._ctx.Pipe()
        proc = self._ctx.Process(target=_worker, args=(child, os.getpid()), daemon=True)
        # A signal raised in the parent half-way through start() leaves the new
        # interpreter reading a cut pickle (a traceback on stderr): the start is held
        # together, and a signal that came meanwhile is raised right after it.
        with interrupts.deferred():
            proc.start()
        child.close()
        return _Slot(proc, parent)

    def run(
        self, jobs: Sequence[Job], stop: Callable[[], bool] = lambda: False
    ) -> Iterator[tuple[int, dict[str, Any]]]:
        """(index, line) for every job, in completion order. ``stop()`` true: no new job
        is started (the running ones finish)."""
        pending = deque(range(len(jobs)))
        self._slots = [self._start() for _ in range(min(self.n, len(jobs)))]
        try:
            while pending or any(s.job is not None for s in self._slots):
                for slot in self._slots:
                    if slot.job is None and pending and not stop():
                        slot.job = pending.popleft()
                        slot.conn.send((slot.job, jobs[slot.job]))
                busy = [s for s in self._slots if s.job is not None]
                if not busy:
                    break  # stopped with jobs left
                ready = wait([s.conn for s in busy] + [s.proc.sentinel for s in busy])
                for k, slot in enumerate(list(self._slots)):
                    if slot.job is None:
                        continue
                    if slot.conn in ready:
                        try:
                            i, line = slot.conn.recv()
                        except (EOFError, OSError):
                            pass  # died while answering: handled below
                        else:
                            slot.job = None
                            yield i, line
                            continue
                    if slot.proc.sentinel in ready or not slot.proc.is_alive():
                        slot.proc.join(1.0)
                        i = slot.job
                        code = slot.proc.exitcode
                        how = f"killed by signal {-code}" if code is not None and code < 0 else f"exit code {code}"
                        line = frame_line(
                            jobs[i], None, (f"internal error: the worker process died ({how}) on this frame", 1)
                        )
                        slot.conn.close()
                        self._slots[k] = self._start()
                        yield i, line
        finally:
            self.close()

    def close(self) -> None:
        """Stop every worker: SIGTERM (writers clean up), then SIGKILL after 5 s."""
        for slot in self._slots:
            if slot.proc.is_alive():
                if slot.job is None:
                    try:
                        slot.conn.send(None)
                    except (OSError, BrokenPipeError):
                        pass
                else:
                    slot.proc.terminate()
        for slot in self._slots:
            slot.proc.join(5.0)
            if slot.proc.is_alive():
                slot.proc.kill()
                slot.proc.join(1.0)
            slot.conn.close()
        self._slots = []

    def pids(self) -> list[int]:
        return [s.proc.pid for s in self._slots if s.proc.pid is not None]
