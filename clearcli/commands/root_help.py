"""What `clear --help` prints, recorded, so that clearcli/cli.py prints it without building
the app: typer and every command module, imported to render one screen of static text,
were 0.14 s of the 0.21 s of CPU `clear --help` took, against 0.07 s printed from here
(issue 39, minima of 15 runs; the target is 0.1 s). Printed only where click would print
exactly this: `--help` alone, under the name `PROG_NAME`, on a terminal of `MIN_COLUMNS`
or more (click's help is 78 columns wide from there on) or a pipe, no shell completion
asked; anything else goes through the app.

Recorded from the app by `tests/cli/record_root_help.py`; tests/cli/test_startup.py
fails when it differs from what the app prints.
"""

PROG_NAME = "clear"
MIN_COLUMNS = 80

TEXT = """\
Usage: clear [OPTIONS] COMMAND [ARGS]...

  Plan how a robot arm clears a cluttered table, from recorded point clouds
  and RGB-D images.

  Results go to stdout (--json: one stable, versioned schema); logs and
  progress to stderr.

  Exit codes:

  0: success (plan: every object removed, an empty table included)

  1: internal error (a bug in clear; rerun with CLEAR_DEBUG=1 and report it)

  2: usage error (unknown option, missing argument)

  3: bad input: file missing, empty, corrupt, not a point cloud, bad settings

  4: no usable table in the frame (no plane, seen from below, no finite
  points)

  5: no plan: no object can be removed (reasons printed; plan --json still
  prints its document)

  6: planner failure: time-out, crash or Fast Downward missing

  7: subcommand not implemented yet

  8: output not written: exists (use --force) or not writable

  9: log read only in part: truncated or corrupt after the frames reported

  10: partial plan: it removes some objects; the others are left, each with
  its reason

  11: batch (several frames): some frames failed; each one's code and message
  are in its line

  12: out of memory: an allocation failed, or the memory limit (ulimit -v /
  -d) is below what clear needs

  130: interrupted (Ctrl-C); a batch still prints the summary of what finished

  141: stdout was closed by its reader (e.g. `| head`): ended quietly

  143: terminated (SIGTERM); a batch still prints the summary of what finished

Options:
  --version             Print the version and exit.
  --install-completion  Install completion for the current shell.
  --show-completion     Show completion for the current shell, to copy it or
                        customize the installation.
  --help                Show this message and exit.

Commands:
  info        What a file holds: points, fields, organized shape, finite...
  segment     Find the table and segment the objects on it (thesis 4.1):...
  predicates  Objects and symbolic facts of FRAME (on, block_grasp,...
  domain      Print the PDDL domain (types obj/direction; actions grasp,...
  plan        Plan how to clear the table in FRAME: numbered actions,...
  replay      Replay a recorded clearing session: segment, predicates and...
  simulate    Simulate a clearing session: plan on a rendered frame,...
  settings    Print every setting as TOML: the defaults, or FILE and each...
  robots      List the robot profiles (--robot NAME, [robot] name), or...
  schema      Print the JSON Schema (draft 2020-12) of a document `clear`...
  evaluate    Score results against ground truth.
"""
