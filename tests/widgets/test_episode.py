import numpy as np
import pytest
from ipywidgets import HTML

from mt_widgets import SKILLS, RidgeLearner, optimal_actions, teaching_risk
from mt_widgets.apps.uarm_screen import ScreenGeometry, fit_episode
from mt_widgets.core import DEFAULT_LAMBDA
from mt_widgets.widgets import EpisodeWidget
from mt_widgets.widgets.episode import stage_css

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
    theta_hat = RidgeLearner(lam=DEFAULT_LAMBDA).fit(skill.features(episode.query_states), actions).theta
    assert np.allclose(result.theta_hat, theta_hat)
    assert result.theta_error == pytest.approx(teaching_risk(theta_hat, skill.theta)) == episode.theta_error
    assert len(result.trajectory.times) > 1 and result.diverged == result.trajectory.diverged
    assert episode.progress.episodes_done == 3 and episode.teaching.locked
    with pytest.raises(RuntimeError, match="demonstrate"):
        episode.demonstrate([0.0, 0.0])


def test_teaching_the_optimal_arrows_gives_zero_error():
    skill = SKILLS["uarm-line"]
    episode = EpisodeWidget(skill, seed=5, guidance=False)
    for action in episode.optimal:
        episode.demonstrate(action)
    assert episode.phase == "finished" and episode.theta_error < 1e-8


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
    assert done.phase == "finished" and done.theta_error < 1e-8


def test_bad_arguments_name_themselves():
    with pytest.raises(ValueError, match="skill"):
        EpisodeWidget("sim-circle")
    with pytest.raises(ValueError, match="lam"):
        EpisodeWidget("sim-point", lam=-1)
    # (None is the default: DEFAULT_LAMBDA, or a shown TeachingEpisode's own; tests/widgets/test_episode_options.py.)
    for bad in ("0.1", [0.1], True):
        with pytest.raises(TypeError, match="lam: expected a real number"):
            EpisodeWidget("sim-point", lam=bad)
    with pytest.raises(ValueError, match="query_states"):
        EpisodeWidget("sim-point", query_states=np.zeros((5, 2)))


def test_fewer_states_than_features_says_exact_teaching_is_impossible():
    skill = SKILLS["sim-point"]
    episode = EpisodeWidget(skill, query_states=skill.query_states(seed=0)[:3], guidance=True)
    assert not episode.exact
    episode.demonstrate([0.1, 0.1])
    assert "least-error" in episode.guidance_panel.value


class LogRefused(RuntimeError):
    pass


@pytest.mark.parametrize("guidance", [True, False])
@pytest.mark.parametrize("last", [False, True])
def test_a_demonstration_a_callback_refuses_is_neither_shown_guidance_nor_counted(recorder, guidance, last):
    skill = SKILLS["sim-point"]
    refuse = [False]
    logged, finished = [], []

    def log(record):  # e.g. the study log could not be written
        if refuse[0]:
            raise LogRefused("the log could not be written")
        logged.append(record)

    episode = EpisodeWidget(skill, seed=1, guidance=guidance, on_demonstration=log, on_finished=finished.append)
    n = len(episode.query_states)
    for action in episode.optimal[: n - 1 if last else 1]:
        episode.demonstrate(action)
        if guidance:
            episode.next()
    index = episode.state_index
    arrows = episode.teaching.view.layer("arrows")
    refuse[0] = True
    recorder.clear()
    episode.teaching.set_action([0.4, 0.1])
    drawn = len(recorder.on(arrows))
    with pytest.raises(LogRefused):
        episode.teaching.confirm()
    # The error reached the caller: nothing moved on, no optimal arrow, no explanation.
    assert len(recorder.on(arrows)) == drawn, "an arrow was drawn for an unlogged demonstration"
    assert episode.phase == "teaching" and episode.guidance_panel.value == ""
    assert episode.next_button.layout.display == "none" and not finished
    assert episode.state_index == episode.teaching.state_index == index
    assert len(episode.demonstrations) == len(episode.records) == len(logged) == index
    assert episode.progress.demonstrations_done == index
    # The arrow stays pending and unlocked: once the log works again, confirming it records it.
    assert episode.teaching.pending_action == [0.4, 0.1] and not episode.teaching.locked
    refuse[0] = False
    episode.teaching.confirm_button.click()
    assert [r.index for r in logged] == list(range(index + 1))
    assert episode.phase == ("guidance" if guidance else "finished" if last else "teaching")


def test_a_confirm_button_click_whose_callback_fails_does_not_record_the_arrow():
    skill = SKILLS["uarm-point"]
    episode = EpisodeWidget(skill, seed=1, guidance=True,
                            on_demonstration=lambda record: 1 / 0)
    episode.teaching.set_action([1.0, 0.0])
    episode.teaching.confirm_button.click()  # ipywidgets' dispatcher reports the error
    assert episode.phase == "teaching" and episode.demonstrations == [] and episode.records == []


