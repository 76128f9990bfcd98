"""The ``mt-widgets`` command: every subcommand's help, wrong arguments, and the folder commands run
for real on a study folder made by the study tests' factories and on a class folder."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10: the same parser as the tomli package (the test extra has it there)
    import tomli as tomllib

import mt_widgets
from mt_widgets.classroom import ProgressRecorder
from mt_widgets.cli import main
from mt_widgets.cli.shipped import copy_notebooks, shipped_folder
from mt_widgets.study import BUILTIN_PROTOCOLS, Session, load_protocol
from mt_widgets.study.pseudonyms import code_of
from mt_widgets.study.study_folder import StudyFolder
from tests.study.scripted import STEPS, run_to_end, run_to_end_one, steps_protocol

REPO = Path(__file__).resolve().parents[2]
SUBCOMMANDS = [[], ["lab"], ["demo"], ["study"], ["study", "serve"], ["study", "status"], ["study", "export"],
               ["study", "withdraw"], ["study", "erase"], ["study", "protocols"], ["study", "copy-protocol"],
               ["course"], ["course", "check"], ["hub"], ["hub", "check"]]


@pytest.mark.parametrize("words", SUBCOMMANDS, ids=lambda words: " ".join(words) or "mt-widgets")
def test_every_subcommand_has_help(words, capsys):
    with pytest.raises(SystemExit) as exit_:
        main([*words, "--help"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith(f"usage: mt-widgets {' '.join(words)}".rstrip())
    assert "options:" in out


def test_version(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.strip() == f"mt-widgets {mt_widgets.__version__}"


@pytest.mark.parametrize("argv, said", [
    ([], "required: COMMAND"),
    (["bogus"], "invalid choice: 'bogus'"),
    (["study"], "required: ACTION"),
    (["study", "status"], "required: folder"),
    (["study", "withdraw", "somewhere"], "required: participant"),
    (["study", "erase", "somewhere"], "required: participant"),
    (["study", "erase", "f", "P01", "P02"], "unrecognized arguments: P02"),
    (["demo", "--port", "eighty"], "expected a port number, got 'eighty'"),
    (["demo", "--port", "70000"], "expected a port from 1 to 65535, got 70000"),
    (["lab", "a", "b"], "unrecognized arguments: b"),
    (["hub", "check"], "required: roster"),
    (["study", "status", "f", "--", "--port=1"], "options after -- go to a server; study starts none"),
])
def test_a_wrong_argument_is_named_and_exits_2(argv, said, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert said in capsys.readouterr().err


def test_the_console_script_is_declared_and_runs():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    assert project["scripts"] == {"mt-widgets": "mt_widgets.cli:main"}
    done = subprocess.run([sys.executable, "-m", "mt_widgets.cli", "study", "status", str(REPO / "no-such-study")],
                          capture_output=True, text=True, cwd=REPO, env={"PYTHONPATH": str(REPO), "PATH": ""})
    assert done.returncode == 1 and "no-such-study holds no study.json" in done.stderr


@pytest.fixture
def study(tmp_path):
    study = StudyFolder.create(tmp_path / "study", steps_protocol())
    run_to_end(Session.start(study, "P01", group="target"))
    quitter = Session.start(study, "P02", group="control")
    run_to_end_one(quitter)
    quitter.close()
    run_to_end(Session.start(study, "P03", group="control"))
    return study


def test_study_status_shows_groups_and_states(study, capsys):
    assert main(["study", "status", str(study.folder)]) == 0
    out = capsys.readouterr().out
    rows = {line.split()[0]: line.split()[1:3] for line in out.splitlines() if line.startswith("P0")}
    assert rows == {"P01": ["target", "completed"], "P02": ["control", "in"], "P03": ["control", "completed"]}
    assert "3 enrolled" in out and "in progress" in out


def test_study_withdraw_then_export_leaves_the_participant_out(study, tmp_path, capsys):
    assert main(["study", "withdraw", str(study.folder), "P02", "--reason", "asked by e-mail"]) == 0
    assert "P02: withdrawn (data: exclude)" in capsys.readouterr().out
    outcome = study.outcomes()["P02"]
    assert outcome["outcome"] == "withdrawn" and outcome["reason"] == "asked by e-mail" and outcome["data"] == "exclude"
    assert study.log_path("P02").exists()  # "exclude" keeps the log
    assert main(["study", "withdraw", str(study.folder), "P02"]) == 1  # already left
    assert "already left the study" in capsys.readouterr().err
    assert main(["study", "withdraw", str(study.folder), "P09"]) == 1
    capsys.readouterr()
    out = tmp_path / "dataset"
    assert main(["study", "export", str(study.folder), str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    subjects = sorted(p.name for p in out.glob("sub-*"))
    # The export labels participants by random codes (their key stays in the study folder): P02 has none.
    assert subjects == sorted(f"sub-{code_of(study.folder, pid)}" for pid in ("P01", "P03"))
    assert code_of(study.folder, "P02") is None
    assert json.loads((out / "dataset_description.json").read_text())["Name"]


def test_study_withdraw_deletes_the_log_when_the_protocol_says_so(tmp_path, capsys):
    study = StudyFolder.create(tmp_path / "study", steps_protocol(STEPS.replace('"exclude"', '"delete"')))
    assert study.protocol.withdrawal == "delete"
    Session.start(study, "P01", group="target").close()
    assert study.log_path("P01").exists()
    assert main(["study", "withdraw", str(study.folder), "P01"]) == 0
    assert not study.log_path("P01").exists() and study.outcomes()["P01"]["data"] == "delete"


def test_study_erase_answers_the_request_and_refuses_an_unknown_id(study, capsys):
    assert main(["study", "erase", str(study.folder), "p02"]) == 1  # IDs match exactly: nothing changed
    err = capsys.readouterr().err
    assert err.startswith("mt-widgets: participant_id: 'p02' is not enrolled") and "did you mean 'P02'?" in err
    assert study.log_path("P02").exists()
    assert main(["study", "erase", str(study.folder), "P02"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("Erased participant 'P02'.") and "Kept:" in out
    assert not study.log_path("P02").exists()
    assert "P02" not in {row["participant"] for row in study.status()}
    assert "P02" not in (study.folder / "_enrolment.jsonl").read_text()
    assert main(["study", "erase", str(study.folder), "P02"]) == 1  # once only
    assert "was erased from study" in capsys.readouterr().err
    assert main(["study", "erase", str(study.folder.parent / "elsewhere"), "P01"]) == 1
    assert "holds no study.json" in capsys.readouterr().err


@pytest.fixture
def a_class(tmp_path):
    folder = tmp_path / "class"
    for login in ("ann", "bo"):
        ProgressRecorder(folder, login).record("episode", lesson="a5", skill="sim-point", error=1.0)
    roster = tmp_path / "roster.csv"
    roster.write_text("login,name,email,role\nann,Ann Lee,ann@example.edu,\nbo,,,student\ncy,,,student\n"
                      "dana,Dana Scully,,instructor\n")
    return folder, roster


def test_hub_check_counts_the_roster_and_names_a_wrong_entry(a_class, tmp_path, capsys):
    _, roster = a_class
    assert main(["hub", "check", str(roster)]) == 0
    assert capsys.readouterr().out.strip() == f"{roster}: 3 students, 1 instructors/TAs (dana)"
    wrong = tmp_path / "wrong.csv"
    wrong.write_text("login,name,email,role\nAnn Lee,,,student\n")
    assert main(["hub", "check", str(wrong)]) == 1
    assert "Ann Lee" in capsys.readouterr().err


def test_course_check_names_students_without_progress_and_damaged_files(a_class, capsys):
    folder, roster = a_class
    assert main(["course", "check", str(folder), "--roster", str(roster)]) == 0
    out = capsys.readouterr().out
    assert "2 students with a progress file" in out and "no progress file yet: cy" in out
    assert "3 students, 2 with a progress file" in out
    damaged = sorted(folder.glob("s-*.jsonl"))[0]
    damaged.write_bytes(damaged.read_bytes() + b"{not json\n")
    assert main(["course", "check", str(folder)]) == 1
    assert "problem:" in capsys.readouterr().out
    assert main(["course", "check", str(folder.parent / "nowhere")]) == 1


def test_lab_copies_the_tutorials_into_an_empty_folder_and_keeps_the_users_files(tmp_path, capsys):
    folder = tmp_path / "mine"
    assert main(["lab", str(folder), "--copy-only"]) == 0
    shipped = len(list((folder / "tutorials").iterdir())) + len(list((folder / "notebooks").iterdir()))
    assert capsys.readouterr().out.strip() == f"{folder}: {shipped} files copied, 0 already there (kept as they are)"
    (folder / "notebooks" / "demo.ipynb").unlink()
    assert main(["lab", str(folder), "--copy-only"]) == 0
    assert capsys.readouterr().out.strip() == f"{folder}: 1 file copied, {shipped - 1} already there (kept as they are)"
    tutorials = sorted(p.name for p in shipped_folder("tutorials").glob("*.ipynb"))
    assert sorted(p.name for p in (folder / "tutorials").glob("*.ipynb")) == tutorials
    assert (folder / "notebooks" / "demo.ipynb").read_bytes() == (REPO / "notebooks" / "demo.ipynb").read_bytes()
    assert (folder / "tutorials" / "capstone.toml").exists()
    start = folder / "tutorials" / "00_start_here.ipynb"
    start.write_text("my work")
    copied, kept = copy_notebooks(folder)
    assert copied == [] and start in kept and start.read_text() == "my work"
    (tmp_path / "a-file").write_text("")
    assert main(["lab", str(tmp_path / "a-file"), "--copy-only"]) == 1
    assert "expected a folder for the tutorials" in capsys.readouterr().err


def test_the_clone_reads_its_own_notebooks():
    # An editable install or a clone has no mt_widgets/_data: the repository's folders, one copy each.
    assert shipped_folder("tutorials") == REPO / "tutorials"
    assert shipped_folder("deploy/voila") == REPO / "deploy" / "voila"
    with pytest.raises(ValueError, match="name: expected one of"):
        shipped_folder("tests")


def test_study_protocols_lists_every_shipped_protocol_with_its_file(capsys):
    assert main(["study", "protocols"]) == 0
    out = capsys.readouterr().out
    for name in [*BUILTIN_PROTOCOLS, "online-pilot"]:
        [line] = [line for line in out.splitlines() if line.startswith(f"{name}: ")]
        path = Path(out.splitlines()[out.splitlines().index(line) + 2].strip())
        assert path.is_file() and load_protocol(path).name == name
    assert "online-pilot: Machine-teaching study, online pilot" in out and "P1 (1), P3 (2), P4 (1)" in out


def test_study_copy_protocol_copies_a_shipped_protocol_to_edit_and_never_overwrites(tmp_path, capsys):
    assert main(["study", "copy-protocol", "online-pilot", str(tmp_path / "mine")]) == 0
    copy = tmp_path / "mine" / "study_online_pilot.toml"
    assert capsys.readouterr().out.strip() == f"wrote {copy}"
    assert copy.read_text() == (REPO / "notebooks" / "study_online_pilot.toml").read_text()
    assert main(["study", "copy-protocol", "paper-sim", str(tmp_path / "mine")]) == 0
    assert load_protocol(tmp_path / "mine" / "paper_sim.toml").hash == load_protocol("paper-sim").hash
    copy.write_text(copy.read_text() + "# my edit\n")
    assert main(["study", "copy-protocol", "online-pilot", str(tmp_path / "mine")]) == 1
    assert "exists already" in capsys.readouterr().err and copy.read_text().endswith("# my edit\n")
    assert main(["study", "copy-protocol", "paper_sim", str(tmp_path)]) == 1
    assert "expected a shipped protocol" in capsys.readouterr().err
