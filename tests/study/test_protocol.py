"""Protocols as data: the paper's protocol ships as files, and bad files are refused precisely."""

import json
import re
from pathlib import Path

import pytest

from mt_widgets import SKILLS
from mt_widgets.study import ProtocolError, load_protocol, parse_protocol

from .scripted import SHORT_PROTOCOL


@pytest.mark.parametrize("name, robot", [("paper-sim", "sim"), ("paper-uarm", "uarm")])
def test_shipped_protocols_are_the_papers(name, robot):
    protocol = load_protocol(name)
    table = [(p.id, p.skill, p.episodes, p.guidance) for p in protocol.phases]
    assert table == [("P1", f"{robot}-point", 1, ()), ("P2", f"{robot}-line", 1, ()),
                     ("P3", f"{robot}-point", 8, ("target",)), ("P4", f"{robot}-point", 1, ()),
                     ("P5", f"{robot}-line", 1, ())]
    assert protocol.practice.duration_s == 120
    assert protocol.groups == ("target", "control")
    # The teaching budget is N = S per episode: 5 in simulation, 3 on the uArm.
    assert {p.demonstrations for p in protocol.phases} == {SKILLS[f"{robot}-point"].n_features}
    # Query states differ in every phase (the paper's text).
    assert len({p.states_index for p in protocol.phases}) == 5


def test_texts_shown_to_participants_never_mention_groups_or_guidance():
    for name in ("paper-sim", "paper-uarm"):
        protocol = load_protocol(name)
        shown = list(protocol.texts.values()) + [protocol.practice.text] + [p.instructions for p in protocol.phases]
        for text in shown:
            for word in (*protocol.groups, "guidance", "guided", "group", "optimal", "feedback"):
                assert not re.search(rf"\b{word}\b", text, re.IGNORECASE), (name, word, text)


def test_the_hash_ignores_comments_and_changes_with_the_protocol():
    base = parse_protocol(SHORT_PROTOCOL)
    assert parse_protocol("# a comment\n" + SHORT_PROTOCOL).hash == base.hash
    assert parse_protocol(SHORT_PROTOCOL.replace("episodes = 3", "episodes = 4")).hash != base.hash


def line_of(text, needle, occurrence=1):
    lines = [i for i, line in enumerate(text.splitlines(), start=1) if needle in line]
    return lines[occurrence - 1]


def test_a_missing_field_is_named_with_its_table_line():
    text = SHORT_PROTOCOL.replace('skill = "uarm-line"\n', "")
    with pytest.raises(ProtocolError) as error:
        parse_protocol(text, "mine.toml")
    assert error.value.field == "phases[1].skill"
    assert error.value.line == line_of(text, "[[phases]]", 2)
    assert "missing required field" in str(error.value) and "mine.toml, line" in str(error.value)


def test_an_unknown_skill_is_named_with_its_line():
    text = SHORT_PROTOCOL.replace('skill = "uarm-line"', 'skill = "uarm-circle"')
    with pytest.raises(ProtocolError) as error:
        parse_protocol(text)
    assert (error.value.field, error.value.line) == ("phases[1].skill", line_of(text, "uarm-circle"))
    assert "'uarm-circle'" in str(error.value) and "sim-point" in str(error.value)


@pytest.mark.parametrize("old, new, field, expected", [
    ("episodes = 3", "episodes = 0", "phases[1].episodes", "expected an integer >= 1 and <= 1000, got 0"),
    ("episodes = 3", "episodes = 2.5", "phases[1].episodes", "expected an integer, got float 2.5"),
    ("episodes = 3", "episodes = 3\ndemonstrations = -1", "phases[1].demonstrations", ">= 1 and <= 1000, got -1"),
    ("block_size = 2", "block_size = 3", "assignment.block_size", "multiple of the 2 groups"),
    ("duration_s = 5", "duration_s = -5", "practice.duration_s", "got -5"),
    ('guidance = ["target"]', 'guidance = ["treatment"]', "phases[1].guidance", "got ['treatment']"),
    ("seed = 11", "seed = -1", "seed", ">= 0, got -1"),
    ('id = "C"', 'id = "A"', "phases[2].id", "unique phase id"),
    ("episodes = 3", "episodes = 3\nepisdoes = 3", "phases[1].episdoes", "unknown field"),
])
def test_impossible_values_are_refused_with_line_and_field(old, new, field, expected):
    text = SHORT_PROTOCOL.replace(old, new, 1)
    with pytest.raises(ProtocolError) as error:
        parse_protocol(text)
    assert error.value.field == field
    assert expected in str(error.value)
    assert error.value.line is not None
    assert new.splitlines()[-1].split("=")[0].strip() in text.splitlines()[error.value.line - 1] \
        or text.splitlines()[error.value.line - 1].startswith("[")


