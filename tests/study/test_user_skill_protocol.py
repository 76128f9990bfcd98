"""A protocol can name a user's own skill: from a file it points to, or as "module:name".

The skill here is tutorial 09's point mass (``tests/user_plant.py``): a plant the package has
never seen, with no drawing of its own. A lesson (the episode widget) and a logged study (a
session in a study folder, reopened from its ``study.json``) of such a protocol run end to end.
"""

import shutil
from pathlib import Path

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.study import ProtocolError, Session, StudyFolder, export_study, load_protocol, parse_protocol
from mt_widgets.widgets import EpisodeWidget
from protocols import phase, protocol_toml

# Each test loads a user's skill module and runs a session with it: seconds each.
pytestmark = pytest.mark.slow

USER_PLANT = Path(__file__).resolve().parents[1] / "user_plant.py"

PROTOCOL = protocol_toml("puck-lab", [phase("A", "puck-park", 2, "Park the puck.", guidance=["target"]),
                                     phase("B", "sim-point", instructions="Now the arm.")],
                         skills_module="skills/puck.py")


@pytest.fixture
def protocol_file(tmp_path):
    """The protocol in lab/, its skills in lab/skills/puck.py (a path relative to the protocol)."""
    (tmp_path / "lab" / "skills").mkdir(parents=True)
    shutil.copy(USER_PLANT, tmp_path / "lab" / "skills" / "puck.py")
    path = tmp_path / "lab" / "puck.toml"
    path.write_text(PROTOCOL, encoding="utf-8")
    return path


def test_a_protocol_names_skills_from_the_file_it_points_to_and_the_papers(protocol_file):
    protocol = load_protocol(protocol_file)
    park = protocol.skills["puck-park"]
    assert type(park.plant).__name__ == "PointMass" and park.n_features == 5
    assert protocol.skills["sim-point"] is SKILLS["sim-point"]
    # Every skill of the file is known by its key, including one only in its own registry.
    assert {"puck-park", "puck-drift"} <= set(protocol.skills)
    assert [p.demonstrations for p in protocol.phases] == [5, 5]
    # The stored form keeps the file's absolute path, so the study reopens from anywhere.
    assert protocol.data["skills"]["module"] == str((protocol_file.parent / "skills" / "puck.py").resolve())
    # Loading twice gives the same skill objects (the file runs once per process).
    assert load_protocol(protocol_file).skills["puck-park"] is park


def test_a_lesson_of_a_user_skill_runs_in_the_episode_widget(protocol_file):
    protocol = load_protocol(protocol_file)
    session = Session.lesson(protocol, group="target")
    widget = None
    errors = []
    while not session.finished:
        step = session.current_step()
        if step.kind == "demonstration":
            if step.index == 0:
                widget = EpisodeWidget(protocol.skills[step.skill], query_states=step.query_states,
                                       guidance=step.guidance, lam=protocol.lam)
            # The teacher demonstrates the target skill's own action, drawn in the widget.
            action = protocol.skills[step.skill].target_actions(step.state[None])[0]
            record = widget.demonstrate(action)
            feedback = session.submit_demonstration(record.action, index=step.index)
            if step.guidance:
                np.testing.assert_allclose(feedback.optimal, record.optimal_action, atol=1e-12)
                widget.next()
        elif step.kind == "episode_end":
            result = session.finish_episode()
            if widget.phase != "finished":
                widget.finish()
            assert widget.result.theta_error == pytest.approx(result.theta_error, abs=1e-12)
            errors.append((step.skill, result.theta_error))
        else:
            session.advance()
    assert [skill for skill, _ in errors] == ["puck-park", "puck-park", "sim-point"]
    # The target's own actions, shrunk by the ridge, teach the skill nearly but not exactly
    # (the optimal ones undo the shrinkage: see the logged study below).
    assert all(0 < error < 0.5 for _, error in errors)


def test_a_logged_study_of_a_user_skill_runs_and_reopens(protocol_file, tmp_path, monkeypatch):
    protocol = load_protocol(protocol_file)
    study = StudyFolder.create(tmp_path / "logs", protocol)
    session = Session.start(study, "P01", group="control")
    while not session.finished:
        step = session.current_step()
        if step.kind == "demonstration":
            skill = protocol.skills[step.skill]
            optimal = np.asarray(session._episodes[(step.phase_index, step.episode)]["optimal"])[step.index]
            session.submit_demonstration(optimal, {"time_to_first_input_s": 0.4, "drawing_duration_s": 0.3})
            assert skill.plant.action_dim == 2
        elif step.kind == "episode_end":
            result = session.finish_episode()
            assert result.theta_error < 1e-9, "the optimal demonstration teaches the user's skill exactly"
        else:
            session.advance()
    session.close()
    finished = [e for e in session.events if e["type"] == "episode_finished"]
    assert [e["skill"] for e in finished] == ["puck-park", "puck-park", "sim-point"]
    # Reopened from its study.json, from another working directory, the study still knows the skill.
    monkeypatch.chdir(tmp_path)
    reopened = StudyFolder(tmp_path / "logs")
    assert reopened.protocol.hash == protocol.hash
    assert reopened.protocol.skills["puck-park"].n_features == 5
    resumed = Session.resume(reopened, "P01")
    assert resumed.finished
    assert resumed.current_step().kind == "thank_you"
    resumed.close()
    demonstrations_csv, episodes_csv = export_study(tmp_path / "logs")
    assert "puck-park" in Path(episodes_csv).read_text(encoding="utf-8")


def test_a_protocol_names_an_importable_skill_as_module_and_name(tmp_path, monkeypatch):
    shutil.copy(USER_PLANT, tmp_path / "my_lab_skills.py")
    monkeypatch.syspath_prepend(str(tmp_path))
    text = (PROTOCOL.replace('[skills]\nmodule = "skills/puck.py"\n', "")
            .replace('skill = "puck-park"', 'skill = "my_lab_skills:park"'))
    protocol = parse_protocol(text, "lab.toml")
    assert protocol.phases[0].skill == "my_lab_skills:park"
    import my_lab_skills

    assert protocol.skills["my_lab_skills:park"] is my_lab_skills.park
    session = Session.lesson(protocol)
    while session.current_step().kind != "demonstration":
        session.advance()
    assert session.current_step().query_states.shape == (5, 4)


@pytest.mark.parametrize("edit, field, message", [
    (('module = "skills/puck.py"', 'module = "skills/nowhere.py"'), "skills.module", "no file at"),
    (('skill = "sim-point"', 'skill = "my_missing_module:park"'), "phases[1].skill", "ModuleNotFoundError"),
    (('skill = "sim-point"', 'skill = "puck-parc"'), "phases[1].skill", "puck-park"),
    (('[skills]\n', '[skills]\ncolour = "red"\n'), "skills.colour", "unknown field"),
])
def test_a_bad_user_skill_reference_is_refused_with_its_line_and_field(protocol_file, edit, field, message):
    text = protocol_file.read_text(encoding="utf-8").replace(*edit)
    protocol_file.write_text(text, encoding="utf-8")
    with pytest.raises(ProtocolError) as error:
        load_protocol(protocol_file)
    assert error.value.field == field and message in str(error.value)
    needle = [line for line in edit[1].splitlines() if line][-1]
    assert error.value.line == next(i for i, line in enumerate(text.splitlines(), 1) if line == needle)
