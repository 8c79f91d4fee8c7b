"""`clear replay LOG`: the whole pipeline over a recorded session, frame by frame.

--json writes one line per replayed frame, then one summary line, each in the shared
envelope ({"schema": "clear.replay", "version": 1, ...}) with a "type":
  frame:   index (position on the topic), stamp_s, time_s (from the start of the log),
           status (ok | cleared | no_table | no_plan | failed), objects [{id, name,
           centroid_m, extents_m, new}], gone [ids], first_action {kind, id, name,
           grasp_kind (grasps: pinch | rim | slide), direction, unit_vector,
           push_length_m} or null, plan_length, plan (actions
           with ids, cost, optimal, replans, unreachable/ungraspable/stuck ids, probe:
           the id of an object pushed to see whether it is two merged ones, else null)
           or null,
           execution (did the previous first action happen: action, id, outcome
           done|failed, detail, moved_along_m) or null, undoes_push, timings_s by stage,
           error and stage when the frame was not planned.
  summary: frames_read, frames, ok, cleared, no_table, no_plan, failed, objects_seen,
           actions, grasps, pushes, executions {done, failed}, back_and_forth,
           unreachable, time_s and mean_time_s by stage, frames_per_s, stopped (why a
           damaged log ended early, else null).

Exit codes: 0 when at least one frame was planned (frames without a table or that failed
are reported and skipped), 9 when a damaged log ended early (after the summary), 4 when
no frame replayed held a usable table.
"""

from __future__ import annotations

from collections.abc import Mapping, Sized
from pathlib import Path
from typing import Annotated, Any, Protocol

import typer

from clearcli.commands import options as bo
from clearcli.commands.common import check_output_path, print_json, stderr, stdout
from clearcli.errors import SceneError, SettingsError


# What this command reads of the replay's reports (clearcli/replay/report.py FrameReport
# and Summary, which task.run hands over): commands reach the stages only through
# clearcli.tasks, so the types are named by what is used of them.
class _Action(Protocol):
    @property
    def kind(self) -> str: ...
    @property
    def obj(self) -> str: ...
    @property
    def direction(self) -> str | None: ...


class _FrameReport(Protocol):
    @property
    def index(self) -> int: ...
    @property
    def status(self) -> str: ...
    @property
    def objects(self) -> Sized: ...
    @property
    def ids_by_name(self) -> Mapping[str, int]: ...
    def first_action(self) -> _Action | None: ...
    def to_json(self) -> dict[str, Any]: ...


class _Summary(Protocol):
    def to_json(self) -> dict[str, Any]: ...