def test_restored_demonstrations_of_the_wrong_shape_are_refused_by_name_not_reshaped():
    skill = SKILLS["uarm-point"]
    episode = EpisodeWidget(skill, seed=3, guidance=False)
    # Two 3-component actions used to be reshaped silently into three 2-component ones.
    with pytest.raises(ValueError, match=r"demonstrations: expected shape \(k, 2\)"):
        episode.restore([[1.0, 0.5, 0.0], [-0.5, 0.2, 0.0]])
    with pytest.raises(ValueError, match=r"demonstrations: expected shape \(k, 2\)"):
        EpisodeWidget(skill, seed=3, demonstrations=[1.0, 0.5, -0.5, 0.2])
    with pytest.raises(ValueError, match=r"actions: expected shape \(k, 2\)"):
        episode.teaching.restore([[1.0, 0.5, 0.0]])
    with pytest.raises(ValueError, match="action: expected 2 finite numbers"):
        episode.teaching.set_action([1.0, 0.5, 0.0])
    assert episode.state_index == 0 and episode.demonstrations == []
    episode.restore([])
    episode.restore(np.zeros((0, 2)))
    assert episode.state_index == 0


@pytest.mark.parametrize("guidance", [True, False])
def test_the_typed_arrow_fields_start_empty_at_each_new_state(guidance):
    skill = SKILLS["sim-point"]
    episode = EpisodeWidget(skill, seed=2, guidance=guidance)
    teaching = episode.teaching
    for mode in ("components", "polar"):
        teaching.entry_mode.value = mode
        teaching.first_entry.value, teaching.second_entry.value = 30.0, 2.0
        teaching.set_button.click()
        assert teaching.pending_action is not None
        teaching.confirm_button.click()
        if guidance:
            episode.next()
        # The next state: no arrow yet, and nothing typed that "Set arrow" would re-apply.
        assert teaching.pending_action is None
        assert (teaching.first_entry.value, teaching.second_entry.value) == (0.0, 0.0)
        teaching.set_button.click()
        assert teaching.pending_action == [0.0, 0.0], "Set arrow re-applied the previous state's arrow"
        teaching.clear_action()
    teaching.set_action([1.5, -0.5])
    teaching.entry_mode.value = "components"
    assert (teaching.first_entry.value, teaching.second_entry.value) == (1.5, -0.5), "the fields show the arrow"
    teaching.clear_action()
    assert (teaching.first_entry.value, teaching.second_entry.value) == (0.0, 0.0)


def test_the_canvases_grow_with_the_window_unless_sized_or_fitted_to_a_screen():
    episode = EpisodeWidget("uarm-point", seed=0)
    views = (episode.teaching.view, episode.player.view)
    classes = [[c for c in view.canvas._dom_classes if c.startswith("mt-stage-canvas-")] for view in views]
    assert classes == [["mt-stage-canvas-63"]] * 2, "304 x 480 canvases: width / height = 0.63"
    css = stage_css(*views)
    assert ".mt-stage-canvas-63 {width: max(260px, min(calc(100vw - 480px), calc((100vh - 350px) * 0.6333)" in css
    assert any(isinstance(w, HTML) and w.value == css for w in episode.children)
    # A given CSS width is kept as it is, and a true-size screen under the arm keeps its size.
    sized = EpisodeWidget("uarm-point", seed=0, css_width="260px")
    assert not any(c.startswith("mt-stage") for c in sized.teaching.view.canvas._dom_classes)
    fit_episode(episode, ScreenGeometry())
    assert not any(c.startswith("mt-stage") for view in views for c in view.canvas._dom_classes)


def test_the_planar_and_the_3d_episode_refuse_what_they_cannot_show_alike():
    # One widget for every arm (episode_to_show decides what it shows): the same refusals, word for word.
    from mt_widgets.core import TeachingEpisode
    widget = EpisodeWidget
    for key in ("sim-point", "ur5-reach"):
        with pytest.raises(TypeError, match=r"^skill: expected a Skill, a TeachingEpisode or a skill key, got int"):
            widget(3)
        with pytest.raises(ValueError, match=r"^skill: expected a Skill, a TeachingEpisode or one of \["):
            widget("no-such-skill")
        shown = TeachingEpisode(SKILLS[key], seed=0)
        with pytest.raises(ValueError, match=r"^duration: expected None when a TeachingEpisode is shown"):
            widget(shown, duration=2.0)
        assert widget(shown).episode is shown


@pytest.mark.parametrize("skill, guidance", [("sim-point", True), ("sim-point", False), ("ur5-reach", True)])
def test_the_state_index_moves_only_forward_through_an_episode(skill, guidance):
    episode = EpisodeWidget(skill, seed=0, guidance=guidance)
    seen = [episode.state_index]
    episode.observe(lambda change: seen.append(change["new"]), "state_index")
    for optimal in episode.optimal:
        episode.demonstrate(optimal)
        if guidance:
            assert episode.state_index == seen[-1] == len(episode.demonstrations) - 1   # the guided state
            episode.next()
    n = len(episode.query_states)
    assert seen == list(range(n + 1)), f"the state shown went {seen}, not 0, 1, ..., {n}"
