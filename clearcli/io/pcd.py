"""PCD reading (pypcd4) into `Frame`. Minimal first version; hardened in the io issue."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from clearcli.errors import InputError
from clearcli.io.frames import Frame


def _unpack_rgb(values: np.ndarray) -> np.ndarray:
    """Packed 0x00RRGGBB (as uint32 or float32 bits) -> (N, 3) uint8."""
    packed = np.ascontiguousarray(values).view(np.uint32) if values.dtype != np.uint32 else values
    rgb = np.empty((packed.shape[0], 3), dtype=np.uint8)
    rgb[:, 0] = (packed >> 16) & 0xFF
    rgb[:, 1] = (packed >> 8) & 0xFF
    rgb[:, 2] = packed & 0xFF
    return rgb


def read_pcd(path: Path) -> Frame:
    import pypcd4

    path = Path(path)
    try:
        cloud = pypcd4.PointCloud.from_path(path)
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except Exception as exc:  # pypcd4 raises many kinds on corrupt input
        raise InputError(f"{path}: not a readable PCD file ({exc})") from None
    meta = cloud.metadata
    data = cloud.pc_data
    names = list(data.dtype.names or ())
    if not {"x", "y", "z"} <= set(names):
        raise InputError(f"{path}: the cloud has no x/y/z fields (fields: {', '.join(names)})")
    points = np.stack([data["x"], data["y"], data["z"]], axis=1).astype(np.float32)
    colors = None
    for cname in ("rgb", "rgba"):
        if cname in names:
            colors = _unpack_rgb(data[cname])
            break
    extra = {n: np.asarray(data[n]) for n in names if n not in ("x", "y", "z", "rgb", "rgba")}
    shape = (int(meta.height), int(meta.width)) if meta.height > 1 else None
    return Frame(points=points, colors=colors, shape=shape, fields=extra, source=str(path))
