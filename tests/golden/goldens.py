"""Golden outputs: record what `clear` prints on real frames, and compare a later run.

    python tests/golden/goldens.py record [SET ...]   # writes tests/golden/data/<set>.json
    python tests/golden/goldens.py compare [SET ...]  # exit 1 and a diff summary on change

Sets: the JSON documents of `segment`, `predicates` and `plan` (and `plan --grasps pinch`, the
thesis's grasp alone: `plan_pinch_*`) on the 50 mOSD frames, the
fixtures' PCDs and the nine uois RealSense frames; `replay --json` of
fixtures/simulated_session.mcap; `simulate --json` for seeds 0-9. Frames run as one batch
per command (`--jobs 2`), the path a batch evaluation takes, and each frame's document
is kept by its source.

What legitimately varies is normalised away before storing and comparing: timings
(`timings_s`, `time_s`, `mean_time_s`, `wall_s`, `frames_per_s`), absolute paths (the
data root becomes `$SHARED`, the checkout `$REPO`, a temporary folder `$TMP`),
provenance keys (`clear`, `settings_digest`), the batch backend, and the `deadline`
flag of a plan that met its time limit (the plan is then what the clock allowed, not
the data). Everything else must be identical, float for float.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data"
SHARED = Path(os.environ.get("CLEAR_SHARED", REPO.parent / "shared")).resolve()
CLEAR = [str(Path(sys.executable).with_name("clear"))]

# Keys dropped wherever they appear: what a run varies in without the data changing.
VOLATILE = {
    "timings_s",
    "time_s",
    "mean_time_s",
    "wall_s",
    "frames_per_s",
    "ray_init_s",
    "backend",
    "clear",
    "settings_digest",
}
SIM_SEEDS = range(10)


def frame_sets() -> dict[str, list[Path]]:
    mosd = sorted((SHARED / "data/mosd/learn").glob("*.pcd")) + sorted((SHARED / "data/mosd/test").glob("*.pcd"))
    return {
        "mosd": mosd,
        "fixtures": sorted((REPO / "fixtures").glob("*.pcd")),
        "uois": sorted((SHARED / "data/scenes/uois_realsense").glob("*.pcd")),
    }


def _paths(text: str, tmp: str | None) -> str:
    text = text.replace(str(SHARED), "$SHARED").replace(str(REPO), "$REPO")
    if tmp:
        text = text.replace(tmp, "$TMP")
    return text


def normalise(value: Any, tmp: str | None = None) -> Any:
    if isinstance(value, dict):
        out = {k: normalise(v, tmp) for k, v in value.items() if k not in VOLATILE}
        if out.get("schema") == "clear.plan" and out.get("deadline"):
            out = {"schema": "clear.plan", "deadline": True}  # decided by the clock
        return out
    if isinstance(value, list):
        return [normalise(v, tmp) for v in value]
    if isinstance(value, str):
        return _paths(value, tmp)
    return value


def _run(args: list[str]) -> list[dict[str, Any]]:
    env = dict(os.environ, PYTHONHASHSEED="0")
    proc = subprocess.run(CLEAR + args, capture_output=True, text=True, env=env, cwd=REPO)
    if proc.returncode not in (0, 4, 5, 9, 10, 11):
        raise RuntimeError(f"clear {' '.join(args)}: exit {proc.returncode}: {proc.stderr[-2000:]}")
    return [json.loads(line) for line in proc.stdout.splitlines() if line.strip()]


def _batch(command: str, frames: list[Path], extra: tuple[str, ...] = ()) -> dict[str, Any]:
    lines = _run([command, *map(str, frames), "--json", "--jobs", "2", *extra])
    out: dict[str, Any] = {}
    for line in lines:
        if line.get("type") != "frame":
            continue
        key = _paths(line["source"], None)
        out[key] = normalise(line.get("document") or line.get("error"))
    return out


def _replay() -> dict[str, Any]:
    return {"lines": normalise(_run(["replay", str(REPO / "fixtures/simulated_session.mcap"), "--json"]))}


def _simulate() -> dict[str, Any]:
    out: dict[str, Any] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for seed in SIM_SEEDS:
            path = Path(tmp) / f"sim{seed}.mcap"
            out[str(seed)] = normalise(_run(["simulate", str(path), "--seed", str(seed), "--json"]), tmp)
    return out


def recorders() -> dict[str, Callable[[], dict[str, Any]]]:
    sets = frame_sets()
    rec: dict[str, Callable[[], dict[str, Any]]] = {}
    for name, frames in sets.items():
        for command in ("segment", "predicates", "plan"):
            rec[f"{command}_{name}"] = lambda c=command, f=frames: _batch(c, f)
        # the thesis's pinch alone: the plans as before the other grasp kinds came
        rec[f"plan_pinch_{name}"] = lambda f=frames: _batch("plan", f, ("--grasps", "pinch"))
    rec["replay_session"] = _replay
    rec["simulate_seeds"] = _simulate
    return rec


def record(names: list[str]) -> None:
    DATA.mkdir(parents=True, exist_ok=True)
    for name in names:
        doc = recorders()[name]()
        (DATA / f"{name}.json").write_text(json.dumps(doc, indent=1, sort_keys=True) + "\n", encoding="utf-8")
        print(f"recorded {name}: {len(doc)} documents", file=sys.stderr)


def diff(a: Any, b: Any, where: str = "") -> list[str]:
    """Where two normalised documents differ (paths into them), first differences only."""
    if type(a) is not type(b):
        return [f"{where}: {json.dumps(a)[:80]} -> {json.dumps(b)[:80]}"]
    if isinstance(a, dict):
        out: list[str] = []
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                out.append(f"{where}.{k}: {'added' if k not in a else 'removed'}")
            else:
                out += diff(a[k], b[k], f"{where}.{k}")
        return out
    if isinstance(a, list):
        if len(a) != len(b):
            return [f"{where}: {len(a)} items -> {len(b)}"]
        return [d for k, (x, y) in enumerate(zip(a, b)) for d in diff(x, y, f"{where}[{k}]")]
    return [] if a == b else [f"{where}: {json.dumps(a)[:80]} -> {json.dumps(b)[:80]}"]


def compare(name: str) -> list[str]:
    """The differences between the stored golden ``name`` and a fresh run."""
    stored = json.loads((DATA / f"{name}.json").read_text(encoding="utf-8"))
    fresh = json.loads(json.dumps(recorders()[name](), sort_keys=True))
    return diff(stored, fresh, name)


def main(argv: list[str]) -> int:
    if not argv or argv[0] not in ("record", "compare"):
        print(__doc__, file=sys.stderr)
        return 2
    names = argv[1:] or list(recorders())
    if argv[0] == "record":
        record(names)
        return 0
    bad = 0
    for name in names:
        found = compare(name)
        print(f"{name}: {'identical' if not found else f'{len(found)} differences'}")
        for line in found[:20]:
            print("  " + line)
        bad += bool(found)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
