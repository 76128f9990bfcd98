"""The one crash-safe JSON-lines module (mt_widgets/study/jsonl.py) that the study log and the
class progress files share: a torn last line is ended before the next record and reported
apart when read, and no module reaches into another's private helpers to get at it."""

import ast
from pathlib import Path

from mt_widgets.study.jsonl import Lock, LogError, append_line, encode, read_jsonl

PACKAGE = Path(__file__).resolve().parents[2] / "mt_widgets"


def test_a_torn_last_line_is_ended_kept_and_reported_by_the_next_append(tmp_path):
    path = tmp_path / "log.jsonl"
    assert append_line(path, encode({"n": 0})) == 0
    with open(path, "ab") as file:
        file.write(b'{"n": 1, "tor')  # a writer killed mid-line
    seen = []
    torn = append_line(path, lambda bytes_torn: seen.append(bytes_torn) or encode({"n": 2, "repairs": bytes_torn}))
    assert torn == seen[0] == len(b'{"n": 1, "tor')
    assert path.read_bytes() == b'{"n":0}\n{"n": 1, "tor\n{"n":2,"repairs":13}\n'
    contents = read_jsonl(path)
    assert [line.value for line in contents.lines] == [{"n": 0}, None, {"n": 2, "repairs": 13}]
    assert contents.tail is None and contents.torn_tail == 0


def test_reading_reports_an_unfinished_last_line_apart_and_keeps_one_missing_only_its_newline(tmp_path):
    path = tmp_path / "log.jsonl"
    path.write_bytes(b'{"n":0}\n\n[1, 2]\n{"n":3}')
    contents = read_jsonl(path)
    assert [(line.number, line.value, line.blank) for line in contents.lines] == [
        (1, {"n": 0}, False), (2, None, True), (3, None, False)]
    assert contents.tail.number == 4 and contents.tail.value == {"n": 3} and contents.torn_tail == 0
    path.write_bytes(b'{"n":0}\n{"n":')
    assert read_jsonl(path).torn_tail == len(b'{"n":')


def test_a_held_lock_makes_another_writer_fail_by_name(tmp_path):
    with Lock(tmp_path / ".locks" / "a.lock", "student 'ada'"):
        try:
            Lock(tmp_path / ".locks" / "a.lock", "student 'ada'", timeout_s=0.1)
        except LogError as error:
            assert "student 'ada' is in use" in str(error)
        else:
            raise AssertionError("a second holder got the lock")


def test_no_package_imports_another_packages_private_names():
    # (classroom once took study.log's _Lock, _write_all and _fsync_folder.)
    for path in PACKAGE.rglob("*.py"):
        own = path.relative_to(PACKAGE).parts[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or "").startswith("mt_widgets."):
                other = node.module.split(".")[1]
                private = [alias.name for alias in node.names if alias.name.startswith("_")]
                assert other == own or not private, \
                    f"{path.relative_to(PACKAGE)} imports {private} from {node.module}"
