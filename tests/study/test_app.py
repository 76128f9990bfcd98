"""The participant app: the experimenter panel stays apart, blinding holds, bad input is refused
before the participant starts, and a new kernel resumes where the last one stopped."""

import datetime
import re
import types

import numpy as np
import pytest
from ipywidgets import Button
from ipywidgets.widgets.widget import _instances

from blinding_support import participant_texts
from mt_widgets import SKILLS
from mt_widgets.apps import StudyApp
from mt_widgets.study import LogError, SessionStateError, read_events
from mt_widgets.study.protocol import PROTOCOL_FOLDER
from mt_widgets.widgets import EpisodeWidget
from mt_widgets.widgets.tree import widget_tree

from .scripted import SHORT_PROTOCOL, act, click_primary


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


def test_list_participants_lists_a_study_and_creates_none(tmp_path, protocol_file):
    app = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    app.experimenter.list_button.click()
    assert not (tmp_path / "logs").exists()
    assert "No study in" in app.experimenter.message.value and app.experimenter.listing.value == ""
    app.start_participant("P01", group="target")
    again = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    again.experimenter.list_button.click()
    assert "P01" in again.experimenter.listing.value and "target" in again.experimenter.listing.value


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


# -- issue 18: buttons act once, plain words, the video, the practice clock, the arrow named ------------------

VIDEO = PROTOCOL_FOLDER / "media" / "instructions.webm"
AROUND = """
guidance_modality = "arrows"
"""
AROUND_STEPS = f"""
[[before]]
id = "video"
kind = "video"
file = "{VIDEO}"
require_watched = true

[[before]]
id = "consent"
kind = "consent"
text = "Do you agree?"

[[before]]
id = "about"
kind = "demographics"
"""


def steps_protocol_file(tmp_path) -> str:
    base = SHORT_PROTOCOL.replace('text = "Practice."', 'text = "Practice."\nreproduction = false')
    first = base.index("[assignment]")
    path = tmp_path / "around.toml"
    path.write_text(base[:first] + AROUND + base[first:] + AROUND_STEPS)
    return str(path)


def buttons_in(widget):
    found, pending = [], [widget]
    while pending:
        node = pending.pop(0)
        if isinstance(node, Button) and node.layout.display != "none":
            found.append(node)
        pending += list(getattr(node, "children", ()))
    return found


def double_press(button):
    """A double click: both clicks reach the kernel before the page has changed."""
    button.click()
    button.click()


def test_every_button_of_the_study_path_pressed_twice_acts_once(tmp_path):
    app = StudyApp(protocol=steps_protocol_file(tmp_path), log_folder=tmp_path / "logs")
    app.start_participant("P01", group="target")
    pressed = set()
    while not app.session.finished:
        step = app.session.current_step()
        before = len(app.session.events)
        if step.kind == "video":
            app.video.player._handle_custom_msg({"event": "ended", "whole": True}, [])
            double_press(app.video.continue_button)
        elif step.kind == "demographics":
            app.form.fields["age"].value = "30"
            app.form.fields["sex"].value = "female"
            double_press(app.form.continue_button)
        elif step.kind == "practice":
            app._practice_done.disabled = False
            double_press(app._practice_done)
        elif step.kind in ("demonstration", "episode_end"):
            if app.episode.phase == "guidance":
                double_press(app.episode.next_button)
            else:
                app.episode.demonstrate(SKILLS[step.skill].target_actions(step.state[None])[0] + 0.3)
                continue
        elif step.kind == "reproduction":
            double_press(app._continue)
        else:
            primary = [b for b in buttons_in(app.body) if b.button_style == "primary"]
            double_press(primary[0])
        pressed.add(step.kind)
        assert app.stopped_by is None, app.stopped_by
        if step.kind not in ("demonstration", "episode_end"):
            # One step's event (and the next step's own, e.g. an episode's start), never two steps.
            done = [e["type"] for e in app.session.events[before:]]
            assert done[0] != "session_finished" or step.kind == "questionnaire"
            assert sum(t in ("screen_done", "step_done", "consent_given", "practice_finished") for t in done) <= 1
    assert pressed >= {"welcome", "video", "consent", "demographics", "instructions", "practice", "phase_intro",
                       "demonstration", "reproduction"}
    assert app.session.completed


def test_a_double_yes_withdraw_ends_on_the_withdrawal_screen_with_nothing_left_to_press(tmp_path, protocol_file):
    app = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    app.start_participant("P04")
    double_press(app.withdraw_button)
    yes = [b for b in buttons_in(app.withdraw_box) if b.description == "Yes, withdraw"][0]
    double_press(yes)
    assert app.stopped_by is None and app.session.ended == "withdrawn"
    text = " ".join(participant_texts(app.participant_view))
    assert "resume participant" not in text.lower() and "Please call the experimenter" not in text
    assert app.withdraw_box.layout.display == "none"
    app.withdraw()  # code calling it again: nothing happens
    assert [e["type"] for e in read_events(tmp_path / "logs" / "P04.jsonl")[0]].count("withdrawn") == 1


