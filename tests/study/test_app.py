"""The participant app: the experimenter panel stays apart, blinding holds, bad input is refused
before the participant starts, and a new kernel resumes where the last one stopped."""

import re

import numpy as np
import pytest
from ipywidgets import Button

from mt_widgets import SKILLS
from mt_widgets.apps import StudyApp, participant_texts
from mt_widgets.study import LogError, SessionStateError, read_events

from .scripted import SHORT_PROTOCOL, act


@pytest.fixture
def protocol_file(tmp_path):
    path = tmp_path / "short.toml"
    path.write_text(SHORT_PROTOCOL)
    return str(path)


WORDS = re.compile(r"\b(target|control|group|groups|condition)\b", re.IGNORECASE)
GUIDANCE_WORDS = re.compile(r"\b(optimal|guidance|guided|correct action)\b", re.IGNORECASE)


@pytest.mark.parametrize("group", ["target", "control"])
def test_nothing_the_participant_view_holds_names_a_group(tmp_path, protocol_file, group):
    app = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    app.start_participant("P01", group=group)
    assert app.children == (app.participant_view,)  # the experimenter panel has left the page
    guidance_seen = False
    while not app.session.finished:
        texts = " ".join(participant_texts(app))
        assert not WORDS.search(texts), WORDS.search(texts).group(0)
        step = app.session.current_step()
        if GUIDANCE_WORDS.search(texts):
            # Only the protocol's guidance, only for the group the protocol gives it to.
            assert group == "target" and step.phase == "B", (step, GUIDANCE_WORDS.search(texts).group(0))
            guidance_seen = True
        act(app)
    assert guidance_seen == (group == "target")
    assert not WORDS.search(" ".join(participant_texts(app)))
    events, _ = read_events(tmp_path / "logs" / "P01.jsonl")
    assert events[-1]["type"] == "session_finished"


def test_a_bad_participant_id_is_refused_in_the_panel_and_nobody_starts(tmp_path, protocol_file):
    app = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    for bad in ("", "../P01", "P 01"):
        app.experimenter.participant.value = bad
        app.experimenter.start_button.click()
        assert "participant_id" in app.experimenter.message.value
        assert app.children == (app.experimenter,) and app.session is None
    assert not list((tmp_path / "logs").glob("*.jsonl"))


def test_an_unwritable_log_folder_is_refused_before_the_participant_starts(tmp_path, protocol_file):
    (tmp_path / "a-file").write_text("")
    app = StudyApp(protocol=protocol_file, log_folder=tmp_path / "a-file" / "logs")
    app.experimenter.participant.value = "P01"
    app.experimenter.start_button.click()
    assert "log folder" in app.experimenter.message.value and app.session is None
    assert app.children == (app.experimenter,)


def test_a_bad_protocol_file_is_named_in_the_panel(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(SHORT_PROTOCOL.replace('skill = "uarm-line"', 'skill = "uarm-circle"'))
    app = StudyApp(protocol=str(path), log_folder=tmp_path / "logs")
    assert "line" in app.experimenter.message.value and "uarm-circle" in app.experimenter.message.value


def test_a_new_kernel_resumes_mid_episode_with_the_given_demonstrations_restored(tmp_path, protocol_file):
    first = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    first.start_participant("P01", group="control")
    while not (app_step := first.session.current_step()).kind == "demonstration" or app_step.index < 2:
        act(first)
    given = [e["action"] for e in first.session.events if e["type"] == "demonstration"]
    first.session.close()  # the old kernel ends (a reload)
    second = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    second.experimenter.participant.value = "P01"
    second.experimenter.resume_button.click()
    assert second.session is not None, second.experimenter.message.value
    step = second.session.current_step()
    assert (step.kind, step.phase, step.index) == ("demonstration", "A", 2)
    np.testing.assert_allclose(second.episode.demonstrations, given)
    assert second.episode.state_index == 2
    while not second.session.finished:
        act(second)
    demos = [e for e in read_events(tmp_path / "logs" / "P01.jsonl")[0] if e["type"] == "demonstration"]
    assert [(d["phase"], d["episode"], d["index"]) for d in demos] == sorted(
        {(d["phase"], d["episode"], d["index"]) for d in demos}, key=lambda k: ("ABC".index(k[0]), k[1], k[2]))
    assert len(demos) == 15


def test_a_lesson_in_the_app_writes_no_log(tmp_path, protocol_file):
    app = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    app.experimenter.group.value = "target"
    app.experimenter.lesson_button.click()
    while not app.session.finished:
        act(app)
    assert not (tmp_path / "logs").exists()


@pytest.mark.parametrize("error", [SessionStateError("submit_demonstration: expected ..."), ValueError("timings"),
                                   TypeError("unhashable"), LogError("continued by another session")])
def test_a_demonstration_the_session_refuses_stops_the_page_with_a_call_for_the_experimenter(
        tmp_path, protocol_file, monkeypatch, error):
    app = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    app.start_participant("P01", group="target")
    while not ((step := app.session.current_step()).kind == "demonstration" and step.index == 1):
        act(app)
    episode = app.episode

    def refuse(*args, **kwargs):
        raise error
    monkeypatch.setattr(app.session, "submit_demonstration", refuse)
    episode.teaching.set_action(SKILLS[step.skill].target_actions(step.state[None])[0])
    episode.teaching.confirm_button.click()  # as the participant does; ipywidgets prints the error
    text = " ".join(participant_texts(app))
    assert "Please call the experimenter" in text and str(error) in text
    assert episode not in app.body.children and not any(isinstance(w, Button) for w in app.body.children)
    # The widget did not move on: no guidance, the demonstration not counted.
    assert episode.phase == "teaching" and episode.state_index == 1 and len(episode.demonstrations) == 1
    # What was logged stays, and the participant can be resumed at the same demonstration.
    demos = [e for e in read_events(tmp_path / "logs" / "P01.jsonl")[0] if e["type"] == "demonstration"]
    assert len(demos) == 1
    monkeypatch.undo()
    app.session.close()
    resumed = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    resumed.resume_participant("P01")
    step = resumed.session.current_step()
    assert (step.kind, step.index) == ("demonstration", 1) and resumed.episode.state_index == 1


def test_the_group_dropdown_shows_randomised_and_the_panel_says_what_the_start_did(tmp_path, protocol_file):
    # Issue 10 bug 3: a Dropdown whose value is None shows a blank box.
    app = StudyApp(str(protocol_file), log_folder=tmp_path / "logs")
    panel = app.experimenter
    assert panel.group.label == "randomised (block randomisation)" and panel.group.index == 0
    panel.participant.value = "P01"
    panel.start_button.click()
    group = app.session.group
    assert group in ("target", "control")
    assert f"P01: assigned to the {group} group by block randomisation" in panel.message.value
    # Switching the protocol keeps the choice visible.
    panel.protocol.value = str(protocol_file)
    assert panel.group.label == "randomised (block randomisation)"
