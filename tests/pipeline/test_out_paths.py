"""Where a run writes (simlunar.pipeline.out_paths)."""

from __future__ import annotations

import pytest

from simlunar.errors import ResultFolderError
from simlunar.pipeline import preflight
from simlunar.pipeline.out_paths import check_out_dir, check_out_file


def test_a_new_folder_under_a_writable_one_is_accepted_and_not_made(tmp_path):
    out = tmp_path / "a" / "b"
    assert check_out_dir(out) == out and not (tmp_path / "a").exists()


def test_a_file_is_no_result_folder(tmp_path):
    f = tmp_path / "f"
    f.write_text("x")
    with pytest.raises(ResultFolderError, match=f"--out {f}: is a file, not a folder"):
        check_out_dir(f)
    with pytest.raises(ResultFolderError, match="is a file, so no folder can be made in it"):
        check_out_dir(f / "sub", option="--save")


def test_units_must_be_a_folder(tmp_path):
    (tmp_path / "units").write_text("x")
    with pytest.raises(ResultFolderError, match="units is not a folder"):
        check_out_dir(tmp_path)


def test_out_file_is_not_a_folder(tmp_path):
    assert check_out_file(tmp_path / "new" / "x.png") == tmp_path / "new" / "x.png"
    with pytest.raises(ResultFolderError, match=f"--out {tmp_path}: is a folder, not a file"):
        check_out_file(tmp_path)


def test_preflight_re_exports_the_checks():
    assert preflight.check_out_dir is check_out_dir and preflight.check_out_file is check_out_file