def test_a_toml_syntax_error_gives_its_line():
    text = SHORT_PROTOCOL.replace("episodes = 3", "episodes = = 3")
    with pytest.raises(ProtocolError) as error:
        parse_protocol(text)
    assert error.value.line == line_of(text, "= = 3") and "not valid TOML" in str(error.value)


def test_json_protocols_work_and_name_the_field_and_line():
    protocol = parse_protocol(SHORT_PROTOCOL)
    text = json.dumps(protocol.data, indent=2)
    assert parse_protocol(text, "p.json").hash == protocol.hash
    broken = json.loads(text)
    broken["phases"][2]["episodes"] = 0
    broken_text = json.dumps(broken, indent=2)
    with pytest.raises(ProtocolError) as error:
        parse_protocol(broken_text, "p.json")
    assert error.value.field == "phases[2].episodes"
    assert '"episodes": 0' in broken_text.splitlines()[error.value.line - 1]


def test_states_from_reuses_an_earlier_phases_query_states_only_when_compatible():
    text = SHORT_PROTOCOL.replace('id = "C"\nskill = "uarm-point"', 'id = "C"\nskill = "uarm-point"\nstates_from = "A"')
    assert parse_protocol(text).phases[2].states_index == 0
    bad = SHORT_PROTOCOL.replace('id = "C"\nskill = "uarm-point"', 'id = "C"\nskill = "uarm-point"\nstates_from = "B"')
    with pytest.raises(ProtocolError, match="same skill"):
        parse_protocol(bad)


def test_a_missing_file_names_the_shipped_protocols(tmp_path):
    with pytest.raises(FileNotFoundError, match="paper-sim"):
        load_protocol(tmp_path / "nope.toml")


def test_a_protocol_pickles_for_worker_processes():
    # In-silico studies send the protocol to a process pool (mt_widgets/in_silico/engine.py).
    import pickle

    protocol = load_protocol("paper-sim")
    copy = pickle.loads(pickle.dumps(protocol))
    assert copy.skills["sim-point"].key == "sim-point" and set(copy.skills) == set(protocol.skills)
    with pytest.raises(TypeError):
        protocol.skills["sim-point"] = None


def _with_learner(line: str) -> str:
    protocols = Path(__file__).resolve().parents[2] / "mt_widgets" / "study" / "protocols"
    source = (protocols / "paper_uarm.toml").read_text()
    return source.replace('lambda = 0.01\n', f'lambda = 0.01\n{line}\n', 1)


def test_a_protocol_names_its_learner_and_ridge_is_the_default():
    assert parse_protocol(_with_learner(""), check_files=False).learner == "ridge"
    assert parse_protocol(_with_learner('learner = "ridge"'), check_files=False).learner == "ridge"


def test_an_unknown_learner_names_the_line_and_the_learners_available():
    text = _with_learner('learner = "svm"')
    line = text.splitlines().index('learner = "svm"') + 1
    available = r"\(ridge, kernel-ridge, gaussian-process, neural-network, reward\)"
    with pytest.raises(ProtocolError, match=rf"line {line}.*unknown learner 'svm'; expected one of the available "
                                            rf"learners {available}"):
        parse_protocol(text, check_files=False)
    with pytest.raises(ProtocolError, match="the learner 'kernel-ridge' exists .* teach ridge only so far"):
        parse_protocol(_with_learner('learner = "kernel-ridge"'), check_files=False)
    with pytest.raises(ProtocolError, match="learner.*expected text"):
        parse_protocol(_with_learner("learner = 3"), check_files=False)
