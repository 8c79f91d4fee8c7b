"""How a `clear` process ends (clearcli/interrupts.py `end_process`, called by
clearcli/cli.py): once the command is over, the exit handlers run, stdout and stderr are
flushed, and the process ends with the command's exit code without the interpreter's
teardown of every module (issue 39: 5-25 ms of each cold call); a thread that is not a
daemon still running keeps the usual exit, which waits for it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from helpers import FIXTURES, run_clear
from helpers.batch import hooked_env

# In the child before clear's main: an exit handler that writes "atexit", and a module
# object whose finaliser writes "teardown" when the interpreter tears the modules down
# (a module global is only finalised there). With CLEAR_TEST_THREAD, a thread that is not
# a daemon, started at the first import of clearcli.cli, writes "thread" after 0.5 s.
_HOOK = """
import atexit, os, sys, threading, time

_OUT = os.environ["CLEAR_TEST_EXIT"]

def _note(word):
    with open(_OUT, "a") as out:
        out.write(word + "\\n")

atexit.register(_note, "atexit")

class _Finalised:
    # what it calls held here: the teardown clears the modules' names before this runs
    def __del__(self, _open=os.open, _write=os.write, _close=os.close, _path=_OUT, _flags=os.O_WRONLY | os.O_APPEND):
        fd = _open(_path, _flags)
        _write(fd, b"teardown\\n")
        _close(fd)

sys.modules[__name__].keep = _Finalised()

if os.environ.get("CLEAR_TEST_THREAD"):
    def _late():
        time.sleep(0.5)
        _note("thread")
    threading.Thread(target=_late, daemon=False).start()
"""


def _run(tmp_path: Path, *args: object, thread: bool = False) -> tuple[int, str, list[str]]:
    folder = tmp_path / f"run{len(list(tmp_path.iterdir()))}"
    folder.mkdir()
    notes = folder / "notes.txt"
    env = hooked_env(folder, _HOOK)
    env["CLEAR_TEST_EXIT"] = str(notes)
    if thread:
        env["CLEAR_TEST_THREAD"] = "1"
    res = run_clear(*args, timeout=120, env=env)
    return res.returncode, res.stdout, notes.read_text().split() if notes.exists() else []


def test_a_command_ends_after_its_exit_handlers_without_the_teardown(tmp_path: Path) -> None:
    # (info: a command that reads a frame without `gc.freeze`, after which the usual exit
    # did not finalise the hook's object either)
    code, out, notes = _run(tmp_path, "info", FIXTURES / "isolated_box.pcd", "--json")
    assert code == 0 and '"schema":"clear.info"' in out.replace(" ", "")
    assert notes == ["atexit"]  # the handlers ran; the modules were not torn down
    code, out, notes = _run(tmp_path, "segment", FIXTURES / "isolated_box.pcd", "--json")
    assert code == 0 and '"schema":"clear.segmentation"' in out.replace(" ", "")
    assert notes == ["atexit"]


def test_exit_codes_are_the_commands(tmp_path: Path) -> None:
    code, _, notes = _run(tmp_path, "segment", tmp_path / "missing.pcd")
    assert code == 3 and notes == ["atexit"]
    code, _, notes = _run(tmp_path, "segment", FIXTURES / "isolated_box.pcd", "--set", "segment.voxel_m=-1")
    assert code == 3 and notes == ["atexit"]


def test_a_running_thread_keeps_the_usual_exit(tmp_path: Path) -> None:
    code, _, notes = _run(tmp_path, "--version", thread=True)
    assert code == 0
    # the usual exit: the thread finished first, then the handlers, then the teardown
    assert notes == ["thread", "atexit", "teardown"]


def test_a_program_calling_main_goes_on_after_it(tmp_path: Path) -> None:
    """Only `clear` itself ends at once: a script of the user's that calls main (and
    catches its SystemExit) runs on, as before."""
    script = tmp_path / "wrapper.py"
    script.write_text(
        "import sys\nfrom clearcli.cli import main\nsys.argv = ['clear', '--version']\n"
        "try:\n    main()\nexcept SystemExit as exc:\n    print('went on', exc.code)\n"
    )
    res = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.splitlines()[-1] == "went on 0"
