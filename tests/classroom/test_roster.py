"""The class roster: what it admits, what it refuses (whole, with every bad line), and its file."""

import os
import stat

import pytest

from mt_widgets.classroom.roster import (
    RESERVED_LOGINS,
    Roster,
    RosterEntry,
    RosterError,
    format_roster,
    login_problem,
    parse_roster,
    read_roster,
    write_roster,
)

CLASS = """login,name,email,role
instructor,Dana Scully,dana@example.edu,instructor
tom,Tom Hart,,TA
ann,Ann Lee,ann@example.edu,
bo,"Chen, Bo",,student
"""


def problems_of(text):
    with pytest.raises(RosterError) as caught:
        parse_roster(text, source="class.csv")
    return caught.value


def test_a_roster_gives_its_people_in_file_order_with_roles():
    roster = parse_roster(CLASS)
    assert roster.logins == ("instructor", "tom", "ann", "bo")
    assert [e.login for e in roster.students] == ["ann", "bo"]
    assert [e.login for e in roster.admins] == ["instructor", "tom"]
    assert roster.entry("tom").role == "ta"
    assert roster.entry("bo") == RosterEntry("bo", "Chen, Bo", "", "student")
    assert roster.entry("ann").email == "ann@example.edu"
    assert "ann" in roster and "zed" not in roster and len(roster) == 4


def test_only_the_login_column_is_required_and_the_role_defaults_to_student():
    roster = parse_roster("login\nann\n\nbo\n")
    assert roster.entries == (RosterEntry("ann"), RosterEntry("bo"))
    assert roster.admins == ()


def test_columns_may_come_in_any_order_with_a_byte_order_mark_and_crlf():
    roster = parse_roster("\ufeffRole,Login\r\ninstructor,dana\r\n,ann\r\n")
    assert roster.entry("dana").role == "instructor"
    assert roster.entry("ann").role == "student"


def test_a_bad_roster_is_refused_whole_listing_every_bad_line_with_its_reason():
    error = problems_of("login,name,role\n"
                        "ann,Ann,student\n"        # 2 fine
                        "bob,\"Bob,student\n"      # 3 unclosed quote
                        "cat,Cat\n"                # 4 two fields of three
                        ",Nobody,student\n"        # 5 no login
                        "ann,Ann again,student\n"  # 6 duplicate
                        "Dan,Dan,student\n"        # 7 upper case
                        "root,Mallory,student\n"   # 8 reserved
                        "eve;rm -rf,Eve,\n"        # 9 unsafe
                        "fay,Fay,boss\n")          # 10 unknown role
    lines = [line for line, _ in error.problems]
    assert lines == [3, 4, 5, 6, 7, 8, 9, 10]
    reasons = dict(error.problems)
    assert "malformed" in reasons[3]
    assert "wrong number of fields: 2" in reasons[4]
    assert reasons[5] == "missing login"
    assert "duplicate login 'ann' (first on line 2)" == reasons[6]
    assert "unsafe login 'Dan'" in reasons[7] and "lower case" in reasons[7]
    assert "reserved" in reasons[8]
    assert "unsafe login 'eve;rm -rf'" in reasons[9]
    assert "unknown role 'boss'" in reasons[10]
    message = str(error)
    assert "class.csv, line 3:" in message and "class.csv, line 10:" in message
    assert "nothing applied" in message and "8 bad lines" in message


def test_a_header_with_an_unknown_or_missing_column_is_refused():
    assert dict(problems_of("login,phone\nann,123\n").problems) == {
        1: "unknown column 'phone': expected some of login, name, email, role"}
    assert "no 'login' column" in str(problems_of("name,role\nAnn,student\n"))
    assert "appears twice" in str(problems_of("login,login\nann,ann\n"))
    assert "empty roster" in str(problems_of("\n  \n"))


@pytest.mark.parametrize("login", ["a", "_svc", "ann-lee", "a1_b-2", "x" * 32])
def test_logins_safe_as_system_user_names_are_accepted(login):
    assert login_problem(login) is None
    assert parse_roster(f"login\n{login}\n").logins == (login,)


@pytest.mark.parametrize("login", ["1ann", "-ann", "ann.lee", "ann lee", "x" * 33, "ännä", "ann$", "../x",
                                   "Ann"])
