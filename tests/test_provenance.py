"""Tests of clearcli/provenance.py: a line on stdout is whole, whatever signal comes."""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
import time

CHILD = textwrap.dedent(
    """
    import sys
    from clearcli import interrupts
    from clearcli.errors import Terminated
    from clearcli.provenance import print_line

    interrupts.hold()
    interrupts.release()
    line = "x" * 2_000_000  # far more than a pipe holds: written in many pieces
    sys.stderr.write("ready\\n"); sys.stderr.flush()
    try:
        while True:
            print_line(line)
    except Terminated:
        sys.exit(143)
    """
)


def test_a_sigterm_while_a_long_line_is_written_cuts_no_line() -> None:
    for delay in (0.05, 0.2, 0.5):
        proc = subprocess.Popen([sys.executable, "-c", CHILD], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        assert proc.stderr is not None and proc.stderr.readline() == b"ready\n"
        time.sleep(delay)
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=60)
        assert proc.returncode == 143
        lines = out.split(b"\n")
        assert lines[-1] == b""  # the output ends with a newline: the last line is whole
        assert all(len(x) == 2_000_000 for x in lines[:-1])
