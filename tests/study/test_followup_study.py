"""paper-sim-followup end to end: synthetic teachers run main and, four simulated weeks later, the
follow-up (forgetting in between); the logs, the tidy rows and the BIDS export carry the sessions
(validated), and the analysis compares across sessions with the same tests and figures."""

import csv
import math

import numpy as np
import pytest
from bids_validator import BIDSValidator

from mt_widgets.analysis import analyse_study
from mt_widgets.in_silico import Forgetting, run_in_silico, run_through_sessions
from mt_widgets.study import export_bids, load_protocol, read_events, read_study

pytestmark = pytest.mark.slow  # four synthetic participants through two sessions of the paper's protocol

DAY = 86400.0


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    root = tmp_path_factory.mktemp("followup")
    return run_through_sessions(root / "study", n_participants=4, protocol="paper-sim-followup", seed=2,
                                forgetting=Forgetting(30.0))


def test_every_participant_ran_both_sessions_in_the_window_keeping_their_group(study):
    for pid in study.participant_ids():
        main, _ = read_events(study.log_path(pid))
        followup, _ = read_events(study.log_path(pid, "followup"))
        assert main[0]["session"] == "main" and followup[0]["session"] == "followup"
        assert followup[0]["group"] == main[0]["group"] == study.enrolment(pid)["group"]
        assert followup[0]["window"]["status"] == "open"
        assert followup[0]["window"]["delay_s"] == pytest.approx(28 * DAY, abs=1)
        assert [e["phase"] for e in followup if e["type"] == "episode_finished"] == ["F1", "F2"]
    assert {row["state"] for row in study.status()} == {"completed"}


def test_the_tidy_rows_and_the_bids_export_carry_the_sessions(study, tmp_path):
    episodes, _ = read_study(study.folder)
    assert [(r["session"], r["phase"]) for r in episodes if r["participant"] == "S001"][-3:] == [
        ("main", "P5"), ("followup", "F1"), ("followup", "F2")]
    out = export_bids(study.folder, tmp_path / "bids")
    files = sorted("/" + str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert "/sub-S001/ses-main/beh/sub-S001_ses-main_task-papersimfollowup_beh.tsv" in files
    assert "/sub-S001/ses-followup/beh/sub-S001_ses-followup_task-papersimfollowup_beh.tsv" in files
    assert "/sub-S001/sub-S001_sessions.tsv" in files
    validator = BIDSValidator()
    assert [f for f in files if not validator.is_bids(f)] == []
    assert not validator.is_bids("/sub-S001/ses-followup/beh/sub-S001_task-papersimfollowup_beh.tsv")
    with open(out / "sub-S001" / "sub-S001_sessions.tsv", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle, delimiter="\t"))
    assert [r["session_id"] for r in rows] == ["ses-main", "ses-followup"]
    assert rows[0]["window_status"] == "first session" and rows[1]["window_status"] == "open"
    assert float(rows[1]["delay_days"]) == pytest.approx(28, abs=1e-3)
    with open(out / "sub-S001" / "ses-followup" / "beh" / "sub-S001_ses-followup_task-papersimfollowup_beh.tsv",
              encoding="utf-8") as handle:
        assert {r["phase"] for r in csv.DictReader(handle, delimiter="\t")} == {"F1", "F2"}


def test_the_analysis_compares_across_sessions_with_the_same_tests_and_figures(study):
    result = analyse_study(study.folder, trajectories_for=[])
    between = result.statistics.between
    assert list(between["change"]) == ["P1_to_P3E8", "P1_to_P4", "P2_to_P5", "P1_to_F1", "P2_to_F2"]
    assert not between[["student_p", "welch_p", "mannwhitney_p"]].isna().any().any()
    ticks = [t.get_text() for t in result.figures["error_by_episode"].axes[0].get_xticklabels()]
    assert ticks[-3:] == ["P5E1", "F1E1", "F2E1"] and len(ticks) == 14
    assert [ax.get_title().split("\n")[0] for ax in result.figures["changes"].axes][-2:] == ["P1 -> F1", "P2 -> F2"]
    assert "retention at the follow-up" in result.summary()


def test_forgetting_leaves_the_main_session_alone_and_costs_skill_at_the_followup():
    protocol = load_protocol("paper-sim-followup")
    kept = run_in_silico(24, protocol, seed=4, reproduce=False).episodes
    forgot = run_in_silico(24, protocol, seed=4, reproduce=False, forgetting=Forgetting(14.0)).episodes
    main = kept["session"] == "main"
    assert np.array_equal(kept.loc[main, "teaching_error"], forgot.loc[main, "teaching_error"])
    target_f1 = (kept["phase"] == "F1") & (kept["group"] == "target")
    assert forgot.loc[target_f1, "teaching_error"].mean() > kept.loc[target_f1, "teaching_error"].mean()
    # A very long half-life forgets nothing measurable.
    same = run_in_silico(24, protocol, seed=4, reproduce=False, forgetting=Forgetting(math.inf)).episodes
    assert np.allclose(same["teaching_error"], kept["teaching_error"])


def test_forgetting_is_the_documented_half_life():
    assert Forgetting(30.0).retained(30 * DAY) == pytest.approx(0.5)
    assert Forgetting(30.0).retained(0.0) == 1.0 and Forgetting(math.inf).retained(365 * DAY) == 1.0
    with pytest.raises(ValueError, match="half_life_days"):
        Forgetting(0)
    with pytest.raises(ValueError, match="half_life_days"):
        Forgetting(True)
