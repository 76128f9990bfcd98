"""Synthetic teachers in space: the in-silico study runs the paper's phases on the UR5's ``ur5-`` skills
(3-D tool velocities), and machine-teaching guidance helps there as on the planar arm."""

import numpy as np
import pytest

from mt_widgets.core import SKILLS
from mt_widgets.in_silico.engine import run_in_silico
from mt_widgets.in_silico.plan import teacher_seed
from mt_widgets.in_silico.teachers import (
    OPTIMAL_TEACHER,
    PAPER_FIT,
    TeacherPopulation,
    position_gain,
    target_offsets,
    with_parameters,
)
from mt_widgets.study import parse_protocol
from protocols import phase, protocol_toml

KEYS = ("ur5-reach", "ur5-place", "ur5-conveyor")


def industrial_protocol(point="ur5-reach", other="ur5-place"):
    """The paper's phases P1-P5 with a UR5 skill for its skill 1 and another for its skill 2."""
    text = protocol_toml("industrial-in-silico", [
        phase("P1", point), phase("P2", other), phase("P3", point, episodes=8, guidance=["target"]),
        phase("P4", point), phase("P5", other)], seed=31)
    return parse_protocol(text, "industrial-in-silico.toml")


@pytest.fixture(scope="module")
def industrial_study():
    return run_in_silico(40, industrial_protocol(), seed=3, reproduce=False)


def test_the_drawn_arrows_have_three_components_and_the_optimal_teacher_teaches_every_ur5_skill_exactly():
    for point, other in (("ur5-reach", "ur5-conveyor"), ("ur5-place", "ur5-reach")):
        study = run_in_silico(2, industrial_protocol(point, other), parameters=OPTIMAL_TEACHER, reproduce=False)
        assert study.episodes.theta_error.max() < 1e-9
        demos = study.demonstrations
        drawn = demos[["action_1", "action_2", "action_3"]].to_numpy()
        assert np.allclose(drawn, demos[["optimal_1", "optimal_2", "optimal_3"]].to_numpy())
        assert np.abs(drawn[:, 2]).max() > 1e-3   # the height is taught, not left at zero


def test_guidance_helps_in_space_the_target_group_learns_and_keeps_it_the_control_group_does_not(industrial_study):
    rows = industrial_study.episodes
    p3 = rows[rows.phase == "P3"].groupby(["group", "episode"]).theta_error.mean()
    assert p3["target"][8] < 0.6 * p3["target"][1]
    assert p3["control"][8] > 0.8 * p3["control"][1]
    first = rows[rows.episode == 1].groupby(["group", "phase"]).theta_error.mean()
    for before, after in (("P1", "P4"), ("P2", "P5")):   # retention on skill 1, transfer to skill 2
        change = {g: first[g][after] - first[g][before] for g in ("target", "control")}
        assert change["target"] < -0.3 * first["target"][before]
        assert abs(change["control"]) < 0.1 * first["control"][before]


def test_a_novice_pulls_the_tool_toward_the_part_where_the_state_says_it_is_too_hard():
    skill = SKILLS["ur5-conveyor"]
    states = skill.query_states(seed=2)
    offsets = target_offsets(skill, states)
    part = skill.target.at(skill.plant.conveyor_phase(states))
    assert np.allclose(skill.end_effector(states)[0] + offsets, part)
    assert len(set(np.round(part[:, 1], 6))) == len(states)   # the part is somewhere else in every state
    # The naive arrow is m_i g times that pull: g is the spectral norm of Theta's 3 x 3 position block.
    assert position_gain(skill.theta) == pytest.approx(1.5)
    quiet = with_parameters(PAPER_FIT, direction_noise=0.0, magnitude_noise=0.0, magnitude_spread=0.0)
    people = TeacherPopulation.draw(quiet, [1], 1, len(states))
    drawn = np.vstack([people.act(0, d, offsets[d][None], np.zeros((1, 3)), 1.5, skill.key, True)
                       for d in range(len(states))])
    assert np.allclose(drawn, quiet.magnitude * 1.5 * offsets)


