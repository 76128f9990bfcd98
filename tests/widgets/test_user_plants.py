"""Robots draw themselves: a user's plant (tutorial 09's point mass) is taught like the paper's arms.

Nothing in the views asks which robot it draws: the plant's drawing and the target's shape say
it. A plant that only reports its end-effector is drawn as a dot with its velocity.
"""

import re
from pathlib import Path

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.widgets import ArmView, DemoPage, EpisodeWidget, TeachingCanvas
from user_plant import drift, park

from .conftest import path_points, pointer

WIDGETS = Path(__file__).resolve().parents[2] / "mt_widgets" / "widgets"


def test_no_view_asks_which_robot_it_draws():
    for path in sorted(WIDGETS.glob("*.py")):
        text = path.read_text(encoding="utf-8")
        assert not re.search(r"\.robot\b(?!s)", text), f"{path.name} reads a robot's name"
        assert not re.search(r"""["'](sim|uarm)["']\s*(?:[:)\]]|==|!=|if)""", text.replace('"sim-', "")), \
            f"{path.name} branches on a robot's name"
        assert "hasattr(" not in text or "direction" not in text, f"{path.name} duck-types a target"


def test_a_user_plant_is_drawn_as_a_dot_with_its_velocity_and_no_links(recorder):
    view = ArmView(park)
    state = np.array([0.5, -0.4, 0.8, 0.6])
    recorder.clear()
    view.show_state(state)
    commands = recorder.on(view.layer("robot"))
    dots = [args for name, args in commands if name == "fillCircle"]
    assert np.allclose(dots[0][:2], view.transform.to_pixel([0.5, -0.4])), "a dot at the end-effector"
    assert ("set", [0, "#000000"]) in commands or any(a[1] == "#000000" for n, a in commands if n == "set")
    assert not any(name == "strokeLine" for name, _ in commands), "no links, no reach line"
    # The velocity arrow: a shaft from the dot along (0.8, 0.6) m/s times 0.3 s.
    shaft = path_points(commands)
    tip = view.transform.to_pixel(np.array([0.5, -0.4]) + 0.3 * np.array([0.8, 0.6]))
    direction = (tip - shaft[0]) / np.linalg.norm(tip - shaft[0])
    along = (np.array(shaft[1]) - shaft[0]) / np.linalg.norm(np.array(shaft[1]) - shaft[0])
    assert np.allclose(shaft[0], view.transform.to_pixel([0.5, -0.4]), atol=0.1) and along @ direction > 0.999


def test_a_plant_without_a_view_is_framed_around_its_query_states():
    box = drift.workspace
    for seed in range(5):
        positions = drift.end_effector(drift.query_states(seed=seed))[0]
        assert np.all(box.contains(positions))
    assert box.contains(np.array(drift.target.point))
    # The arrow scale makes the skill's typical action a fifth of the view.
    drawing = drift.drawing()
    states = drift.plant.sample_states(np.random.default_rng(0), 256)
    typical = np.median(np.linalg.norm(drift.target_actions(states), axis=-1))
    assert typical * drawing.action_length == pytest.approx(0.2 * (box.xlim[1] - box.xlim[0]))


def test_the_your_own_skill_tutorials_plant_is_taught_with_pointer_drags_in_the_episode_widget(recorder):
    episode = EpisodeWidget(park, seed=2, guidance=True)
    view = episode.teaching.view
    for index in range(len(episode.query_states)):
        ee = view.end_effector_pixel(episode.teaching.current_state)
        tip = view.transform.action_tip(park.end_effector(episode.teaching.current_state)[0], episode.optimal[index])
        pointer(view.canvas, "mouse_down", *ee)
        pointer(view.canvas, "mouse_move", *((ee + tip) / 2))
        pointer(view.canvas, "mouse_up", *tip)
        np.testing.assert_allclose(episode.teaching.pending_action, episode.optimal[index], atol=1e-9)
        episode.teaching.confirm()
        assert episode.phase == "guidance"
        episode.next()
    assert episode.phase == "finished"
    # Drawn to the pixel, the optimal arrows teach the skill to well within a pixel's worth.
    one_pixel = 1.0 / view.transform.pixels_per_action
    assert episode.result.theta_error < 1e-6 + 10 * one_pixel
    assert episode.result.trajectory.positions.shape[-1] == 2
    frames = episode.player.view.painter.frame_points(episode.player.view.transform,
                                                      episode.result.trajectory.states[:3])
    assert frames.shape == (3, 1, 2), "one point a frame: the puck itself"


