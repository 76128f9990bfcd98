"""The shipped online pilot (notebooks/study_online_pilot.toml) is analysed as its phases allow:
its own ``[analysis]`` table, and, for a pilot folder of a protocol without one, the paper's
comparisons that fit its phases (not the paper's P3E8 of a P3 with two episodes)."""

from pathlib import Path

import pytest

from mt_widgets.analysis import analyse_study
from mt_widgets.analysis.statistics import analyse_protocol
from mt_widgets.in_silico import run_through_sessions
from mt_widgets.study import PAPER_CHANGES, load_protocol
from mt_widgets.study.analysis_plan import changes_that_fit
from mt_widgets.study.protocol_schema import parse_protocol

PILOT = Path(__file__).resolve().parents[2] / "notebooks" / "study_online_pilot.toml"


def pilot_without_analysis_table() -> str:
    """The pilot as it shipped before it had an ``[analysis]`` table (a researcher's copy of it)."""
    text = PILOT.read_text(encoding="utf-8")
    start = text.index("\n[analysis]\n")
    return text[:start] + text[text.index("\n[online]\n"):]


def test_the_paper_comparisons_that_fit_are_those_whose_two_episodes_exist():
    assert [c.name for c in changes_that_fit(PAPER_CHANGES, {"P1": 1, "P2": 1, "P3": 8, "P4": 1, "P5": 1})] == [
        "P1_to_P3E8", "P1_to_P4", "P2_to_P5"]
    assert [c.name for c in changes_that_fit(PAPER_CHANGES, {"P1": 1, "P3": 2, "P4": 1})] == ["P1_to_P4"]
    assert changes_that_fit(PAPER_CHANGES, {"P1": 1, "P3": 7, "P5": 1}) == ()


def test_the_shipped_pilot_plans_its_own_comparisons():
    plan = load_protocol(PILOT).analysis
    assert [(c.before, c.after, c.meaning) for c in plan.changes] == [
        (("P1", 1), ("P3", 2), "effect of guidance"), (("P1", 1), ("P4", 1), "retention")]
    assert plan.baseline is None and plan.test == "student" and plan.alternative == "less"


def test_a_protocol_without_an_analysis_table_gets_the_paper_comparisons_its_phases_have():
    protocol = parse_protocol(pilot_without_analysis_table(), "pilot.toml")
    assert [c.name for c in protocol.analysis.changes] == ["P1_to_P4"]
    assert load_protocol("paper-sim").analysis.changes == PAPER_CHANGES


def test_a_protocol_fitting_none_of_the_paper_comparisons_is_told_to_name_its_own():
    text = pilot_without_analysis_table().replace('id = "P1"', 'id = "B1"')
    protocol = parse_protocol(text, "pilot.toml")
    assert protocol.analysis.changes == ()
    with pytest.raises(ValueError, match=r"changes: protocol 'online-pilot' has no comparisons.*\[analysis\] table"):
        analyse_protocol([], protocol)


@pytest.mark.slow   # 8 synthetic participants through the session engine, twice: about 3 s
def test_analyse_study_reports_on_an_in_silico_pilot_and_an_earlier_pilots_folder(tmp_path):
    run_through_sessions(tmp_path / "pilot", n_participants=8, protocol=PILOT, seed=2)
    report = analyse_study(tmp_path / "pilot", trajectories_for=[])
    assert list(report.statistics.between["change"].unique()) == ["P1_to_P3E2", "P1_to_P4"]
    assert "P1 -> P3E2 (effect of guidance)" in report.summary() and report.statistics.baseline.empty
    assert set(report.statistics.changes["participant"]) == {f"S00{i}" for i in range(1, 9)}

    (tmp_path / "earlier.toml").write_text(pilot_without_analysis_table(), encoding="utf-8")
    run_through_sessions(tmp_path / "earlier", n_participants=8, protocol=tmp_path / "earlier.toml", seed=2)
    earlier = analyse_study(tmp_path / "earlier", trajectories_for=[])
    assert list(earlier.statistics.between["change"].unique()) == ["P1_to_P4"]
    assert "P1 -> P4 (retention)" in earlier.summary()
