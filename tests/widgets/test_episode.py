import numpy as np
import pytest

from mt_widgets import SKILLS, RidgeLearner, optimal_actions, teaching_risk
from mt_widgets.core import DEFAULT_LAMBDA
from mt_widgets.widgets import EpisodeWidget

from .conftest import near, path_points, pointer


def test_guidance_arrows_are_the_optimal_actions_of_core(recorder):
    skill = SKILLS["sim-point"]
    episode = EpisodeWidget(skill, seed=4, guidance=True, lam=0.05)
    expected = optimal_actions(skill.features(episode.query_states), skill.theta, 0.05)
    view = episode.teaching.view
    for index in range(len(episode.query_states)):
        recorder.clear()
        record = episode.demonstrate([0.3, -0.2])
        assert episode.phase == "guidance"
        assert np.allclose(record.optimal_action, expected[index])
        origin = skill.end_effector(episode.query_states[index:index + 1])[0][0]
        tip = view.transform.action_tip(origin, expected[index])
        assert near(path_points(recorder.on(view.layer("arrows"))), tip), "the optimal arrow ends at u_bar"
        assert "optimal" in episode.guidance_panel.value and "N" in episode.guidance_panel.value
        episode.next()
    assert episode.phase == "finished"


def test_without_guidance_the_episode_never_shows_the_optimal_arrow(recorder):
    skill = SKILLS["uarm-point"]
    episode = EpisodeWidget(skill, seed=2, guidance=False)
    assert episode.next_button.layout.display == "none"
    episode.demonstrate([1.0, 0.0])
    assert episode.phase == "teaching" and episode.state_index == 1 and episode.guidance_panel.value == ""
    with pytest.raises(RuntimeError, match="next"):
        episode.next()


def test_an_episode_runs_teaching_guidance_finished_and_reports_what_it_learnt():
    skill = SKILLS["sim-line"]
    records, results, phases = [], [], []
    episode = EpisodeWidget(skill, seed=7, guidance=True, episode_index=2, episodes_total=8,
                            on_demonstration=records.append, on_finished=results.append)
    episode.observe(lambda change: phases.append(change["new"]), names="phase")
    rng = np.random.default_rng(0)
    actions = rng.normal(size=(len(episode.query_states), 2))
    for index, action in enumerate(actions):
        with pytest.raises(RuntimeError, match="expected phase 'guidance'"):
            episode.next()
        episode.demonstrate(action)
        assert episode.progress.demonstrations_done == index + 1
        episode.next()
    assert phases == ["guidance", "teaching"] * 4 + ["guidance", "finished"]
    assert [r.index for r in records] == [0, 1, 2, 3, 4] and all(r.episode_index == 2 for r in records)
    assert all(r.method == "code" and r.time_to_first_input_s is None for r in records)
    (result,) = results
    theta_hat = RidgeLearner(lam=DEFAULT_LAMBDA).fit(skill.features(episode.query_states), actions)
    assert np.allclose(result.theta_hat, theta_hat)
    assert result.error == pytest.approx(teaching_risk(theta_hat, skill.theta)) == episode.error
    assert len(result.trajectory.times) > 1 and result.diverged == result.trajectory.diverged
    assert episode.progress.episodes_done == 3 and episode.teaching.locked
    with pytest.raises(RuntimeError, match="demonstrate"):
        episode.demonstrate([0.0, 0.0])


def test_teaching_the_optimal_arrows_gives_zero_error():
    skill = SKILLS["uarm-line"]
    episode = EpisodeWidget(skill, seed=5, guidance=False)
    for action in episode.optimal:
        episode.demonstrate(action)
    assert episode.phase == "finished" and episode.error < 1e-8


def test_pointer_timing_is_recorded_for_the_study_log():
    skill = SKILLS["sim-point"]
    records = []
    episode = EpisodeWidget(skill, seed=1, guidance=False, on_demonstration=records.append)
    view = episode.teaching.view
    ee = view.end_effector_pixel(episode.query_states[0])
    pointer(view.canvas, "mouse_down", *ee)
    pointer(view.canvas, "mouse_move", *(ee + [10, 5]))
    pointer(view.canvas, "mouse_up", *(ee + [30, 10]))
    episode.teaching.confirm_button.click()
    (record,) = records
    assert record.method == "pointer" and record.time_to_first_input_s >= 0 and record.drawing_duration_s >= 0
    assert not record.guidance_shown and np.allclose(record.action, episode.demonstrations[0])


def test_resuming_restores_given_demonstrations_and_finishes_when_all_are_there():
    skill = SKILLS["uarm-point"]
    first = EpisodeWidget(skill, seed=3, guidance=False)
    given = [[1.0, 0.5], [-0.5, 0.2]]
    resumed = EpisodeWidget(skill, seed=3, guidance=False, demonstrations=given)
    assert resumed.state_index == 2 and resumed.demonstrations == given and resumed.phase == "teaching"
    assert resumed.progress.demonstrations_done == 2
    done = EpisodeWidget(skill, seed=3, guidance=False, demonstrations=first.optimal)
    assert done.phase == "finished" and done.error < 1e-8


def test_bad_arguments_name_themselves():
    with pytest.raises(ValueError, match="skill"):
        EpisodeWidget("sim-circle")
    with pytest.raises(ValueError, match="lam"):
        EpisodeWidget("sim-point", lam=-1)
    with pytest.raises(ValueError, match="query_states"):
        EpisodeWidget("sim-point", query_states=np.zeros((5, 2)))


def test_fewer_states_than_features_says_exact_teaching_is_impossible():
    skill = SKILLS["sim-point"]
    episode = EpisodeWidget(skill, query_states=skill.query_states(seed=0)[:3], guidance=True)
    assert not episode.exact
    episode.demonstrate([0.1, 0.1])
    assert "least-error" in episode.guidance_panel.value