def test_in_space_the_direction_slip_turns_each_arrow_by_its_angle_and_keeps_its_length():
    slippy = with_parameters(PAPER_FIT, direction_noise=0.3, magnitude_noise=0.0, magnitude_spread=0.0)
    people = TeacherPopulation.draw(slippy, [teacher_seed(1, p) for p in range(50)], 1, 1)
    intended = np.random.default_rng(0).normal(size=(50, 3))
    drawn = people.act(0, 0, intended / (slippy.magnitude * 1.0), np.zeros((50, 3)), 1.0, "ur5-reach", True)
    cosine = np.sum(drawn * intended, axis=1) / np.linalg.norm(drawn, axis=1) / np.linalg.norm(intended, axis=1)
    slips = np.abs(0.3 * people.demonstration_noise[:, 0, 0, 0])
    assert np.allclose(np.arccos(np.clip(cosine, -1, 1)), slips, atol=1e-9)
    assert np.allclose(np.linalg.norm(drawn, axis=1), np.linalg.norm(intended, axis=1))
    # The axes are drawn apart per person: the slips are turned about different axes, not one.
    turn = np.cross(intended, drawn)
    assert np.linalg.matrix_rank(turn[:6], tol=1e-6) == 3


def test_unguided_teachers_turn_all_of_an_episodes_arrows_by_one_rotation_in_space():
    exploring = with_parameters(PAPER_FIT, direction_noise=0.0, magnitude_noise=0.0, magnitude_spread=0.0,
                                exploration=0.5)
    people = TeacherPopulation.draw(exploring, [7], 2, 4)
    arrows = np.random.default_rng(1).normal(size=(4, 3))
    drawn = np.vstack([people.act(0, d, arrows[d][None] / exploring.magnitude, np.zeros((1, 3)), 1.0, "ur5-reach",
                                  False) for d in range(4)])
    rotation = np.linalg.lstsq(arrows[:3], drawn[:3], rcond=None)[0].T   # drawn = rotation @ arrow
    assert np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-9) and np.linalg.det(rotation) > 0
    assert np.allclose(drawn[3], rotation @ arrows[3])
    assert not np.allclose(rotation, np.eye(3), atol=1e-3)


def test_the_turn_axes_are_drawn_last_so_a_planar_teacher_is_the_same_person():
    people = TeacherPopulation.draw(PAPER_FIT, [teacher_seed(2, 0)], 3, 5)
    rng = np.random.default_rng(teacher_seed(2, 0))
    assert np.array_equal(people.traits[0], rng.standard_normal(2))
    assert np.array_equal(people.demonstration_noise[0], rng.standard_normal((3, 5, 4)))
    assert np.array_equal(people.episode_noise[0], rng.standard_normal(3))
    assert np.array_equal(people.turn_axes[0], rng.standard_normal((3, 6, 3)))


def test_an_arrow_of_neither_two_nor_three_components_is_refused_with_its_size():
    people = TeacherPopulation.draw(PAPER_FIT, [1], 1, 1)
    with pytest.raises(ValueError, match="offsets: expected arrows of 2 .* got 4"):
        people.act(0, 0, np.ones((1, 4)), np.ones((1, 4)), 1.0, "x", True)


@pytest.mark.slow
def test_in_space_the_session_engine_and_the_batched_engine_give_the_same_study(tmp_path):
    import pandas as pd

    from mt_widgets.in_silico.sessions import run_through_sessions
    from mt_widgets.study.tidy import read_study
    protocol = industrial_protocol("ur5-conveyor", "ur5-place")
    run_through_sessions(tmp_path / "study", 2, protocol=protocol, seed=4)
    episodes, _ = read_study(tmp_path / "study")
    logged = pd.DataFrame(episodes)
    groups = logged.groupby("participant").group.first().tolist()
    batched = run_in_silico(2, protocol, seed=4, groups=groups, reproduce=False).episodes
    key = ["participant", "phase_index", "episode"]
    assert logged.sort_values(key).theta_error.to_numpy() == pytest.approx(
        batched.sort_values(key).theta_error.to_numpy(), abs=1e-9)
