"""Names beside pseudonyms: computed from the roster, kept outside the class folder, for the owner only."""

from __future__ import annotations

import json
import os

import pytest

from mt_widgets.apps.class_view import ClassView
from mt_widgets.classroom import ProgressRecorder, pseudonym, read_class_meta
from mt_widgets.classroom.names import NamesFileError, class_names, main, read_names, write_names
from mt_widgets.classroom.roster import read_roster


@pytest.fixture
def a_class(tmp_path):
    folder = tmp_path / "class"
    for login in ("ann", "bo"):
        ProgressRecorder(folder, login).record("episode", lesson="a5", skill="sim-point", error=1.0)
    roster = tmp_path / "private" / "roster.csv"
    roster.parent.mkdir()
    roster.write_text("login,name,email,role\nann,Ann Lee,ann@example.edu,\nbo,,,student\n"
                      "dana,Dana Scully,,instructor\n")
    return folder, roster


def test_names_are_the_roster_students_by_their_pseudonym(a_class):
    folder, roster = a_class
    salt = read_class_meta(folder)["salt"]
    names = class_names(read_roster(roster), folder)
    # The instructor is not a student; a student without a name is shown by login.
    assert names == {pseudonym("ann", salt): "Ann Lee", pseudonym("bo", salt): "bo"}


def test_the_names_file_is_owner_only_outside_the_class_and_refused_when_others_can_read_it(a_class, tmp_path):
    folder, roster = a_class
    out = write_names(roster, folder, tmp_path / "private" / "names.json")
    assert oct(out.stat().st_mode & 0o777) == "0o600"
    assert set(read_names(out).values()) == {"Ann Lee", "bo"}
    with pytest.raises(NamesFileError, match="outside the class folder"):
        write_names(roster, folder, folder / "names.json")
    os.chmod(out, 0o644)
    with pytest.raises(NamesFileError, match="chmod 600"):
        read_names(out)
    # Nothing in the class folder names anyone.
    assert not any("Ann" in p.read_text() or "ann" in p.name for p in folder.iterdir() if p.is_file())


def test_the_command_line_writes_the_file(a_class, tmp_path, capsys):
    folder, roster = a_class
    assert main([str(roster), str(folder), str(tmp_path / "names.json")]) == 0
    assert "MT_WIDGETS_CLASS_NAMES" in capsys.readouterr().out
    assert json.loads((tmp_path / "names.json").read_text())["format"] == 1


def test_the_class_view_shows_names_only_when_given_a_private_names_file(a_class, tmp_path):
    folder, roster = a_class
    out = write_names(roster, folder, tmp_path / "names.json")
    view = ClassView(folder, refresh_s=0, names=out)
    assert "Ann Lee" in view.table.value and "<th>name</th>" in view.table.value
    plain = ClassView(folder, refresh_s=0)
    assert "Ann Lee" not in plain.table.value and "<th>name</th>" not in plain.table.value
    os.chmod(out, 0o640)
    careless = ClassView(folder, refresh_s=0, names=out)
    assert "Ann Lee" not in careless.table.value and "names not shown" in careless.problems.value
