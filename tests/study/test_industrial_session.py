"""The study engine runs a protocol on the UR5's skills end to end, and the BIDS export keeps 3-D actions."""

import csv
import json

import numpy as np
import pytest
from bids_validator import BIDSValidator

from mt_widgets import SKILLS, RidgeLearner, teaching_risk
from mt_widgets.study import Session, StudyFolder, export_bids, parse_protocol
from mt_widgets.study.pseudonyms import code_of
from protocols import phase, protocol_toml

from .scripted import run


@pytest.fixture(scope="module")
def industrial(tmp_path_factory):
    root = tmp_path_factory.mktemp("industrial")
    text = protocol_toml("industrial", [phase("P1", "ur5-reach"), phase("P2", "ur5-conveyor", episodes=2,
                                                                          guidance=["target"])])
    study = StudyFolder.create(root / "study", parse_protocol(text, "industrial.toml"))
    for participant, group in (("P01", "target"), ("P02", "control")):
        session = Session.start(study, participant, group=group)
        run(session)
        assert session.finished
        session.close()
    return study, export_bids(study.folder, root / "dataset")


def _rows(path):
    with open(path, encoding="utf-8") as handle:
        return list(csv.DictReader(handle, delimiter="\t"))


def test_the_export_holds_every_component_of_the_3d_actions_as_logged(industrial):
    study, out = industrial
    label = f"sub-{code_of(study.folder, 'P01')}"   # the export's random code for P01 (its key stays in the study)
    rows = _rows(out / label / "beh" / f"{label}_task-industrial_beh.tsv")
    assert len(rows) == 4 + 2 * 5   # S = 4 for reach, 5 for the conveyor (two episodes)
    logged = [json.loads(line) for line in (study.folder / "P01.jsonl").read_text().splitlines()]
    demonstrations = [e for e in logged if e["type"] == "demonstration"]
    for row, event in zip(rows, demonstrations):
        actions = [float(row[f"action_{i}"]) for i in (1, 2, 3)]
        optimal = [float(row[f"optimal_{i}"]) for i in (1, 2, 3)]
        assert actions == pytest.approx(event["action"], abs=0) and optimal == pytest.approx(event["optimal"], abs=0)
        if row["skill"] == "ur5-reach":   # 12 state components; the conveyor's 13th is its phase
            assert row["state_13"] == "n/a"
    # the optimal actions in the export teach the skill exactly, as they did in the session
    conveyor = [row for row in rows if row["skill"] == "ur5-conveyor"][:5]
    states = np.array([[float(row[f"state_{i}"]) for i in range(1, 14)] for row in conveyor])
    skill = SKILLS["ur5-conveyor"]
    U = np.array([[float(row[f"optimal_{i}"]) for i in (1, 2, 3)] for row in conveyor])
    assert teaching_risk(RidgeLearner(lam=0.01).fit(skill.features(states), U).theta, skill.theta) < 1e-9


def test_the_3d_columns_are_described_and_the_names_pass_the_bids_validator(industrial):
    _, out = industrial
    sidecar = json.loads((out / "task-industrial_beh.json").read_text())
    assert sidecar["action_3"]["Units"] == "m/s" and "optimal_3" in sidecar
    validator = BIDSValidator()
    files = sorted("/" + str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert [f for f in files if not validator.is_bids(f)] == []
