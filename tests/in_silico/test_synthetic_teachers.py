"""Synthetic teachers and in-silico studies: the model does what its documentation says."""

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from mt_widgets.analysis.paper_comparison import baseline_comparison, compare_with_paper
from mt_widgets.analysis.power import simulated_power
from mt_widgets.core import SKILLS
from mt_widgets.in_silico.engine import run_in_silico, run_many_studies
from mt_widgets.in_silico.paper_results import implied_baselines, paper_changes, paper_results
from mt_widgets.in_silico.plan import episode_plan, imagined_line_target, paper_fit, resolve_protocol, teacher_seed
from mt_widgets.in_silico.progress import Progress
from mt_widgets.in_silico.sessions import run_through_sessions
from mt_widgets.in_silico.teachers import (
    OPTIMAL_TEACHER,
    PAPER_FIT,
    PAPER_FIT_UARM,
    TeacherParameters,
    TeacherPopulation,
    line_foot,
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
    assert not np.allclose(a.episodes.theta_error, c.episodes.theta_error)


def test_the_optimal_teacher_teaches_every_skill_exactly():
    study = run_in_silico(4, parameters=OPTIMAL_TEACHER, reproduce=False)
    assert study.episodes.theta_error.max() < 1e-9
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
    p3 = rows[rows.phase == "P3"].groupby(["group", "episode"]).theta_error.mean()
    assert p3["target"][8] < 0.6 * p3["target"][1]
    assert p3["control"][8] > 0.8 * p3["control"][1]


@pytest.mark.slow
def test_batched_engine_and_session_engine_give_the_same_study(tmp_path):
    from mt_widgets.study.tidy import read_study
    run_through_sessions(tmp_path / "study", 2, seed=4)
    episodes, demonstrations = read_study(tmp_path / "study")
    logged = pd.DataFrame(episodes)
    groups = logged.groupby("participant").group.first().tolist()
    fast = run_in_silico(2, seed=4, groups=groups, reproduce=True)
    key = ["participant", "phase_index", "episode"]
    logged, batched = logged.sort_values(key), fast.episodes.sort_values(key)
    assert logged.theta_error.to_numpy() == pytest.approx(batched.theta_error.to_numpy(), abs=1e-9)
    assert list(logged.reproduction_diverged.astype(bool)) == list(batched.reproduction_diverged.astype(bool))
    logged_demos = pd.DataFrame(demonstrations).sort_values(key + ["index"])
    batched_demos = fast.demonstrations.sort_values(key + ["index"])
    assert logged_demos.action_1.to_numpy() == pytest.approx(batched_demos.action_1.to_numpy(), abs=1e-12)
    assert logged_demos.drawing_duration_s.to_numpy() == pytest.approx(batched_demos.drawing_duration_s.to_numpy())


@pytest.mark.parametrize("protocol", ["paper-sim", "paper-uarm"])
def test_the_fitted_teachers_land_near_the_papers_changes(protocol):
    # A large run on another seed than the fit's (0): each change's mean lies within half the
    # paper's SD of the paper's, and its SD between 0.4 and 1.6 times the paper's (the control
    # groups' SDs come out low, 0.6-0.8 times: see docs/user/analysis.md). Two exceptions,
    # both the uArm control group, whose printed changes move (-1.54 better by P3E8, +2.21 worse
    # by P5) where teachers who only turn their arrows cannot move on average: its P1 -> P3E8
    # mean is allowed 0.75 SD (the model gives about +0.8, the P3E8 states being a little harder
    # for the same habit), and its P2 -> P5 SD (paper 5.54) is not checked (about 1.5).
    experiment = "physical" if protocol == "paper-uarm" else "simulation"
    deltas = run_many_studies(1, 600, seed=21, share_states=True, progress=False, protocol=protocol)
    for name, groups in paper_changes(paper_results(), experiment).items():
        for group, paper in groups.items():
            allowed = 0.75 if (experiment, name, group) == ("physical", "P1_to_P3E8", "control") else 0.5
            assert abs(deltas[name][group].mean() - paper["mean"]) < allowed * paper["sd"], (name, group)
            if (experiment, name, group) != ("physical", "P2_to_P5", "control"):
                assert 0.4 < deltas[name][group].std(ddof=1) / paper["sd"] < 1.6, (name, group)


@pytest.mark.parametrize("protocol", ["paper-sim", "paper-uarm"])
def test_the_fitted_baselines_are_the_ones_the_papers_percentages_imply(protocol):
    experiment = "physical" if protocol == "paper-uarm" else "simulation"
    deltas = run_many_studies(1, 600, seed=21, share_states=True, progress=False, protocol=protocol)
    implied = implied_baselines(paper_results(), experiment)
    # P1 is the baseline of P1 -> P3E8, P2 of P2 -> P5; within 5 % of the paper's.
    assert deltas["P1_to_P3E8"]["before"].mean() == pytest.approx(implied["P1"], rel=0.05)
    assert deltas["P2_to_P5"]["before"].mean() == pytest.approx(implied["P2"], rel=0.05)


def test_the_papers_baselines_follow_from_its_changes_and_percentages():
    simulation = implied_baselines(paper_results(), "simulation")
    assert simulation["P1"] == pytest.approx((2.03 / 0.6940 + 1.51 / 0.5147) / 2)
    assert simulation["P2"] == pytest.approx(1.47 / 0.5003)
    physical = implied_baselines(paper_results(), "physical")
    assert physical == pytest.approx({"P1": 5.30 / 0.8826, "P2": 6.32 / 0.7734})


@pytest.mark.slow
def test_in_the_simulation_the_two_baselines_do_not_differ_as_in_the_paper():
    # The paper's post-hoc check finds no difference between the P1 and P2 errors (p = 0.0989,
    # 0.1148). Over 150 studies of 2 x 16 with their own query states, the paired t-test of
    # P1 against P2 within a group is significant at 0.05 in only a few of them (a model whose
    # line baseline sat at 2.2 against P1's 3.0 made it significant in nearly every study).
    deltas = run_many_studies(150, 16, seed=3, progress=False, workers=1)
    p1, p2 = deltas["P1_to_P3E8"]["before"], deltas["P2_to_P5"]["before"]
    for members in (slice(0, 16), slice(16, 32)):
        p = stats.ttest_rel(p1[:, members], p2[:, members], axis=1).pvalue
        assert np.mean(p < 0.05) < 0.25
        assert np.median(p) > 0.1


def test_novices_aim_at_the_point_they_taught_when_asked_for_a_line():
    # Model item 1b: on the line skill the arrow aims at (1 - s) * foot + s * anchor, the
    # anchor being skill 1's point (0.8, 1.2) m, which lies on the line r1 = 0.8.
    protocol = resolve_protocol("paper-sim")
    assert np.array_equal(imagined_line_target(protocol, 1), [0.8, 1.2])
    assert imagined_line_target(protocol, 0) is None
    steady = with_parameters(QUIET, exploration=0.0)
    for share in (0.0, 0.6):
        study = run_in_silico(4, parameters=with_parameters(steady, line_as_point=share), groups=["control"] * 4,
                              reproduce=False, protocol=protocol)
        p2 = study.demonstrations[study.demonstrations.phase == "P2"]
        states = np.array([np.array(eval(s)) for s in p2.state])
        positions, _ = SKILLS["sim-line"].end_effector(states)
        aim = np.column_stack([np.full(len(positions), 0.8), (1 - share) * positions[:, 1] + share * 1.2])
        offsets = aim - positions
        actions = p2[["action_1", "action_2"]].to_numpy()
        cross = offsets[:, 0] * actions[:, 1] - offsets[:, 1] * actions[:, 0]
        assert np.abs(cross).max() < 1e-9 * np.abs(actions).max() * np.abs(offsets).max()
        assert np.all(np.sum(offsets * actions, axis=1) > 0)


def test_the_uarm_line_is_taken_for_skill_1s_point_projected_onto_it():
    anchor = imagined_line_target(resolve_protocol("paper-uarm"), 1)
    assert np.array_equal(anchor, [23.0, 11.0])
    # (23, 11) cm is 0.4 cm off r1 = 2 r2; the teacher aims at its foot on the line.
    assert line_foot(anchor, SKILLS["uarm-line"].target) == pytest.approx([22.8, 11.4])


def test_each_protocol_runs_with_its_own_fit():
    assert paper_fit("paper-sim") is PAPER_FIT
    assert paper_fit("paper-uarm") is PAPER_FIT_UARM
    assert PAPER_FIT_UARM != PAPER_FIT
    assert run_in_silico(4, protocol="paper-uarm", reproduce=False).parameters is PAPER_FIT_UARM


def test_the_physical_p1_to_p4_row_is_compared_as_later_minus_earlier():
    # The paper prints it as an improvement, 4.55 +- 1.80 for the target group.
    physical = paper_changes(paper_results(), "physical")
    assert physical["P1_to_P4"]["target"] == {"mean": -4.55, "sd": 1.80}
    assert physical["P1_to_P4"]["control"] == {"mean": 0.35, "sd": 2.46}
    assert physical["P2_to_P5"]["control"] == {"mean": 2.21, "sd": 5.54}
    table = compare_with_paper(run_in_silico(16, protocol="paper-uarm", reproduce=False))
    assert len(table) == 6
    row = table[(table.change == "P1_to_P4") & (table.group == "target")].iloc[0]
    assert row.paper_mean == -4.55 and row.in_silico_mean < 0


def test_an_unknown_experiment_is_named_in_the_error():
    with pytest.raises(ValueError, match="experiment"):
        paper_changes(paper_results(), "orbital")


def test_baseline_comparison_reads_the_first_episode_of_p1_and_p2():
    study = run_in_silico(8, reproduce=False)
    table = baseline_comparison(study).set_index("phase")
    rows = study.episodes
    assert table.loc["P2", "in_silico_mean"] == pytest.approx(rows[rows.phase == "P2"].theta_error.mean())
    assert table.loc["P1", "paper_mean"] == pytest.approx(implied_baselines(paper_results(), "simulation")["P1"])


def test_compare_with_paper_has_one_row_per_change_and_group():
    table = compare_with_paper(run_in_silico(16, reproduce=False))
    assert len(table) == 6
    assert table.loc[0, "mean_gap"] == pytest.approx(table.loc[0, "in_silico_mean"] - table.loc[0, "paper_mean"])


@pytest.mark.slow
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


@pytest.mark.slow
def test_the_study_analysis_imports_without_widgets():
    code = ("import sys, mt_widgets.in_silico, mt_widgets.analysis.figures, mt_widgets.analysis.power, "
            "mt_widgets.in_silico.teachers, mt_widgets.analysis.statistics, mt_widgets.analysis; "
            "print(any(m in sys.modules for m in ('ipywidgets', 'ipycanvas', 'serial')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


def test_the_plan_follows_the_protocol():
    plan = episode_plan(resolve_protocol("paper-sim"))
    assert [f"{s['phase']}E{s['episode']}" for s in plan][:4] == ["P1E1", "P2E1", "P3E1", "P3E2"]
    assert len(plan) == 12


@pytest.mark.slow
@pytest.mark.parametrize("which", ["sim", "uarm"])
def test_the_shipped_synthetic_studies_are_what_the_current_model_writes(which, tmp_path):
    # Fails when the teacher model or a fit changes without ``python -m mt_widgets.analysis.example_studies``.
    from mt_widgets.analysis import example_studies as analysis
    from mt_widgets.study.tidy import read_study
    folder, settings = {"sim": (analysis.EXAMPLE_STUDY, analysis.EXAMPLE_SETTINGS),
                        "uarm": (analysis.EXAMPLE_UARM_STUDY, analysis.EXAMPLE_UARM_SETTINGS)}[which]
    fresh = analysis.write_example_study(tmp_path / which, **settings)
    key = ["participant", "phase_index", "episode"]
    shipped = pd.DataFrame(read_study(folder)[0]).sort_values(key)
    rewritten = pd.DataFrame(read_study(fresh)[0]).sort_values(key)
    assert set(shipped.skill) == set(rewritten.skill)
    assert shipped.theta_error.to_numpy() == pytest.approx(rewritten.theta_error.to_numpy(), rel=1e-9)
