"""The novice baseline of tutorial 00: kept once per phase, compared with the capstone's episodes."""

import pytest

from mt_widgets.classroom.baseline import baseline_changes, read_baseline, save_baseline


def test_the_first_baseline_episode_of_each_phase_is_kept_and_compared(tmp_path):
    path = tmp_path / "lessons" / "baseline.json"
    assert read_baseline(path) == {}
    save_baseline("P1", 2.9, path)
    assert save_baseline("P1", 0.4, path) == {"P1": 2.9}       # a retake, theory known, is not a baseline
    save_baseline("P2", 3.1, path)
    assert read_baseline(path) == {"P1": 2.9, "P2": 3.1}
    changes = baseline_changes(read_baseline(path), {"P1": 1.5, "P4": 1.0, "P5": 2.6})
    assert changes == pytest.approx({"P1(00)_to_P1": -1.4, "P1(00)_to_P4": -1.9, "P2(00)_to_P5": -0.5})
    assert baseline_changes({"P1": 2.9}, {"P4": 1.0}) == pytest.approx({"P1(00)_to_P4": -1.9})
    with pytest.raises(ValueError, match="phase: expected one of P1, P2"):
        save_baseline("P3", 1.0, path)
    with pytest.raises(ValueError, match="error: expected a teaching error"):
        save_baseline("P1", True, path)
