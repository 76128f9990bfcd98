"""The shipped ``industrial-sim`` protocol (the paper's P1-P5 on the UR5) runs end to end headless:
scripted participants of both groups, the tidy CSVs with the third action component, the BIDS
export and the analysis of the paper's protocols."""

import csv
import json

import numpy as np
import pytest

from mt_widgets import SKILLS, RidgeLearner, teaching_risk
from mt_widgets.analysis.study_analysis import analyse_study
from mt_widgets.study import export_bids, export_study, load_protocol
from mt_widgets.study.practice import PRACTICE_SKILLS

from .scripted import scripted_study

#: Participants per group: enough for the paper's tests to have two samples of spread.
PER_GROUP = 4


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    root = tmp_path_factory.mktemp("industrial-sim")
    folder = scripted_study(root, "industrial-sim", 2 * PER_GROUP)
    return folder, root


def test_the_protocol_is_the_papers_five_phases_on_the_ur5_skills_with_a_neutral_3d_practice():
    protocol = load_protocol("industrial-sim")
    assert [(p.id, p.skill, p.episodes, tuple(p.guidance)) for p in protocol.phases] == [
        ("P1", "ur5-reach", 1, ()), ("P2", "ur5-conveyor", 1, ()), ("P3", "ur5-reach", 8, ("target",)),
        ("P4", "ur5-reach", 1, ()), ("P5", "ur5-conveyor", 1, ())]
    practice = PRACTICE_SKILLS[protocol.practice.skill]
    assert protocol.practice.skill not in {p.skill for p in protocol.phases}
    assert practice.plant.action_dim == 3 and practice.plant.drawing().__class__.__name__ == "SpaceDrawing"
    # the practice goal is none of the phases' goals
    goals = [np.asarray(SKILLS[p.skill].target.shape().points) for p in protocol.phases]
    ours = np.asarray(practice.target.shape().points)[0]
    assert min(np.min(np.linalg.norm(g - ours, axis=-1)) for g in goals) > 0.2


def test_every_episode_is_logged_with_3d_actions_and_mt_teaches_each_exactly(study):
    folder, _ = study
    events = [json.loads(line) for line in (folder.folder / "P01.jsonl").read_text().splitlines()]
    finished = [e for e in events if e["type"] == "episode_finished"]
    assert [(e["phase"], e["episode"]) for e in finished] == [
        ("P1", 1), ("P2", 1), *[("P3", k) for k in range(1, 9)], ("P4", 1), ("P5", 1)]
    # a reproduction that met a joint limit or the table stopped cleanly, where it was
    assert all(np.all(np.isfinite(e["reproduction"]["final_position"])) for e in finished)
    for started in (e for e in events if e["type"] == "episode_started"):
        skill = SKILLS[started["skill"]]
        U = np.asarray(started["optimal"])
        assert U.shape == (skill.feature_map.dim, 3)
        learnt = RidgeLearner(lam=0.01).fit(skill.features(np.asarray(started["query_states"])), U).theta
        assert teaching_risk(learnt, skill.theta) < 1e-9


def test_the_tidy_csv_holds_the_third_component_and_the_target_group_shows_guidance_in_p3_only(study):
    folder, root = study
    _, demonstrations_csv = export_study(folder.folder, root / "tidy")
    with open(demonstrations_csv, encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 2 * PER_GROUP * (4 + 5 + 8 * 4 + 4 + 5)
    logged = [json.loads(line) for line in (folder.folder / "P01.jsonl").read_text().splitlines()]
    logged = [e for e in logged if e["type"] == "demonstration"]
    first = [row for row in rows if row["participant"] == "P01"]
    for row, event in zip(first, logged, strict=True):
        assert [float(row[f"action_{i}"]) for i in (1, 2, 3)] == event["action"]
        assert [float(row[f"optimal_{i}"]) for i in (1, 2, 3)] == event["optimal"]
    shown = {(row["group"], row["phase"]) for row in rows if row["guidance_shown"] == "1"}
    assert shown == {("target", "P3")}


def test_the_bids_export_keeps_the_3d_actions(study):
    folder, root = study
    out = export_bids(folder.folder, root / "bids")
    tables = sorted(out.glob("sub-*/beh/*_beh.tsv"))
    assert len(tables) == 2 * PER_GROUP
    with open(tables[0], encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle, delimiter="\t"))
    assert len(rows) == 4 + 5 + 8 * 4 + 4 + 5
    assert all(row["action_3"] not in ("", "n/a") and row["optimal_3"] not in ("", "n/a") for row in rows)


def test_the_papers_analysis_runs_and_finds_the_guided_groups_gain(study):
    folder, root = study
    analysis = analyse_study(folder.folder)
    changes = analysis.statistics.changes
    # The scripted target group learnt from the arrows shown in P3, the control group saw none:
    # the error fell from P1 to P4 in the target group only.
    mean = changes[changes["change"] == "P1_to_P4"].groupby("group")["delta"].mean()
    assert mean["target"] < 0 < mean["control"]
    between = analysis.statistics.between.set_index("change")
    assert list(between.index) == ["P1_to_P3E8", "P1_to_P4", "P2_to_P5"]
    assert between.loc["P1_to_P4", "student_p"] < 0.05 and between.loc["P1_to_P4", "n_target"] == PER_GROUP
    assert "trajectories" in analysis.figures   # what each participant's arm learnt, from the top
    saved = analysis.save(root / "analysis", formats=("png",))
    assert (root / "analysis" / "summary.txt") in saved
