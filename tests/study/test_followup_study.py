"""paper-sim-followup end to end: synthetic teachers run main and, four simulated weeks later, the
follow-up (forgetting in between); the logs, the tidy rows and the BIDS export carry the sessions
(validated), and the analysis compares across sessions with the same tests and figures."""

import csv
import math

import numpy as np
import pytest
from bids_validator import BIDSValidator

from mt_widgets.analysis import analyse_study
from mt_widgets.analysis.power import simulated_power
from mt_widgets.in_silico import Forgetting, run_in_silico, run_through_sessions
from mt_widgets.study import export_bids, load_protocol, read_events, read_study
from mt_widgets.study.pseudonyms import code_of

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
    code = code_of(study.folder, "S001")
    files = sorted("/" + str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert f"/sub-{code}/ses-main/beh/sub-{code}_ses-main_task-papersimfollowup_beh.tsv" in files
    assert f"/sub-{code}/ses-followup/beh/sub-{code}_ses-followup_task-papersimfollowup_beh.tsv" in files
    assert f"/sub-{code}/sub-{code}_sessions.tsv" in files
    validator = BIDSValidator()
    assert [f for f in files if not validator.is_bids(f)] == []
    assert not validator.is_bids(f"/sub-{code}/ses-followup/beh/sub-{code}_task-papersimfollowup_beh.tsv")
    with open(out / f"sub-{code}" / f"sub-{code}_sessions.tsv", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle, delimiter="\t"))
    assert [r["session_id"] for r in rows] == ["ses-main", "ses-followup"]
    assert rows[0]["window_status"] == "first session" and rows[1]["window_status"] == "open"
    assert float(rows[1]["delay_days"]) == pytest.approx(28, abs=1e-3)
    with open(out / f"sub-{code}" / "ses-followup" / "beh" / f"sub-{code}_ses-followup_task-papersimfollowup_beh.tsv",
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
    assert np.array_equal(kept.loc[main, "theta_error"], forgot.loc[main, "theta_error"])
    target_f1 = (kept["phase"] == "F1") & (kept["group"] == "target")
    assert forgot.loc[target_f1, "theta_error"].mean() > kept.loc[target_f1, "theta_error"].mean()
    # A very long half-life forgets nothing measurable.
    same = run_in_silico(24, protocol, seed=4, reproduce=False, forgetting=Forgetting(math.inf)).episodes
    assert np.allclose(same["theta_error"], kept["theta_error"])


def test_forgetting_is_the_documented_half_life():
    assert Forgetting(30.0).retained(30 * DAY) == pytest.approx(0.5)
    assert Forgetting(30.0).retained(0.0) == 1.0 and Forgetting(math.inf).retained(365 * DAY) == 1.0
    with pytest.raises(ValueError, match="half_life_days"):
        Forgetting(0)
    with pytest.raises(ValueError, match="half_life_days"):
        Forgetting(True)


def test_the_followups_simulated_power_falls_with_faster_forgetting():
    slow = simulated_power(16, n_studies=60, seed=5, protocol="paper-sim-followup", share_states=True,
                           forgetting=Forgetting(30.0), progress=False)
    fast = simulated_power(16, n_studies=60, seed=5, protocol="paper-sim-followup", share_states=True,
                           forgetting=Forgetting(7.0), progress=False)
    assert set(slow.power) == {"P1_to_P3E8", "P1_to_P4", "P2_to_P5", "P1_to_F1", "P2_to_F2"}
    assert slow.power["P1_to_F1"]["student"] > 0.8 > 0.3 > fast.power["P1_to_F1"]["student"]
    assert slow.power["P1_to_P4"] == fast.power["P1_to_P4"]  # forgetting happens after the main session only


def test_the_batched_engine_and_the_session_engine_agree_across_sessions_with_forgetting(study):
    # The module's study: 4 teachers, seed 2, a 30-day half-life, through Session.arrive 28 days later.
    episodes, _ = read_study(study.folder)
    groups = [study.enrolment(pid)["group"] for pid in study.participant_ids()]
    batched = run_in_silico(4, "paper-sim-followup", seed=2, groups=groups, reproduce=False,
                            forgetting=Forgetting(30.0)).episodes
    logged = sorted((r["participant"], r["session"], r["phase"], r["episode"], r["theta_error"]) for r in episodes)
    simulated = sorted(zip(batched["participant"], batched["session"], batched["phase"], batched["episode"],
                           batched["theta_error"]))
    assert [row[:4] for row in logged] == [row[:4] for row in simulated] and len(logged) == 4 * 14
    assert np.allclose([row[4] for row in logged], [row[4] for row in simulated], rtol=0, atol=1e-9)