def test_logins_unsafe_as_system_user_names_are_refused(login):
    assert "unsafe login" in login_problem(login)


@pytest.mark.parametrize("login", ["root", "daemon", "nobody", "admin", "www-data", "sshd"])
def test_system_account_names_are_refused(login):
    assert login in RESERVED_LOGINS
    assert "reserved" in login_problem(login)
    with pytest.raises(ValueError, match="reserved"):
        RosterEntry(login)


def test_a_name_with_a_control_character_or_a_bad_email_is_refused():
    error = problems_of("login,name,email\nann,Ann\x07,ann@example.edu\nbo,Bo,not-an-address\n")
    assert [line for line, _ in error.problems] == [2, 3]
    assert "control character" in error.problems[0][1]
    assert "not an e-mail address" in error.problems[1][1]


def test_entries_check_their_own_fields():
    with pytest.raises(ValueError, match="unknown role 'dean'"):
        RosterEntry("ann", role="dean")
    with pytest.raises(ValueError, match="login must be a string, got int"):
        RosterEntry(7)
    with pytest.raises(ValueError, match="appears twice"):
        Roster((RosterEntry("ann"), RosterEntry("ann", "Ann")))
    with pytest.raises(TypeError, match="RosterEntry items, got str"):
        Roster(("ann",))


def test_roster_and_entry_are_immutable_and_edits_give_new_rosters():
    roster = parse_roster(CLASS)
    with pytest.raises(AttributeError):
        roster.entries = ()
    with pytest.raises(AttributeError):
        roster.entries[0].role = "student"
    added = roster.with_entry(RosterEntry("cy", "Cy"))
    assert added.logins[-1] == "cy" and "cy" not in roster
    promoted = added.with_entry(RosterEntry("ann", "Ann Lee", "ann@example.edu", "ta"))
    assert promoted.logins == added.logins and promoted.entry("ann").role == "ta"
    assert roster.entry("ann").role == "student"
    removed = promoted.without("bo")
    assert "bo" not in removed and "bo" in promoted


def test_an_unknown_login_raises_key_error_naming_the_roster_size():
    roster = parse_roster(CLASS)
    with pytest.raises(KeyError, match=r"'zed' is not on the roster \(4 logins\)"):
        roster.entry("zed")
    with pytest.raises(KeyError, match="'zed'"):
        roster.without("zed")


def test_wrong_types_are_type_errors():
    with pytest.raises(TypeError, match="text: expected"):
        parse_roster(b"login\nann\n")
    with pytest.raises(TypeError, match="path: expected"):
        read_roster(3)
    with pytest.raises(TypeError, match="entry: expected a RosterEntry"):
        Roster().with_entry("ann")


def test_a_written_roster_reads_back_the_same_and_only_its_owner_can_read_it(tmp_path):
    roster = parse_roster(CLASS).with_entry(RosterEntry("q", 'Quinn "Q" O\'Neil, Jr', "q@example.org"))
    path = tmp_path / "roster.csv"
    path.write_text("login\nold\n")
    os.chmod(path, 0o644)
    write_roster(roster, path)
    assert read_roster(path) == roster
    assert parse_roster(format_roster(roster)) == roster
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert sorted(p.name for p in tmp_path.iterdir()) == ["roster.csv"]


def test_a_failed_write_leaves_the_old_roster_and_no_temporary_file(tmp_path, monkeypatch):
    path = tmp_path / "roster.csv"
    path.write_text("login\nold\n")

    def refuse(*args):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", refuse)
    with pytest.raises(OSError, match="disk full"):
        write_roster(parse_roster(CLASS), path)
    assert path.read_text() == "login\nold\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["roster.csv"]


def test_reading_names_the_file_and_the_line_of_bytes_that_are_not_utf8(tmp_path):
    path = tmp_path / "latin1.csv"
    path.write_bytes("login,name\nann,Ann\nzoe,Zoë\n".encode("latin-1"))
    with pytest.raises(RosterError, match=r"latin1\.csv, line 3: not UTF-8"):
        read_roster(path)
    with pytest.raises(FileNotFoundError):
        read_roster(tmp_path / "missing.csv")
