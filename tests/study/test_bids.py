"""The BIDS-style export: names the BIDS validator accepts, every column described, the left-out left out."""

import csv
import json

import pytest
from bids_validator import BIDSValidator

from mt_widgets.study import Session, StudyFolder, export_bids, load_protocol
from mt_widgets.study.pseudonyms import code_of

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
    study, out = dataset
    validator = BIDSValidator()
    files = sorted("/" + str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert "/dataset_description.json" in files and "/participants.tsv" in files
    code = code_of(study.folder, "P-01")
    assert f"/sub-{code}/beh/sub-{code}_task-short_beh.tsv" in files
    rejected = [f for f in files if not validator.is_bids(f)]
    assert rejected == []
    # The validator does reject what is not BIDS, so passing means something.
    assert not validator.is_bids(f"/sub-{code}/beh/{code}_short.tsv")


def test_participants_are_the_ones_kept_with_their_demographics(dataset):
    study, out = dataset
    rows = {r["participant_id"]: r for r in _rows(out / "participants.tsv")}
    first, second = (f"sub-{code_of(study.folder, pid)}" for pid in ("P-01", "P02"))
    assert sorted(rows) == sorted([first, second])   # P03 withdrew, P04 declined: no code drawn for them
    assert code_of(study.folder, "P03") is None and code_of(study.folder, "P04") is None
    assert rows[first]["age"] == "30" and rows[first]["sex"] == "female" and rows[first]["group"] == "target"
    sidecar = json.loads((out / "participants.json").read_text())
    assert set(rows[first]) <= set(sidecar) and sidecar["age"]["Units"] == "years"
    assert sorted(p.name for p in out.glob("sub-*")) == sorted([first, second])
    readme = (out / "README.md").read_text()
    assert "1 withdrawn, 1 declined consent" in readme


def test_every_behavioural_column_is_described_with_its_units(dataset):
    study, out = dataset
    protocol = study.protocol
    code = code_of(study.folder, "P-01")
    tsv = out / f"sub-{code}" / "beh" / f"sub-{code}_task-short_beh.tsv"
    rows = _rows(tsv)
    assert len(rows) == sum(p.episodes * p.demonstrations for p in protocol.phases)
    sidecar = json.loads(tsv.with_suffix(".json").read_text())
    assert set(rows[0]) <= set(sidecar)
    onsets = [float(r["onset"]) for r in rows]   # seconds from the session's start, in order
    assert 0 < onsets[0] and onsets == sorted(onsets) and sidecar["onset"]["Units"] == "s"
    assert sidecar["action_1"]["Units"] == "cm" and sidecar["drawing_duration"]["Units"] == "s"
    assert sidecar["Learner"] == protocol.learner == "ridge" and sidecar["LearnerRidgeLambda"] == protocol.lam
    assert {r["guidance_modality"] for r in rows} == {"arrows"}
    assert {r["guidance_shown"] for r in rows if r["phase"] == "B"} == {"1"}
    assert all(r["theta_error"] != "n/a" for r in rows)
    phenotype = _rows(out / "phenotype" / "tlx.tsv")
    by_code = {r["participant_id"]: r for r in phenotype}
    assert sorted(by_code) == sorted(f"sub-{code_of(study.folder, p)}" for p in ("P-01", "P02"))
    assert by_code[f"sub-{code}"]["effort"] == "5" and by_code[f"sub-{code}"]["notes"] == "n/a"
    description = json.loads((out / "dataset_description.json").read_text())
    assert description["BIDSVersion"] and protocol.hash in description["GeneratedBy"][0]["Description"]


def test_the_export_refuses_a_folder_with_files_and_ids_that_differ_by_punctuation_get_their_own_codes(
        dataset, tmp_path):
    study, out = dataset
    with pytest.raises(ValueError, match="out_folder"):
        export_bids(study.folder, out)
    # "P-1" and "P1" made the same label while labels came from IDs; random codes never clash.
    clash = StudyFolder.create(tmp_path / "s", load_protocol("paper-sim"))
    clash.enrol("P-1")
    clash.enrol("P1")
    for pid in ("P-1", "P1"):
        Session.resume(clash, pid).close()
    export_bids(clash.folder, tmp_path / "out")
    codes = {code_of(clash.folder, "P-1"), code_of(clash.folder, "P1")}
    assert len(codes) == 2 and {p.name for p in (tmp_path / "out").glob("sub-*")} == {f"sub-{c}" for c in codes}
