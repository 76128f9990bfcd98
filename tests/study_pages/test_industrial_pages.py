"""The study pages run industrial-sim (the paper's phases on the UR5) with the 3-D canvas: the lab page
from the experimenter's panel to the end, the online page from the link to the next screen."""

import numpy as np

from mt_widgets import SKILLS
from mt_widgets.apps.study import LabStudyPage, OnlineStudyPage
from mt_widgets.study import read_events
from mt_widgets.widgets import EpisodeWidget, SpaceTeachingCanvas, TeachingCanvas
from protocols import industrial_online_toml

from .support import act, prolific


def test_the_lab_page_teaches_industrial_sim_in_3d_from_practice_to_the_end(tmp_path):
    page = LabStudyPage("industrial-sim", tmp_path / "logs", "", experimenter_code="s3cret")
    page.unlock("s3cret")
    page.app.experimenter.participant.value = "I01"
    page.app.experimenter.start_button.click()
    view = page.app.participant_view
    while page.session.current_step().kind != "practice":
        act(view)
    # Practice: a 3-D drawing round on the neutral skill; its last arrow starts a new round.
    practice = view.episode
    assert isinstance(practice.teaching, SpaceTeachingCanvas) and practice.skill.key == "ur5-practice"
    assert not practice.guidance and not practice.reproduce
    for _ in practice.query_states:
        practice.demonstrate(np.array([0.05, -0.02, 0.01]))
    assert view.episode is not practice and isinstance(view.episode.teaching, SpaceTeachingCanvas)
    assert view.episode.episode.demonstrations == []
    assert not [e for e in page.session.events if e["type"] == "demonstration"]  # practice is not a result
    guided_phases, kinds = set(), set()
    while not page.session.finished:
        step = page.session.current_step()
        if step.kind == "demonstration":
            episode = view.episode
            kinds.add(type(episode.teaching))
            assert isinstance(episode, EpisodeWidget) and episode.episode is step.teaching_episode
            assert not any(isinstance(getattr(w, "teaching", None), TeachingCanvas) for w in view.body.children)
            if episode.phase == "guidance":
                guided_phases.add(step.phase)
                # The optimal arrow is the canvas's: its words name it beside the participant's.
                assert episode.teaching.showing_guidance and "optimal arrow" in episode.teaching.describe()
        if step.kind == "questionnaire":
            view.form.fields["difficulty"].value = "easy"
            view.form.continue_button.click()
            continue
        act(view)
    assert kinds == {SpaceTeachingCanvas}
    events = read_events(tmp_path / "logs" / "I01.jsonl")[0]
    group = events[0]["group"]
    assert guided_phases == ({"P3"} if group == "target" else set())
    finished = [e for e in events if e["type"] == "episode_finished"]
    assert len(finished) == 12 and page.session.completed
    shown = [e for e in events if e["type"] == "demonstration"]
    assert all(len(e["action"]) == 3 for e in shown) and len(shown) == 4 + 5 + 8 * 4 + 4 + 5


def test_the_online_page_builds_the_3d_canvas_for_industrial_sim_and_moves_on_after_an_episode(tmp_path):
    protocol = tmp_path / "industrial_online.toml"
    protocol.write_text(industrial_online_toml(practice_s=1))
    page = OnlineStudyPage(str(protocol), tmp_path / "logs", prolific("IND00001"))
    view = page.view
    while page.session.current_step().kind != "demonstration":
        act(view)
    episode = view.episode
    assert isinstance(episode.teaching, SpaceTeachingCanvas) and episode.skill.key == "ur5-reach"
    step = page.session.current_step()
    episode.demonstrate(SKILLS["ur5-reach"].target_actions(step.state[None])[0])
    assert page.session.current_step().index == 1 and episode.state_index == 1
    while page.session.current_step().kind != "reproduction":
        act(view)
    assert episode.phase == "finished" and episode.teaching.animation is not None
    continue_button = episode.next_actions.children[-1]
    assert continue_button.description == "Continue" and continue_button.layout.display is None
    continue_button.disabled = False   # enabled once the reproduction has played (a timer in a kernel)
    continue_button.click()
    assert page.session.current_step().kind == "phase_intro" and page.session.current_step().phase == "P2"


def test_a_new_kernel_resumes_a_3d_episode_mid_way_from_the_log(tmp_path):
    # A reload in Voila is a new kernel: the page rebuilds the episode from the log, on the UR5 as on a planar arm.
    def lab_page():
        page = LabStudyPage("industrial-sim", tmp_path / "logs", "", experimenter_code="s3cret")
        page.unlock("s3cret")
        page.app.experimenter.participant.value = "I02"
        return page
    first = lab_page()
    first.app.experimenter.start_button.click()
    indices, followed = [], []
    while not ((step := first.session.current_step()).kind == "demonstration" and step.episode == 2
               and step.index == 2):
        shown = first.app.participant_view.episode
        if step.kind == "demonstration" and not any(shown is seen for seen in followed):
            followed.append(shown)
            shown.on_demonstration(lambda record: indices.append((record.episode_index, record.index)))
        act(first.app.participant_view)
    # Every 3-D demonstration carried its episode's index (0-based, the log's episode - 1), not 0 for all.
    logged = [e for e in first.session.events if e["type"] == "demonstration"]
    assert indices == [(e["episode"] - 1, e["index"]) for e in logged] and indices[-1] == (1, 1)
    given = [e["action"] for e in logged[-2:]]
    first.session.close()                                   # the old kernel ends
    again = lab_page()
    again.app.experimenter.resume_button.click()
    assert again.session is not None, again.app.experimenter.message.value
    episode = again.app.participant_view.episode
    assert isinstance(episode.teaching, SpaceTeachingCanvas) and episode.episode is step_episode(again)
    np.testing.assert_allclose(episode.demonstrations, given)
    assert episode.state_index == 2 and episode.phase == "teaching" and episode.progress.demonstrations_done == 2
    assert "State 3 of 4" in episode.teaching.describe()
    step = again.session.current_step()
    record = episode.demonstrate(SKILLS[step.skill].target_actions(step.state[None])[0])
    assert record.index == 2 and record.episode_index == 1
    assert again.session.events[-1]["type"] == "demonstration" and again.session.events[-1]["index"] == 2


def step_episode(page):
    return page.session.current_step().teaching_episode
