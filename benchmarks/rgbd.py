"""RGB-D inputs: reading one 640 x 480 depth/colour PNG pair, and `replay` of the RGB-D
MCAP against a point-cloud MCAP of the same nine frames (../shared/data/rgbd).

    .venv/bin/python benchmarks/rgbd.py [--repeat N]

Prints the median time to read one pair (warm: the libraries loaded, the intrinsics file
read once as a batch reads it), the same for the PCD of the same frame, and the
frames per second `clear replay --json` reports on both logs (the point-cloud log is
written here from the nine PCDs, stamps one second apart like the RGB-D log's).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
DATA = REPO.parent / "shared" / "data"


def _median_ms(fn, repeat: int) -> float:
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times) * 1000


def _replay_fps(log: Path) -> tuple[float, int]:
    res = subprocess.run(
        [sys.executable, "-m", "clearcli.cli", "replay", str(log), "--json"], capture_output=True, text=True
    )
    lines = [json.loads(x) for x in res.stdout.splitlines() if x.strip()]
    summary = lines[-1]
    return float(summary["frames_per_s"]), int(summary["frames"])


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()
    from clearcli.io.frames import Frame
    from clearcli.io.mcap_write import write_pointcloud2_mcap
    from clearcli.io.pcd import read_pcd
    from clearcli.io.read import read_frame

    depth = DATA / "rgbd/uois/uois_0003_depth.png"
    pcd = DATA / "scenes/uois_realsense/uois_image_0003.pcd"
    print(
        f"read one 640 x 480 pair (depth + colour PNG, intrinsics): {_median_ms(lambda: read_frame(depth), args.repeat):.1f} ms"
        f" (median of {args.repeat}; target <= 15 ms)"
    )
    print(
        f"read the PCD of the same frame:                             {_median_ms(lambda: read_pcd(pcd), args.repeat):.1f} ms"
    )
    rgbd_log = DATA / "rgbd/uois_realsense_ros2.mcap"
    with tempfile.TemporaryDirectory() as tmp:
        cloud_log = Path(tmp) / "uois_points.mcap"
        frames = []
        for k in range(9):
            f = read_pcd(DATA / f"scenes/uois_realsense/uois_image_{k:04d}.pcd")
            frames.append(
                Frame(f.points, f.colors, f.shape, {}, 1_700_000_000.0 + k, "camera_color_optical_frame", f.source)
            )
        write_pointcloud2_mcap(cloud_log, frames)
        fps_rgbd, n_rgbd = _replay_fps(rgbd_log)
        fps_cloud, n_cloud = _replay_fps(cloud_log)
    print(f"replay, RGB-D MCAP (depth + colour images, camera info): {fps_rgbd:.2f} frames/s ({n_rgbd} frames)")
    print(f"replay, point-cloud MCAP of the same frames:            {fps_cloud:.2f} frames/s ({n_cloud} frames)")


if __name__ == "__main__":
    main()
