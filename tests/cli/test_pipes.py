"""Tables printed to a pipe or a file are whole: no cell cut to 80 columns."""

from __future__ import annotations

import shutil
from pathlib import Path

from helpers import REPO
from helpers import run_clear as clear


def test_piped_batch_table_prints_every_cell_whole(tmp_path: Path) -> None:
    folder = tmp_path / ("a_folder_with_a_long_name_" * 4)
    folder.mkdir()
    name = "a_frame_whose_name_is_far_longer_than_eighty_columns_of_a_terminal_" * 2 + ".pcd"
    shutil.copy(REPO / "fixtures" / "isolated_box.pcd", folder / name)
    shutil.copy(REPO / "fixtures" / "box_on_box.pcd", folder / "second.pcd")
    proc = clear("segment", folder, "--jobs", "1")
    assert proc.returncode == 0, proc.stderr
    assert "…" not in proc.stdout
    assert str(folder / name) in proc.stdout
