"""Tests of clearcli/io/messages.py: decoded messages become frames, or are refused."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from clearcli.io.messages import pointcloud2_frame


def _cloud(height: int, width: int, data: bytes, row_step: int | None = None) -> SimpleNamespace:
    fields = [SimpleNamespace(name=n, offset=4 * k, datatype=7, count=1) for k, n in enumerate("xyz")]
    return SimpleNamespace(
        header=SimpleNamespace(stamp=SimpleNamespace(sec=1, nanosec=0), frame_id="cam"),
        height=height,
        width=width,
        fields=fields,
        is_bigendian=False,
        point_step=12,
        row_step=width * 12 if row_step is None else row_step,
        data=data,
        is_dense=True,
    )


def test_a_whole_message_is_read() -> None:
    pts = np.arange(2 * 3 * 3, dtype=np.float32)
    frame = pointcloud2_frame(_cloud(2, 3, pts.tobytes()), 0, "t")
    assert frame.shape == (2, 3) and frame.points.tolist() == pts.reshape(-1, 3).tolist()


@pytest.mark.parametrize(
    "height, width, n_points, row_step",
    [
        (0, 4, 4, None),  # height 0 with data
        (1, 2, 4, None),  # width halved: the data is twice too long
        (2, 2, 3, None),  # data cut short
        (1, 4, 4, 24),  # a row_step shorter than width x point_step
    ],
)
def test_a_message_that_lies_about_its_layout_is_refused(height: int, width: int, n_points: int, row_step) -> None:
    data = np.zeros(n_points * 3, dtype=np.float32).tobytes()
    with pytest.raises(ValueError, match="damaged PointCloud2"):
        pointcloud2_frame(_cloud(height, width, data, row_step), 0, "t")
