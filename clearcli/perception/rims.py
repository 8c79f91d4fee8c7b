"""Stage 3d (ours, not in the thesis): join the inside and the outside of a container.

A bowl, mug or open can shows the camera its outer wall and, over the rim, its inner
wall. The inner wall is concave, so LCCP keeps the two apart. They touch only along the
rim, which is the top of both. So two touching segments are joined when nearly all of
their contact lies within ``rim_tolerance_m`` of the top of each:
- a box on a box touches the lower one at the lower one's top but the upper one's
  bottom: kept apart (unless the upper one is flatter than the tolerance);
- objects side by side touch down a vertical seam: kept apart;
- tall objects side by side, whose lower parts hide each other, touch along their top
  edges: a contact where either voxel lies on a top face (``voxel_is_top``: a
  horizontal patch) is not a rim, which is two walls meeting.
"""

from __future__ import annotations

import numpy as np

from clearcli.perception.context import RefineContext
from clearcli.perception.lccp import join_pairs

# share of the contact (voxel adjacencies) that must be near both tops
_MIN_SHARE_AT_TOP = 0.9
_MIN_CONTACTS = 5


def join_rims(seg_of_voxel: np.ndarray, ctx: RefineContext) -> np.ndarray:
    """The stage: `merge_rims` on the frame's voxels, top faces from the supervoxels."""
    s = ctx.settings
    return merge_rims(
        seg_of_voxel,
        ctx.vox.centroids,
        ctx.voxel_height,
        s.rim_tolerance_m,
        s.rim_contact_m,
        voxel_is_top=ctx.voxel_is_top,
    )


def merge_rims(
    seg_of_voxel: np.ndarray,
    voxel_centroids: np.ndarray,
    voxel_height: np.ndarray,
    tolerance_m: float,
    contact_m: float,
    voxel_is_top: np.ndarray | None = None,
) -> np.ndarray:
    """(V,) segment per voxel after joining segments that touch only along their tops.

    "Touch": voxels of the two within ``contact_m`` (a thin wall seen edge-on at the
    sides of a container loses its depth, so the two walls need not be adjacent)."""
    from scipy.spatial import cKDTree

    n_seg = int(seg_of_voxel.max()) + 1 if seg_of_voxel.size else 0
    if n_seg < 2:
        return seg_of_voxel
    voxel_edges = cKDTree(voxel_centroids).query_pairs(contact_m, output_type="ndarray")
    if voxel_edges.shape[0] == 0:
        return seg_of_voxel
    a, b = seg_of_voxel[voxel_edges[:, 0]], seg_of_voxel[voxel_edges[:, 1]]
    cross = a != b
    if not cross.any():
        return seg_of_voxel
    top = np.full(n_seg, -np.inf)
    np.maximum.at(top, seg_of_voxel, voxel_height)
    ea, eb = a[cross], b[cross]
    ha, hb = voxel_height[voxel_edges[cross, 0]], voxel_height[voxel_edges[cross, 1]]
    h_contact = 0.5 * (ha + hb)
    lo, hi = np.minimum(ea, eb), np.maximum(ea, eb)
    at_top = (h_contact >= top[lo] - tolerance_m) & (h_contact >= top[hi] - tolerance_m)
    if voxel_is_top is not None:
        at_top &= ~(voxel_is_top[voxel_edges[cross, 0]] | voxel_is_top[voxel_edges[cross, 1]])
    key = lo * n_seg + hi
    uniq, inv = np.unique(key, return_inverse=True)
    n_contacts = np.bincount(inv)
    n_top = np.bincount(inv, weights=at_top.astype(np.float64))
    join = (n_contacts >= _MIN_CONTACTS) & (n_top >= _MIN_SHARE_AT_TOP * n_contacts)
    return join_pairs(seg_of_voxel, np.stack([uniq[join] // n_seg, uniq[join] % n_seg], axis=1), n_seg)
