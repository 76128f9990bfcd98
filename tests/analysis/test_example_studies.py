"""Regenerating the shipped studies never deletes a folder it was not clearly told to replace."""

import pytest

from mt_widgets.analysis.example_studies import write_example_study


@pytest.mark.parametrize("value", ["no", "false", 0, 1, None])
def test_overwrite_no_keeps_the_existing_folder(tmp_path, value):
    folder = tmp_path / "study"
    folder.mkdir()
    (folder / "keep.txt").write_text("a participant's data")
    with pytest.raises(TypeError, match=r"^overwrite: expected True or False, got "):
        write_example_study(folder, overwrite=value)
    assert (folder / "keep.txt").read_text() == "a participant's data"


def test_without_overwrite_an_existing_folder_is_refused(tmp_path):
    folder = tmp_path / "study"
    folder.mkdir()
    with pytest.raises(FileExistsError, match="overwrite=True"):
        write_example_study(folder)
    assert folder.is_dir()
