"""Pseudonymous IDs are checked strictly; block randomisation is balanced, seeded and recorded."""

from collections import Counter

import pytest

from mt_widgets.study import ParticipantIdError, StudyFolder, block_assignment, validate_participant_id

from .scripted import short_protocol


@pytest.mark.parametrize("bad, reason", [
    ("", "empty"),
    ("   ", "empty"),
    (" P01", "spaces at the start or end"),
    ("P/01", "path separators"),
    ("P\\01", "path separators"),
    ("C:P01", "path separators"),
    ("..", "'..'"),
    ("P..01", "'..'"),
    ("P 01", "plain text"),
    ("Pé01", "LATIN SMALL LETTER E WITH ACUTE"),
    ("P01\n", "spaces at the start or end"),
    ("P\x0001", "plain text"),
    ("P.01", "plain text"),
    ("_P01", "start with a letter or a digit"),
    ("-rf", "start with a letter or a digit"),
    ("P" * 65, "at most 64"),
    ("nul", "reserved"),
    (7, "expected text"),
    (None, "expected text"),
])
def test_bad_participant_ids_are_refused_with_the_reason(bad, reason):
    with pytest.raises(ParticipantIdError, match="participant_id") as error:
        validate_participant_id(bad)
    assert reason in str(error.value)


def test_duplicates_are_refused_ignoring_case():
    assert validate_participant_id("P01", ["P02"]) == "P01"
    with pytest.raises(ParticipantIdError, match="already enrolled"):
        validate_participant_id("P01", ["P01"])
    with pytest.raises(ParticipantIdError, match="ignoring case"):
        validate_participant_id("p01", ["P01"])


def test_every_complete_block_is_balanced_and_blocks_differ():
    groups = ("target", "control")
    sequence = [block_assignment(i, groups, 4, seed=1) for i in range(32)]
    for start in range(0, 32, 4):
        assert Counter(sequence[start:start + 4]) == {"target": 2, "control": 2}
    assert len({tuple(sequence[s:s + 4]) for s in range(0, 32, 4)}) > 1


def test_assignment_is_reproducible_and_depends_on_the_seed():
    groups = ("target", "control")
    first = [block_assignment(i, groups, 4, seed=1) for i in range(40)]
    assert first == [block_assignment(i, groups, 4, seed=1) for i in range(40)]
    assert first != [block_assignment(i, groups, 4, seed=2) for i in range(40)]


def test_assignment_with_three_groups_balances_each_block():
    groups = ("a", "b", "c")
    sequence = [block_assignment(i, groups, 6, seed=9) for i in range(12)]
    assert Counter(sequence[:6]) == Counter(sequence[6:]) == {"a": 2, "b": 2, "c": 2}


@pytest.mark.parametrize("block_size", [0, 3, 2.0, True])
def test_a_block_size_that_cannot_balance_is_refused(block_size):
    with pytest.raises(ValueError, match="block_size"):
        block_assignment(0, ("a", "b"), block_size, 1)


def test_enrolment_records_the_assignment_and_follows_the_protocols_sequence(tmp_path):
    protocol = short_protocol()
    study = StudyFolder.create(tmp_path / "study", protocol)
    records = [study.enrol(f"P{i:02d}") for i in range(6)]
    assert [r["group"] for r in records] == [block_assignment(i, protocol.groups, protocol.block_size,
                                                              protocol.assignment_seed) for i in range(6)]
    assert [r["index"] for r in records] == list(range(6))
    # An experimenter's choice is recorded as such and does not shift the randomised sequence.
    manual = study.enrol("X01", group="control")
    assert (manual["method"], manual["group"], manual["block_slot"]) == ("experimenter", "control", None)
    after = study.enrol("P06")
    assert after["group"] == block_assignment(6, protocol.groups, protocol.block_size, protocol.assignment_seed)
    reopened = StudyFolder(tmp_path / "study")
    assert [r["participant"] for r in reopened.enrolments()] == [f"P{i:02d}" for i in range(6)] + ["X01", "P06"]
    with pytest.raises(ParticipantIdError, match="already enrolled"):
        reopened.enrol("p03")
    with pytest.raises(ValueError, match="group"):
        reopened.enrol("P99", group="placebo")
