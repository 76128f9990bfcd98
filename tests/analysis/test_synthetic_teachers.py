"""Synthetic teachers and in-silico studies: the model does what its documentation says."""

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from mt_widgets.core import SKILLS
from mt_widgets.study.in_silico import (
    Progress,
    compare_with_paper,
    episode_plan,
    resolve_protocol,
    run_in_silico,
    run_many_studies,
    run_through_sessions,
    teacher_seed,
)
from mt_widgets.study.power import simulated_power
from mt_widgets.study.synthetic_teachers import (
    OPTIMAL_TEACHER,
    PAPER_FIT,
    TeacherParameters,
    TeacherPopulation,
    naive_offsets,
    with_parameters,
)

QUIET = with_parameters(PAPER_FIT, direction_noise=0.0, magnitude_noise=0.0, reproduction_learning=0.0)


def test_a_teacher_is_the_same_drawn_alone_or_in_a_crowd():
    alone = TeacherPopulation.draw(PAPER_FIT, [teacher_seed(5, 3)], 12, 5)
    crowd = TeacherPopulation.draw(PAPER_FIT, [teacher_seed(5, p) for p in range(6)], 12, 5)
    assert alone.magnitude[0] == crowd.magnitude[3]
    assert np.array_equal(alone.demonstration_noise[0], crowd.demonstration_noise[3])
    assert not np.array_equal(crowd.demonstration_noise[2], crowd.demonstration_noise[3])


def test_an_in_silico_study_is_reproducible_from_its_seed():
    a = run_in_silico(8, seed=11, reproduce=False)
    b = run_in_silico(8, seed=11, reproduce=False)
    c = run_in_silico(8, seed=12, reproduce=False)
    pd.testing.assert_frame_equal(a.episodes, b.episodes)
    pd.testing.assert_frame_equal(a.demonstrations, b.demonstrations)
    assert not np.allclose(a.episodes.teaching_error, c.episodes.teaching_error)


def test_the_optimal_teacher_teaches_every_skill_exactly():
    study = run_in_silico(4, parameters=OPTIMAL_TEACHER, reproduce=False)
    assert study.episodes.teaching_error.max() < 1e-9
    demos = study.demonstrations
    assert np.allclose(demos[["action_1", "action_2"]].to_numpy(), demos[["optimal_1", "optimal_2"]].to_numpy())


def test_novices_point_at_the_target_too_hard_and_ignore_velocity():
    study = run_in_silico(6, parameters=QUIET, reproduce=False)
    p1 = study.demonstrations[study.demonstrations.phase == "P1"]
    skill = SKILLS["sim-point"]
    states = np.array([np.array(eval(s)) for s in p1.state])
    positions, _ = skill.end_effector(states)
    offsets = naive_offsets(positions, skill.target)
    actions = p1[["action_1", "action_2"]].to_numpy()
    # P1 has no guidance, so the arrow is the naive one turned by the episode's exploration angle:
    # one rotation per participant, and a length m_i * distance (g = 1 N/m for the sim skills).
    cos = np.sum(actions * offsets, axis=1) / np.linalg.norm(actions, axis=1) / np.linalg.norm(offsets, axis=1)
    per_participant = pd.Series(cos).groupby(p1.participant.to_numpy()).agg(np.ptp)
    assert per_participant.max() < 1e-9
    ratio = np.linalg.norm(actions, axis=1) / np.linalg.norm(offsets, axis=1)
    assert pd.Series(ratio).groupby(p1.participant.to_numpy()).agg(np.ptp).max() < 1e-9
    optimal = p1[["optimal_1", "optimal_2"]].to_numpy()
    assert np.median(np.linalg.norm(actions, axis=1) / np.linalg.norm(optimal, axis=1)) > 1


def test_without_guidance_teachers_explore_direction_but_not_magnitude():
    control = ["control"] * 4
    study = run_in_silico(4, parameters=QUIET, groups=control, reproduce=False)
    demos = study.demonstrations[study.demonstrations.skill == "sim-point"]
    skill = SKILLS["sim-point"]
    states = np.array([np.array(eval(s)) for s in demos.state])
    offsets = naive_offsets(skill.end_effector(states)[0], skill.target)
    actions = demos[["action_1", "action_2"]].to_numpy()
    gain = np.linalg.norm(actions, axis=1) / np.linalg.norm(offsets, axis=1)
    by_participant = pd.Series(gain).groupby(demos.participant.to_numpy())
    assert by_participant.agg(np.ptp).max() < 1e-9     # the same magnitude habit in every episode
    angle = np.arctan2(offsets[:, 0] * actions[:, 1] - offsets[:, 1] * actions[:, 0], np.sum(offsets * actions, 1))
    turns = pd.Series(angle).groupby([demos.participant.to_numpy(), demos.phase_index.to_numpy(),
                                      demos.episode.to_numpy()]).first()
    assert turns.groupby(level=0).std().min() > 0.05    # but a new direction every episode


