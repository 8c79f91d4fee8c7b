"""The subcommands: each parses its flags into its task's request (clearcli/tasks/) and
prints the outcome.

Imports: `clear --help` prints its recording (root_help.py) and imports no command
module, but a completion request, `clear --help` on a narrow terminal and a mistyped
command register them all (they list them), so a command module imports at its top only
what costs that next to nothing: typer, its options
(options.py), the shared consoles and output paths (common.py), the errors and the task
layer's plain data (clearcli/tasks/base.py). Its task module, which loads the stages
(measured with `python -X importtime`: ~0.1 s for `info`, ~0.3 s for `domain`, 0.5 to
1.3 s for the others), is imported inside the command's function, as are the frame
sources (clearcli/tasks/sources.py, ~170 ms) and rich's tables and progress bars
(~6 and ~12 ms): each such import is marked `noqa: PLC0415` with what it saves.
"""
