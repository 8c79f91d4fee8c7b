"""A Segmentation as the payload of schema ``clear.segmentation`` (documented in the
README and `clearcli/commands/segment.py`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from clearcli.io.frames import object_label
from clearcli.rounding import rounded, timings

if TYPE_CHECKING:
    from clearcli.perception.types import Segmentation

SCHEMA = "segmentation"
# version 1 had no rims of open containers and no table edges; version 2 no `support`
# (which surface the objects stand on, and why) and no `excluded` (issue 37)
VERSION = 3


def _surface(v: Any) -> dict[str, Any]:
    return {
        "normal": rounded(np.asarray(v.normal)),
        "offset": rounded(v.offset_m),
        "area_m2": rounded(v.area_m2),
        "standing_points": int(v.standing_points),
    }


def _support(seg: Segmentation) -> dict[str, Any]:
    chosen = [v for v in seg.support if v.chosen]
    return {
        "chosen": _surface(chosen[0]) if chosen else None,
        "why": chosen[0].why if chosen else "the segmentation came from elsewhere (labels)",
        "rejected": [{**_surface(v), "why": v.why} for v in seg.support if not v.chosen],
    }


def _rim(opening: Any) -> dict[str, Any] | None:
    rim = opening.rim
    if rim is None:
        return None
    return {
        "center": rounded(rim.center),
        "radius_m": rounded(rim.radius_m),
        "height_m": rounded(rim.height_m),
        "wall_m": rounded(rim.wall_m),
        "inside_depth_m": rounded(rim.inside_depth_m),
        "arc_deg": rounded(rim.arc_deg),
    }


def segmentation_payload(seg: Segmentation) -> dict[str, Any]:
    return {
        "source": seg.source,
        "frame_id": seg.frame_id,
        "stamp_s": float(seg.stamp_s),
        "n_points": int(seg.n_points),
        "table": {
            "normal": rounded(seg.table.normal),
            "offset": rounded(seg.table.offset),
            "polygon": rounded(seg.table_polygon),
            "n_points": int(seg.table_indices.shape[0]),
            # how the support was chosen (README "Which plane is the table")
            "planes": [
                {
                    "normal": rounded(np.asarray(v.normal)),
                    "offset": rounded(v.offset_m),
                    "area_m2": rounded(v.area_m2),
                    "standing_points": int(v.standing_points),
                    "chosen": bool(v.chosen),
                    "why": v.why,
                }
                for v in seg.support
            ],
            "beyond_edge_m2": rounded(seg.beyond_edge_m2),
            # the polygon's sides and whether the camera sees the table end there (a
            # flat object is slid only to such a side): clearcli/perception/openings.py
            "edges": [
                {"start": rounded(e.start), "end": rounded(e.end), "seen": bool(e.seen), "why": e.why}
                for e in seg.table_edges
            ],
        },
        "support": _support(seg),
        "excluded": [
            {"points": int(e.indices.shape[0]), "centroid": rounded(e.centroid), "reason": e.reason}
            for e in seg.excluded
        ],
        "objects": [
            {
                "id": k,
                "label": object_label(k),
                "n_points": obj.n_points,
                "centroid": rounded(obj.centroid),
                "obb": {
                    "center": rounded(obj.obb_center),
                    "axes": rounded(obj.obb_axes),
                    "extents": rounded(obj.obb_extents),
                },
                "principal_axes": rounded(obj.principal_axes),
                # an open container's rim (sensor frame; height above the table), else why not
                "rim": _rim(seg.openings[k]) if k < len(seg.openings) else None,
                "rim_why": seg.openings[k].why if k < len(seg.openings) else "",
            }
            for k, obj in enumerate(seg.objects)
        ],
        "color": {"used": bool(seg.color_used), "note": seg.color_note},
        "timings_s": timings(seg.timings_s),
    }
