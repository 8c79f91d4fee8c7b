"""The options the commands share, defined once: settings (`--settings`, `--set`), the
frame to read (`--topic`, `--frame`), outputs (`--force`, `--json`) and batches (see
clearcli/batch/run.py)."""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import typer

from clearcli import interrupts, startup
from clearcli import settings as clear_settings
from clearcli.errors import InputError
from clearcli.files import exists
from clearcli.settings import kinds as grasp_kinds
from clearcli.settings.profiles import names_text as profile_names_text

SettingsFile = Annotated[Path | None, typer.Option("--settings", help="TOML settings file (see `clear settings`).")]
Set = Annotated[
    list[str] | None,
    typer.Option(
        "--set",
        help="Override one setting, SECTION.KEY=VALUE (repeatable; checked like the file), "
        "e.g. --set segment.voxel_m=0.004. See `clear settings`.",
        metavar="SECTION.KEY=VALUE",
    ),
]
Topic = Annotated[
    str | None,
    typer.Option("--topic", help="Logs (MCAP, ROS 1 bag, rosbag2): the point-cloud topic, when there are several."),
]
FrameIndex = Annotated[int, typer.Option("--frame", help="Logs: which frame of the topic (from 0).", min=0)]
Force = Annotated[bool, typer.Option("--force", help="Overwrite existing output files.")]
Robot = Annotated[
    str | None,
    typer.Option(
        "--robot",
        help=f"Robot profile: {profile_names_text()} (`clear robots`). An alias of --set robot.name=NAME: "
        "the profile's [robot] and [gripper] values, under the file's and --set's.",
        metavar="NAME",
    ),
]
Grasps = Annotated[
    str | None,
    typer.Option(
        "--grasps",
        help=f"Grasp kinds the planner may use, cheapest first: {grasp_kinds.help_text()}. "
        f"'{grasp_kinds.REQUIRED_KINDS[0]}' alone is the thesis's behaviour exactly. Any order, each kind at most "
        f"once, {', '.join(grasp_kinds.REQUIRED_KINDS)} included: the rule of --set plan.grasps=KINDS, whose alias "
        f"this is (default {grasp_kinds.default_kinds()}).",
        metavar="KINDS",
    ),
]

Inputs = Annotated[
    list[Path],
    typer.Argument(
        metavar="FRAME",
        help="Frames: .pcd, .mcap or .bag files, rosbag2 folders, depth images (.png, .tif, .npy; see "
        "--intrinsics, --color), and folders to search for them. More than one frame makes a batch.",
    ),
]
Every = Annotated[
    int | None, typer.Option("--every", help="Batch: every N-th frame of each log (from --frame, default 0).", min=1)
]
OutDir = Annotated[
    Path | None,
    typer.Option("--out-dir", help="Batch: write each frame's outputs and its <name>.json line into this folder."),
]
Resume = Annotated[
    bool, typer.Option("--resume", help="Batch: skip frames whose <name>.json is in --out-dir; redo the others.")
]
Jobs = Annotated[
    int | None, typer.Option("--jobs", help="Batch: worker processes (default: the cores available).", min=1)
]
Ray = Annotated[
    str | None,
    typer.Option(
        "--ray",
        help="Batch on a Ray cluster at ADDRESS (`--ray` alone: a local one); needs `pip install 'clear-table[ray]'`.",
        metavar="[ADDRESS]",
    ),
]
Intrinsics = Annotated[
    str | None,
    typer.Option(
        "--intrinsics",
        help="Depth images: the camera's intrinsics, a file (ROS camera_info YAML, Open3D JSON, camera_params.json) "
        'or "fx fy cx cy"; default: the intrinsics file beside the image ([images] intrinsics).',
    ),
]
Color = Annotated[
    Path | None,
    typer.Option(
        "--color",
        help="Depth image: its colour image (registered to the depth, same size); default: the image the naming "
        "rule pairs with it (<stem>_depth.png -> <stem>_color.png).",
    ),
]
DepthScale = Annotated[
    float | None,
    typer.Option(
        "--depth-scale",
        help="Integer depth images: metres per unit (default 0.001: millimetres; [images] depth_scale_m).",
    ),
]
FailFast = Annotated[bool, typer.Option("--fail-fast", help="Batch: stop at the first frame that fails.")]
Wait = Annotated[
    bool,
    typer.Option("--wait", help="Batch: when another batch is writing in --out-dir, wait for it instead of refusing."),
]