def test_guided_teachers_move_toward_the_optimal_arrows_and_control_does_not():
    study = run_in_silico(40, reproduce=False)
    rows = study.episodes
    p3 = rows[rows.phase == "P3"].groupby(["group", "episode"]).teaching_error.mean()
    assert p3["target"][8] < 0.6 * p3["target"][1]
    assert p3["control"][8] > 0.8 * p3["control"][1]


def test_batched_engine_and_session_engine_give_the_same_study(tmp_path):
    from mt_widgets.study.tidy import read_study
    run_through_sessions(tmp_path / "study", 2, seed=4)
    episodes, demonstrations = read_study(tmp_path / "study")
    logged = pd.DataFrame(episodes)
    groups = logged.groupby("participant").group.first().tolist()
    fast = run_in_silico(2, seed=4, groups=groups, reproduce=True)
    key = ["participant", "phase_index", "episode"]
    logged, batched = logged.sort_values(key), fast.episodes.sort_values(key)
    assert logged.teaching_error.to_numpy() == pytest.approx(batched.teaching_error.to_numpy(), abs=1e-9)
    assert list(logged.reproduction_diverged.astype(bool)) == list(batched.reproduction_diverged.astype(bool))
    logged_demos = pd.DataFrame(demonstrations).sort_values(key + ["index"])
    batched_demos = fast.demonstrations.sort_values(key + ["index"])
    assert logged_demos.action_1.to_numpy() == pytest.approx(batched_demos.action_1.to_numpy(), abs=1e-12)
    assert logged_demos.drawing_duration_s.to_numpy() == pytest.approx(batched_demos.drawing_duration_s.to_numpy())


def test_the_fitted_teachers_land_near_the_papers_changes():
    deltas = run_many_studies(1, 600, seed=21, share_states=True, progress=False)
    from mt_widgets.study.in_silico import paper_results
    for name, groups in paper_results()["simulation"]["changes"].items():
        for group, paper in groups.items():
            assert abs(deltas[name][group].mean() - paper["mean"]) < 0.5 * paper["sd"], (name, group)
            assert 0.4 < deltas[name][group].std(ddof=1) / paper["sd"] < 1.6, (name, group)


def test_compare_with_paper_has_one_row_per_change_and_group():
    table = compare_with_paper(run_in_silico(16, reproduce=False))
    assert len(table) == 6
    assert table.loc[0, "mean_gap"] == pytest.approx(table.loc[0, "in_silico_mean"] - table.loc[0, "paper_mean"])


def test_without_an_effect_simulated_power_is_the_false_positive_rate():
    # Teachers who learn nothing from guidance: the groups differ by chance only, so a
    # one-sided test at alpha = 0.05 rejects in about 5 % of studies.
    null = with_parameters(PAPER_FIT, learning_rate=0.0)
    result = simulated_power(n_per_group=8, n_studies=400, parameters=null, seed=2, progress=False, share_states=True)
    assert result.power["P1_to_P4"]["welch"] < 0.1
    strong = simulated_power(n_per_group=8, n_studies=60, seed=2, progress=False)
    assert strong.power["P1_to_P3E8"]["welch"] > 0.8


def test_simulated_power_is_reproducible_from_its_seed():
    a = simulated_power(n_per_group=4, n_studies=20, seed=9, progress=False)
    b = simulated_power(n_per_group=4, n_studies=20, seed=9, progress=False)
    assert a.power == b.power
    assert set(a.table().columns) >= {"change", "test", "power", "mc_se"}


def test_teacher_parameters_refuse_values_out_of_range():
    with pytest.raises(ValueError, match="retention"):
        TeacherParameters(retention=1.5)
    with pytest.raises(ValueError, match="magnitude"):
        TeacherParameters(magnitude=-1.0)


def test_progress_prints_a_text_line_outside_a_kernel(capsys):
    bar = Progress(3, "studies")
    for _ in range(3):
        bar.update()
    assert "studies 3/3" in capsys.readouterr().err


def test_the_study_analysis_imports_without_widgets():
    code = ("import sys, mt_widgets.study.in_silico, mt_widgets.study.figures, mt_widgets.study.power, "
            "mt_widgets.study.synthetic_teachers, mt_widgets.study.statistics; "
            "print(any(m in sys.modules for m in ('ipywidgets', 'ipycanvas', 'serial')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


def test_the_plan_follows_the_protocol():
    plan = episode_plan(resolve_protocol("paper-sim"))
    assert [f"{s['phase']}E{s['episode']}" for s in plan][:4] == ["P1E1", "P2E1", "P3E1", "P3E2"]
    assert len(plan) == 12
