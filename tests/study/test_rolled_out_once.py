"""A finished episode is rolled out exactly once, whoever shows it (the widget, the study app)
or logs it (the session): they all read one ``TeachingEpisode``'s reproduction.

Rollouts are counted twice over: at ``Skill.reproduce`` and at the plants (every ``Plant``
subclass's ``rollout``), so a rollout that bypasses the skill is counted too."""

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.apps import StudyApp
from mt_widgets.core import Plant, Skill, TeachingEpisode, learner
from mt_widgets.study import Session, read_events
from mt_widgets.widgets import EpisodeWidget

from .scripted import SHORT_PROTOCOL, act, short_protocol


@pytest.fixture
def rollouts(monkeypatch):
    """Every ``Skill.reproduce`` call, as (skill key, theta), whoever makes it."""
    calls = []
    original = Skill.reproduce

    def counting(self, theta, *args, **kwargs):
        calls.append((self.key, np.array(theta, dtype=float)))
        return original(self, theta, *args, **kwargs)

    monkeypatch.setattr(Skill, "reproduce", counting)
    return calls


def _plant_classes(cls=Plant):
    for subclass in cls.__subclasses__():
        yield subclass
        yield from _plant_classes(subclass)


@pytest.fixture
def plant_rollouts(monkeypatch):
    """Every outermost ``rollout`` call of any plant, as its thetas, whoever makes it (a plant's
    rollout calling its parent class's counts once)."""
    calls, depth = [], [0]

    def counting(original):
        def rollout(self, thetas, *args, **kwargs):
            if depth[0] == 0:
                calls.append(np.array(thetas, dtype=float))
            depth[0] += 1
            try:
                return original(self, thetas, *args, **kwargs)
            finally:
                depth[0] -= 1
        return rollout

    for cls in {Plant, *_plant_classes()}:
        if "rollout" in vars(cls):
            monkeypatch.setattr(cls, "rollout", counting(vars(cls)["rollout"]))
    return calls


@pytest.fixture
def built(monkeypatch):
    """Every ``TeachingEpisode`` built, as its query states, and the number of SVDs of Phi taken
    for a learner's operator (``ridge_operator``, what ``RidgeLearner.operator`` takes), whoever
    makes them."""
    episodes, svds = [], [0]
    original_init, original_svd = TeachingEpisode.__init__, learner.ridge_operator

    def init(self, skill, query_states=None, **kwargs):
        original_init(self, skill, query_states, **kwargs)
        episodes.append(np.array(self.query_states))

    def svd(Phi, lam):
        svds[0] += 1
        return original_svd(Phi, lam)

    monkeypatch.setattr(TeachingEpisode, "__init__", init)
    monkeypatch.setattr(learner, "ridge_operator", svd)
    return episodes, svds


def _is_a_skills_own(theta) -> bool:
    """Whether plant-level thetas are one paper skill's own policy (the ghost), not a learnt one."""
    return any(theta.size == skill.theta.size and np.array_equal(theta.reshape(skill.theta.shape), skill.theta)
               for skill in SKILLS.values())


def _learnt(calls, skill_key):
    """The calls that rolled out a learnt policy (not the target skill's own motion, the ghost)."""
    return [theta for key, theta in calls if not np.array_equal(theta, SKILLS[key].theta)]


def test_an_episode_shown_by_the_widget_and_logged_by_the_session_is_rolled_out_once(rollouts, plant_rollouts):
    session = Session.lesson(short_protocol(), group="target")
    finished = 0
    while not session.finished:
        step = session.current_step()
        if step.kind != "demonstration":
            session.advance() if step.kind != "practice" else session.finish_practice(duration_s=1.0)
            continue
        rollouts.clear()
        plant_rollouts.clear()
        widget = EpisodeWidget(step.skill, query_states=step.query_states, lam=session.protocol.lam,
                               duration=session.protocol.reproduction_duration_s, ghost=True,
                               guidance=step.guidance)
        widget.on_demonstration(lambda record: session.submit_demonstration(record.action, index=record.index))
        widget.on_finished(lambda result: session.finish_episode(result.episode))
        skill = SKILLS[step.skill]
        for state in step.query_states:
            widget.demonstrate(skill.target_actions(state[None])[0] + 0.3)
            if widget.phase == "guidance":
                widget.next()
        assert widget.phase == "finished"
        # Everything that shows or reads the reproduction afterwards: the session's step and
        # result, the widget's result, a replay.
        reproduction = session.current_step()
        assert reproduction.kind == "reproduction"
        assert reproduction.result.trajectory is widget.result.trajectory is widget.episode.reproduction
        widget.player.replay_button.click()
        assert reproduction.result.theta_error == pytest.approx(widget.theta_error)
        learnt = _learnt(rollouts, step.skill)
        assert len(learnt) == 1, f"the learnt skill was rolled out {len(learnt)} times"
        np.testing.assert_allclose(learnt[0], widget.episode.theta_hat)
        assert len(rollouts) - len(learnt) <= 1, "the target skill's own motion is rolled out at most once"
        at_plants = [theta for theta in plant_rollouts if not _is_a_skills_own(theta)]
        assert len(at_plants) == 1, f"the plants rolled out a learnt skill {len(at_plants)} times"
        np.testing.assert_allclose(at_plants[0].reshape(widget.episode.theta_hat.shape), widget.episode.theta_hat)
        assert len(plant_rollouts) == len(rollouts), "a rollout bypassed Skill.reproduce"
        finished += 1
        session.advance()
    assert finished == short_protocol().n_episodes


def test_the_study_app_rolls_out_each_logged_episode_once(tmp_path, rollouts, plant_rollouts, built):
    protocol_file = tmp_path / "short.toml"
    protocol_file.write_text(SHORT_PROTOCOL)
    app = StudyApp(protocol=str(protocol_file), log_folder=tmp_path / "logs")
    app.start_participant("P01", group="target")
    while not app.session.finished:
        step = app.session.current_step()
        if step.kind == "reproduction":
            assert step.result.trajectory is app.episode.result.trajectory
        act(app)
    events, _ = read_events(tmp_path / "logs" / "P01.jsonl")
    logged = [event for event in events if event["type"] == "episode_finished"]
    assert len(logged) == short_protocol().n_episodes
    # The practice was not taught (act() continues past it): every rollout is a logged episode's.
    learnt = [theta for key, theta in rollouts]
    assert len(learnt) == len(logged), f"{len(learnt)} rollouts for {len(logged)} episodes"
    for event, theta in zip(logged, learnt):
        np.testing.assert_allclose(theta, event["theta_hat"], atol=1e-12)
    assert len(plant_rollouts) == len(logged), f"the plants rolled out {len(plant_rollouts)} times for {len(logged)}"
    for event, theta in zip(logged, plant_rollouts):
        np.testing.assert_allclose(theta.reshape(np.shape(event["theta_hat"])), event["theta_hat"], atol=1e-12)
    # One TeachingEpisode per study episode, shared by the session (the log) and the widget (the
    # page), and so one SVD of its features.
    episodes, svds = built
    for started in (event for event in events if event["type"] == "episode_started"):
        states = np.asarray(started["query_states"])
        copies = sum(1 for built_states in episodes if np.array_equal(built_states, states))
        assert copies == 1, f"episode {started['phase']}E{started['episode']} was built {copies} times"
    assert svds[0] == len(episodes), f"{svds[0]} SVDs for {len(episodes)} episodes"
