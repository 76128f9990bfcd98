"""The shipped ``paper-so101`` protocol (the paper's P1-P5 on the SO-101, taught by hand) runs end to
end headless: scripted participants of both groups, the BIDS export and the analysis of the paper's
protocols."""

import csv

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.analysis.study_analysis import analyse_study
from mt_widgets.study import export_bids, load_protocol
from mt_widgets.study.practice import PRACTICE_SKILLS

from .scripted import scripted_study

#: Participants per group: the fewest for the paper's tests to have a spread.
PER_GROUP = 2
#: Demonstrations per participant: S = 4 per episode (the tool's position and 1), 12 episodes.
DEMONSTRATIONS = 4 * 12


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    root = tmp_path_factory.mktemp("paper-so101")
    folder = scripted_study(root, "paper-so101", 2 * PER_GROUP, learning=0.8)
    return folder, root


def test_the_protocol_is_the_papers_five_phases_on_the_so101_taught_by_hand():
    protocol = load_protocol("paper-so101")
    assert [(p.id, p.skill, p.episodes, tuple(p.guidance)) for p in protocol.phases] == [
        ("P1", "so101-reach", 1, ()), ("P2", "so101-place", 1, ()), ("P3", "so101-reach", 8, ("target",)),
        ("P4", "so101-reach", 1, ()), ("P5", "so101-place", 1, ())]
    assert protocol.demonstration_modality == "hand" and protocol.guidance_modality == "arrows"
    practice = PRACTICE_SKILLS[protocol.practice.skill]
    assert practice.plant is not SKILLS["so101-reach"].plant or practice.key == "so101-practice"
    goals = [np.asarray(SKILLS[p.skill].target.shape().points) for p in protocol.phases]
    ours = np.asarray(practice.target.shape().points)[0]
    assert min(np.min(np.linalg.norm(g - ours, axis=-1)) for g in goals) > 0.05   # no phase's goal


@pytest.mark.slow
def test_the_bids_export_and_the_papers_analysis_run_on_its_logs(study):
    folder, root = study
    out = export_bids(folder.folder, root / "bids")
    tables = sorted(out.glob("sub-*/beh/*_beh.tsv"))
    assert len(tables) == 2 * PER_GROUP
    with open(tables[0], encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle, delimiter="\t"))
    assert len(rows) == DEMONSTRATIONS
    assert all(row["action_3"] not in ("", "n/a") for row in rows)
    analysis = analyse_study(folder.folder, trajectory_duration=2.0)
    between = analysis.statistics.between.set_index("change")
    assert list(between.index) == ["P1_to_P3E8", "P1_to_P4", "P2_to_P5"]
    assert between.loc["P1_to_P4", "n_target"] == PER_GROUP
    changes = analysis.statistics.changes
    mean = changes[changes["change"] == "P1_to_P4"].groupby("group")["delta"].mean()
    assert mean["target"] < mean["control"]   # the guided scripted teachers improved more
