"""The BIDS-style export: names the BIDS validator accepts, every column described, the left-out left out."""

import csv
import json

import pytest
from bids_validator import BIDSValidator

from mt_widgets.study import Session, StudyFolder, export_bids, load_protocol

from .scripted import run_to_end, run_to_end_one, steps_protocol


def _rows(path):
    with open(path, encoding="utf-8") as handle:
        return list(csv.DictReader(handle, delimiter="\t"))


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    root = tmp_path_factory.mktemp("bids")
    study = StudyFolder.create(root / "study", steps_protocol())
    run_to_end(Session.start(study, "P-01", group="target"))
    run_to_end(Session.start(study, "P02", group="control"))
    quitter = Session.start(study, "P03", group="target")
    for _ in range(12):
        run_to_end_one(quitter)
    quitter.withdraw()
    quitter.close()
    decliner = Session.start(study, "P04", group="control")
    decliner.advance()
    decliner.finish_video(True, 1)
    decliner.advance()
    decliner.decline_consent()
    decliner.close()
    return study, export_bids(study.folder, root / "dataset")


def test_every_file_name_passes_the_bids_validator(dataset):
    _, out = dataset
    validator = BIDSValidator()
    files = sorted("/" + str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert "/dataset_description.json" in files and "/participants.tsv" in files
    assert "/sub-P01/beh/sub-P01_task-short_beh.tsv" in files
    rejected = [f for f in files if not validator.is_bids(f)]
    assert rejected == []
    # The validator does reject what is not BIDS, so passing means something.
    assert not validator.is_bids("/sub-P01/beh/P01_short.tsv")


def test_participants_are_the_ones_kept_with_their_demographics(dataset):
    _, out = dataset
    rows = _rows(out / "participants.tsv")
    assert [r["participant_id"] for r in rows] == ["sub-P01", "sub-P02"]   # P03 withdrew, P04 declined
    assert rows[0]["age"] == "30" and rows[0]["sex"] == "female" and rows[0]["group"] == "target"
    sidecar = json.loads((out / "participants.json").read_text())
    assert set(rows[0]) <= set(sidecar) and sidecar["age"]["Units"] == "years"
    assert not (out / "sub-P03").exists() and not (out / "sub-P04").exists()
    readme = (out / "README.md").read_text()
    assert "1 withdrawn, 1 declined consent" in readme


def test_every_behavioural_column_is_described_with_its_units(dataset):
    study, out = dataset
    protocol = study.protocol
    tsv = out / "sub-P01" / "beh" / "sub-P01_task-short_beh.tsv"
    rows = _rows(tsv)
    assert len(rows) == sum(p.episodes * p.demonstrations for p in protocol.phases)
    sidecar = json.loads(tsv.with_suffix(".json").read_text())
    assert set(rows[0]) <= set(sidecar)
    assert sidecar["action_1"]["Units"] == "cm" and sidecar["drawing_duration"]["Units"] == "s"
    assert sidecar["Learner"] == protocol.learner == "ridge" and sidecar["LearnerRidgeLambda"] == protocol.lam
    assert {r["guidance_modality"] for r in rows} == {"arrows"}
    assert {r["guidance_shown"] for r in rows if r["phase"] == "B"} == {"1"}
    assert all(r["teaching_error"] != "n/a" for r in rows)
    phenotype = _rows(out / "phenotype" / "tlx.tsv")
    assert [r["participant_id"] for r in phenotype] == ["sub-P01", "sub-P02"] and phenotype[0]["effort"] == "5"
    assert phenotype[0]["notes"] == "n/a"
    description = json.loads((out / "dataset_description.json").read_text())
    assert description["BIDSVersion"] and protocol.hash in description["GeneratedBy"][0]["Description"]


def test_the_export_refuses_a_folder_with_files_and_clashing_labels(dataset, tmp_path):
    study, out = dataset
    with pytest.raises(ValueError, match="out_folder"):
        export_bids(study.folder, out)
    clash = StudyFolder.create(tmp_path / "s", load_protocol("paper-sim"))
    clash.enrol("P-1")
    clash.enrol("P1")
    for pid in ("P-1", "P1"):
        Session.resume(clash, pid).close()
    with pytest.raises(ValueError, match="same BIDS label"):
        export_bids(clash.folder, tmp_path / "out")