def resolve_settings(
    path: Path | None,
    sets: list[str] | None,
    section: str | None = None,
    robot: str | None = None,
    grasps: str | None = None,
    **flags: Any,
) -> Any:
    """The resolved settings tree, checked before any frame is read: defaults, the file,
    each --set, then the command's own flags (aliases of --set in ``section``). ``robot``
    (--robot) is --set robot.name=ROBOT given first: the profile's defaults, then the
    file's and the other --set values over them."""
    sets = ([f"robot.name={robot}"] if robot is not None else []) + list(sets or ())
    settings = clear_settings.load_settings(path, sets)
    if grasps is not None:  # a flag over the file and --set, checked by [plan] grasps's own rule
        settings = clear_settings.override(settings, "plan", grasps=grasps)
    clear_settings.check_tools(settings)  # the kinds asked for and the robot's tool agree
    if settings.robot.urdf:
        from clearcli.tasks.robots import check_robot  # noqa: PLC0415  (~7 ms for `clear --help`; a URDF only)

        check_robot(settings.robot)
    if section is not None:
        settings = clear_settings.override(settings, section, **flags)
    return settings


def with_images(settings: Any, intrinsics: str | None, depth_scale: float | None) -> Any:
    """``settings`` with the depth-image flags applied ([images]: --intrinsics, --depth-scale).
    An intrinsics file is recorded by its absolute path, so that batch workers (and the
    results' settings.toml) find the same file wherever they run."""
    if intrinsics is not None and intrinsics.strip() and exists(intrinsics):
        intrinsics = str(Path(intrinsics).resolve())
    if intrinsics:
        from clearcli.tasks.sources import check_intrinsics  # noqa: PLC0415  (~170 ms for `clear --help`)

        check_intrinsics(intrinsics)  # a bad file or string: one line, exit 3, before any frame
    return clear_settings.override(settings, "images", intrinsics=intrinsics, depth_scale_m=depth_scale)


def no_color_in_batch(color: Path | None) -> None:
    """--color names one file: a batch pairs images by the naming rule instead."""
    if color is not None:
        raise InputError(
            "--color names the colour image of one depth image; with several frames each depth image "
            "<stem>_depth.png is paired with <stem>_color.png beside it (the naming rule: [images] "
            "depth_suffix and color_suffix)"
        )


def is_batch(inputs: Any, every: int | None, out_dir: Path | None, ray: str | None) -> bool:
    """Several frames, a folder (not a rosbag2 bag), --every, --out-dir or --ray make a batch."""
    first = Path(inputs[0]) if inputs else Path()
    folder = first.is_dir() and not (first / "metadata.yaml").is_file()
    return len(inputs) != 1 or folder or every is not None or out_dir is not None or ray is not None


def outputs_option(kinds: tuple[str, ...]) -> Any:
    return Annotated[
        str | None,
        typer.Option(
            "--outputs", help=f"Batch: what to write per frame into --out-dir, comma-separated: {','.join(kinds)}."
        ),
    ]


def single_only(**given: Any) -> None:
    """Options that name one file cannot serve a batch."""
    named = [flag for flag, value in given.items() if value is not None]
    if named:
        raise InputError(
            f"{', '.join(named)} name(s) one file, for a single frame; with several frames use --out-dir DIR and --outputs"
        )