def test_the_demo_page_takes_the_callers_skills():
    page = DemoPage(skills=[("Puck: park it", park), ("Arm: reach a point", "sim-point")], duration=1.0)
    assert page.episode.skill is park
    assert [label for label, _ in page.skill_chooser.options] == ["Puck: park it", "Arm: reach a point"]
    for action in page.episode.optimal:
        page.episode.demonstrate(action)
        page.episode.next()
    assert page.errors and page.errors[-1][0] == "puck-park" and page.errors[-1][2] < 1e-9
    page.skill_chooser.value = "sim-point"
    assert page.episode.skill is SKILLS["sim-point"]
    with pytest.raises(KeyError, match="known skills"):
        DemoPage(skills=[("Nope", "sim-circle")])
    with pytest.raises(ValueError, match="skills: expected distinct"):
        DemoPage(skills=[("A", park), ("B", park)])


def test_every_reproduction_frame_draws_the_elbow_and_the_base_stays_on_the_background_issue_10_bug_6(recorder):
    from mt_widgets.widgets import ReproductionPlayer

    skill = SKILLS["sim-point"]
    player = ReproductionPlayer(skill)
    view = player.view
    base = view.transform.to_pixel([0.0, 0.0])
    rects = [a for n, a in recorder.on(view.layer("background")) if n == "fillRect"]
    assert any(np.allclose(a[:2], base + [-12, -4]) for a in rects), "the base block is on the background"
    trajectory = skill.reproduce(skill.theta * 0.5, duration=1.0)
    recorder.clear()
    player.play(trajectory)
    commands = recorder.on(view.layer("robot"))
    frames, frame = [], []
    for name, args in commands:
        if name in ("sleep", "clear") and frame:
            frames.append(frame)
            frame = []
        elif name not in ("sleep", "clear"):
            frame.append((name, args))
    frames.append(frame)
    assert len(frames) >= 60
    for index, frame in enumerate(frames[:-1]):
        links = [a for n, a in frame if n == "strokeLine"]
        pins = [a for n, a in frame if n == "clearRect"]
        assert len(links) == 2 and len(pins) == 1, f"frame {index}: two links and the elbow's pin"
        elbow = np.array(links[0][2:4])
        assert np.allclose(links[0][:2], np.rint(base)) and np.allclose(links[1][:2], elbow)
        assert np.allclose(np.array(pins[0][:2]) + 3, elbow), "the pin sits on the elbow"


@pytest.mark.parametrize("key", ["ur5-reach", "ur5-conveyor"])
def test_a_plant_in_space_is_refused_by_the_planar_views_with_a_reason(key):
    # The UR5 says SpaceDrawing (three views); the planar views draw one plane and say so.
    with pytest.raises(TypeError, match=rf"skill: expected a skill whose plant is drawn in the plane .*'{key}', "
                                        r"drawn in space \(SpaceDrawing\)"):
        ArmView(SKILLS[key])
    with pytest.raises(TypeError, match="drawn in space"):
        TeachingCanvas(SKILLS[key])
    # The one episode widget draws it with the 3-D renderer instead: the plant's drawing chooses.
    assert type(EpisodeWidget(key, seed=0).teaching).__name__ == "SpaceTeachingCanvas"