def replay_cmd(
    log: Annotated[Path, typer.Argument(help="An MCAP log of point clouds (a PCD works too: one frame).")],
    topic: Annotated[
        str | None, typer.Option("--topic", help="Point-cloud topic (needed when the log has several).")
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option("--out", help="Write an annotated MCAP (frames + scene, predicates, plan) for Foxglove."),
    ] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite --out if it exists.")] = False,
    json_out: Annotated[
        bool, typer.Option("--json", help="One JSON line per frame on stdout, then a summary line.")
    ] = False,
    every: Annotated[int, typer.Option("--every", min=1, help="Replay every N-th frame only.")] = 1,
    from_s: Annotated[
        float | None, typer.Option("--from", help="Start at this many seconds from the start of the log.")
    ] = None,
    to_s: Annotated[
        float | None, typer.Option("--to", help="Stop after this many seconds from the start of the log.")
    ] = None,
    fail_fast: Annotated[bool, typer.Option("--fail-fast", help="Stop at the first frame that fails.")] = False,
    no_push_memory: Annotated[
        bool,
        typer.Option("--no-push-memory", help="Plan every frame afresh, as the thesis did (pushes may be undone)."),
    ] = False,
    base_frame: Annotated[
        str | None,
        typer.Option(
            "--base-frame",
            help="The log's name for the robot's base frame, looked up in its /tf_static or /tf "
            "(default: the profile's base frame, e.g. panda_link0, then the names WAM setups use). "
            "It names a frame of the log; which arm it is, is --robot.",
        ),
    ] = None,
    settings: bo.SettingsFile = None,
    sets: bo.Set = None,
    robot: bo.Robot = None,
    grasps: bo.Grasps = None,
) -> None:
    """Replay a recorded clearing session: segment, predicates and plan on every frame,
    with object ids stable across frames, a check of whether each planned action
    happened, and no pushing back and forth. Progress on stderr; a summary at the end."""
    from clearcli.tasks import replay as task  # noqa: PLC0415  (the task, ~0.5 s: not for `clear --help`)

    config = bo.resolve_settings(
        settings, sets, "replay", robot=robot, grasps=grasps, push_memory=False if no_push_memory else None
    )
    if from_s is not None and to_s is not None and to_s < from_s:
        raise SettingsError(f"--to {to_s} is before --from {from_s}")
    if out is not None:
        from clearcli.tasks import sources  # noqa: PLC0415  (~170 ms: not for `clear --help`)

        check_output_path(out, force, sources.files_read(log, config, also=(settings,)))
    request = task.Request(
        config, every=every, from_s=from_s, to_s=to_s, fail_fast=fail_fast, base_frame=base_frame, out=out
    )
    from rich.progress import (  # noqa: PLC0415  (~12 ms: not for `clear --help`)
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
    )

    progress = Progress(
        TextColumn("replay"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TextColumn("{task.description}"),
        console=stderr,
        transient=True,
        disable=json_out,
    )
    with progress:
        bar = progress.add_task("", total=None)

        def on_report(report: _FrameReport, frames_read: int, total: int | None) -> None:
            if json_out:
                print_json(task.SCHEMA, task.VERSION, report.to_json(), config, "replay")
            progress.update(bar, total=total, completed=frames_read, description=_brief(report))

        result, partial = task.run(
            request, log, topic, on_report, lambda text: stderr.print(text, markup=False, highlight=False)
        )
    if json_out:
        print_json(task.SCHEMA, task.VERSION, result.to_json(), config, "replay")
    else:
        _print_summary(result, stdout, out)
    if partial is not None:
        raise partial
    if result.frames > 0 and result.no_table + result.failed == result.frames:
        # every frame was skipped: a script must not mistake this for a replayed session
        raise SceneError(
            f"{log}: none of the {result.frames} frame(s) replayed held a usable table "
            f"({result.no_table} without a table, {result.failed} failed)"
        )


def _brief(report: _FrameReport) -> str:
    first = report.first_action()
    action = ""
    if first is not None:
        ids = report.ids_by_name
        action = f" next: {first.kind} #{ids.get(first.obj, first.obj)}" + (
            f" {first.direction}" if first.direction else ""
        )
    return f"frame {report.index}: {report.status}, {len(report.objects)} objects{action}"


def _print_summary(summary: _Summary, console: Any, out: Path | None) -> None:
    from rich.table import Table  # noqa: PLC0415  (~6 ms: not for `clear --help`)

    data = summary.to_json()
    table = Table(title="replay", show_header=False, title_justify="left")
    table.add_column("what")
    table.add_column("value", justify="right")
    table.add_row("frames replayed", f"{data['frames']} of {data['frames_read']} read")
    table.add_row("planned", str(data["ok"]))
    table.add_row("table cleared", "yes" if data["cleared"] else "no")
    table.add_row("objects seen", str(data["objects_seen"]))
    table.add_row("actions planned", f"{data['actions']} ({data['grasps']} grasps, {data['pushes']} pushes)")
    table.add_row(
        "actions carried out",
        f"{data['executions']['done']} done, {data['executions']['failed']} not",
    )
    table.add_row("unreachable objects", ", ".join(f"#{i}" for i in data["unreachable"]) or "none")
    table.add_row("pushes undoing a push", str(data["back_and_forth"]))
    table.add_row("frames without a table", str(data["no_table"]))
    table.add_row("frames without a plan", str(data["no_plan"]))
    table.add_row("failed frames", str(data["failed"]))
    for stage in ("read", "segment", "predicates", "plan", "total"):
        mean = data["mean_time_s"].get(stage)
        if mean is not None:
            table.add_row(f"time per frame: {stage}", f"{mean:.3f} s")
    if data["frames_per_s"] is not None:
        table.add_row("frames per second", f"{data['frames_per_s']:.2f}")
    if out is not None:
        table.add_row("annotated log", str(out))
    if data["stopped"]:
        table.add_row("stopped early", data["stopped"])
    console.print(table)