def ray_argv(argv: list[str]) -> list[str]:
    """``--ray`` may stand alone (a local cluster): give it the value "local" when the
    next word is missing, an option, or an input that exists (a file or folder), since
    an address is none of those."""
    out: list[str] = []
    for k, word in enumerate(argv):
        out.append(word)
        if word == "--ray":
            nxt = argv[k + 1] if k + 1 < len(argv) else None
            if nxt is None or nxt.startswith("-") or Path(nxt).exists():
                out.append("local")
    return out


@dataclass(frozen=True)
class Batch:
    """The batch options of a frame command (--every, --out-dir, --outputs, --resume,
    --jobs, --ray, --fail-fast), as `batch_options` hands them to the command."""

    every: int | None = None
    out_dir: Path | None = None
    outputs: str | None = None
    resume: bool = False
    jobs: int | None = None
    ray: str | None = None
    fail_fast: bool = False
    wait: bool = False

    def wanted(self, inputs: Any) -> bool:
        return is_batch(inputs, self.every, self.out_dir, self.ray)

    def run(
        self,
        command: str,
        inputs: Any,
        request: Any,
        *,
        frame: int,
        topic: str | None,
        force: bool,
        json_out: bool,
        reads: tuple[str | Path | None, ...] = (),
        **more: Any,
    ) -> int:
        """The batch's exit code (clearcli/batch/run.py); ``reads``: files the run reads
        besides its frames (--settings), which no output may name; ``more``: its
        on_line, extra_summary and render hooks."""
        from clearcli.batch.run import run_command_batch  # noqa: PLC0415  (~0.3 s: batches only)

        return run_command_batch(
            command,
            inputs,
            request,
            outputs=self.outputs,
            jobs=self.jobs,
            frame=frame,
            every=self.every,
            topic=topic,
            out_dir=self.out_dir,
            force=force,
            resume=self.resume,
            ray=self.ray,
            fail_fast=self.fail_fast,
            wait=self.wait,
            json_out=json_out,
            reads=tuple(str(p) for p in reads if p is not None),
            **more,
        )


def batch_options(outputs: tuple[str, ...]) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Give a frame command the batch options, declared once here: the command takes a
    keyword ``batch: Batch`` instead of seven parameters. ``outputs``: the kinds its
    --outputs accepts (its task's OUTPUTS)."""
    declared: list[tuple[str, Any, Any]] = [
        ("every", Every, None),
        ("out_dir", OutDir, None),
        ("outputs", outputs_option(outputs), None),
        ("resume", Resume, False),
        ("jobs", Jobs, None),
        ("ray", Ray, None),
        ("fail_fast", FailFast, False),
        ("wait", Wait, False),
    ]
    if not outputs:
        declared = [d for d in declared if d[0] != "outputs"]

    def wrap(fn: Callable[..., Any]) -> Callable[..., Any]:
        own = inspect.signature(fn, eval_str=True)
        params = [p for p in own.parameters.values() if p.name != "batch"]
        params += [
            inspect.Parameter(n, inspect.Parameter.KEYWORD_ONLY, default=d, annotation=a) for n, a, d in declared
        ]

        @functools.wraps(fn)
        def command(*args: Any, **kwargs: Any) -> Any:
            batch = Batch(**{n: kwargs.pop(n) for n, _, _ in declared})
            if not batch.wanted(kwargs.get("inputs", args[0] if args else ())):
                interrupts.release()  # one frame: Ctrl-C from here on; a batch releases in its run
            else:
                startup.resume_collection()  # a batch's parent reads no frame (clearcli/startup.py)
            return fn(*args, batch=batch, **kwargs)

        # attributes set on a function: valid Python (inspect.signature reads __signature__),
        # which mypy does not model
        command.__signature__ = own.replace(parameters=params)  # type: ignore[attr-defined]
        command.releases_interrupts = True  # type: ignore[attr-defined]
        return command

    return wrap