def test_a_stopped_page_offers_no_withdraw_button(tmp_path, protocol_file):
    app = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    app.start_participant("P01")
    app.stop_for_experimenter(LogError("the disk is full"))
    assert app.withdraw_box.layout.display == "none"
    assert not [b for b in buttons_in(app.participant_view) if not b.disabled and b.layout.display != "none"]


def test_form_problems_are_said_in_plain_words_and_nothing_is_logged(tmp_path):
    app = StudyApp(protocol=steps_protocol_file(tmp_path), log_folder=tmp_path / "logs")
    app.start_participant("P01")
    while app.session.current_step().kind != "demographics":
        step = app.session.current_step()
        if step.kind == "video":
            app.video.player._handle_custom_msg({"event": "ended", "whole": True}, [])
            app.video.continue_button.click()
        else:
            [b for b in buttons_in(app.body) if b.button_style == "primary"][0].click()
    logged = len(app.session.events)
    for age, words in (("-5", "from 18 to 120"), ("twelve", "in digits"), ("30.5", "whole number"),
                       ("", "Please answer")):
        app.form.fields["age"].value = age
        app.form.fields["sex"].value = "female"
        app.form.continue_button.click()
        message = app.form.message.value
        assert words in message and "Your age" in message, message
        assert "answers[" not in message and "expected" not in message
        assert not app.form.continue_button.disabled  # offered again
    assert len(app.session.events) == logged and app.stopped_by is None
    app.form.fields["age"].value = "30"
    app.form.continue_button.click()
    assert app.session.current_step().kind == "instructions"


def test_a_video_scrubbed_to_its_end_does_not_count_as_watched(tmp_path):
    app = StudyApp(protocol=steps_protocol_file(tmp_path), log_folder=tmp_path / "logs")
    app.start_participant("P01")
    click_primary(app)  # welcome
    video = app.video
    video.player._handle_custom_msg({"event": "played"}, [])
    video.player._handle_custom_msg({"event": "ended", "whole": False}, [])  # the player reached its end by seeking
    assert video.continue_button.disabled and not video.watched_to_end
    assert "skipped ahead" in video.note.value
    video.player._handle_custom_msg({"event": "ended", "whole": True}, [])  # played through
    assert not video.continue_button.disabled
    video.continue_button.click()
    done = [e for e in app.session.events if e["type"] == "step_done"][-1]
    assert done["watched_to_end"] is True and done["plays"] == 1


def test_the_practice_clock_continues_after_a_reload(tmp_path, protocol_file, monkeypatch):
    from mt_widgets.apps.study import practice
    first = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    first.start_participant("P01")
    while first.session.current_step().kind != "practice":
        act(first)
    first.session.close()
    started = [e for e in first.session.events if e["type"] == "practice_started"][0]
    # The reload comes 3.5 s after the practice began (of its 5 s).
    began = datetime.datetime.fromisoformat(started["time"].replace("Z", "+00:00")).timestamp()
    # Both clocks stand still, so the figures below hold however slowly the machine runs the resume.
    monkeypatch.setattr(practice, "time", types.SimpleNamespace(time=lambda: began + 3.5, monotonic=lambda: 1000.0))
    second = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    second.resume_participant("P01")
    view = second.participant_view.practice
    assert view.elapsed_s == pytest.approx(3.5)
    assert "0:02" in view.left.value  # not 0:05 again
    assert view.done_button.disabled


def test_the_guidance_arrow_is_named_for_the_guided_group_only_while_it_is_shown(tmp_path, protocol_file):
    for group in ("target", "control"):
        app = StudyApp(protocol=protocol_file, log_folder=tmp_path / f"logs-{group}")
        app.start_participant("P01", group=group)
        named = 0
        while not app.session.finished:
            text = " ".join(participant_texts(app.participant_view))
            if "arrow shows the optimal action" in text:
                assert group == "target" and app.episode.phase == "guidance"
                assert "dashed orange arrow" in text
                named += 1
            act(app)
        assert (named > 0) == (group == "target")


def test_a_whole_session_keeps_a_bounded_number_of_widgets_open(tmp_path, protocol_file):
    # An episode leaving the page closes its widgets (tests/widgets/test_retire.py): a study of twelve
    # episodes kept about 1,760 open in the kernel and the browser.
    app = StudyApp(protocol=protocol_file, log_folder=tmp_path / "logs")
    app.start_participant("P01", group="target")
    before = len(_instances)
    episodes, open_after_episode = [], []
    while not app.session.finished:
        act(app)
        episode = app.participant_view.episode
        if isinstance(episode, EpisodeWidget) and (not episodes or episode is not episodes[-1]):
            episodes.append(episode)
            open_after_episode.append(len(_instances) - before)
    assert len(episodes) == 6   # the practice's, then the five of the study
    # Every episode but the last left the page and is closed, its off-page parts too.
    for old in episodes[:-1]:
        assert not any(w.comm is not None for w in widget_tree(old)), "an episode that left the page kept widgets open"
    # Each new episode brings about 120 widgets; without retiring them the count grew by that
    # much per episode (five episodes: over 600).
    assert max(open_after_episode) - min(open_after_episode) < 60, open_after_episode
    assert len(_instances) - before < 250
