"""Words match the picture (issue 10 bug 5) and a legend explains every mark on the canvas."""

import re

import numpy as np
import pytest

from blinding_support import participant_texts
from mt_widgets import SKILLS
from mt_widgets.apps import StudyApp
from mt_widgets.widgets import THEMES, ArmView, EpisodeWidget, ReproductionPlayer, Theme
from mt_widgets.widgets.guidance import explain_difference
from mt_widgets.widgets.theme import fill_words
from protocols import phase as phase_table
from protocols import protocol_toml


def lab(hex_color: str) -> np.ndarray:
    """CIELAB of an sRGB colour (D65): distances there follow how different colours look."""
    rgb = np.array([int(hex_color[i:i + 2], 16) for i in (1, 3, 5)]) / 255.0
    linear = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]]) @ linear
    xyz /= np.array([0.95047, 1.0, 1.08883])
    f = np.where(xyz > 0.008856, np.cbrt(xyz), 7.787 * xyz + 16 / 116)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def test_the_velocity_arrow_is_clearly_another_colour_than_the_users_arrow():
    for theme in THEMES.values():
        difference = np.linalg.norm(lab(theme.velocity_arrow.color) - lab(theme.user_arrow.color))
        assert difference > 40, (theme.name, difference)     # sky-blue vs blue was about 27
        assert theme.velocity_arrow.width < theme.user_arrow.width
        assert theme.color_name("velocity_arrow") != theme.color_name("user_arrow")


@pytest.mark.parametrize("theme, words", [("okabe-ito", "the red-orange point marked goal"),
                                          ("paper", "the red point marked goal")])
def test_target_words_name_the_colour_the_canvas_draws_the_target_in(recorder, theme, words):
    skill = SKILLS["sim-point"]
    view = ArmView(skill, theme=theme)
    assert view.theme.target_words(skill.target) == words
    # The colour named is the one the target dot is filled with on the canvas.
    commands = view.layer("background")
    fills, current = {}, None
    for name, args in recorder.on(commands):
        if name == "set" and isinstance(args[1], str) and args[1].startswith("#"):
            current = args[1]
        if name == "fillCircle" and np.allclose(args[:2], view.transform.to_pixel(skill.target.point)):
            fills["target"] = current
    assert view.theme.color_name("target") == words.split()[1]
    assert fills["target"].upper() == view.theme.target.upper()
    line = SKILLS["sim-line"]
    assert THEMES[theme].target_words(line.target) == words.replace("point", "vertical line")


def test_a_theme_names_its_own_colours_and_a_nameless_colour_is_left_out():
    theme = Theme(name="mine", target="#123456", color_names=(("#123456", "navy"),))
    assert theme.target_words(SKILLS["sim-point"].target) == "the navy point marked goal"
    nameless = Theme(name="nameless", target="#123457")
    assert nameless.target_words(SKILLS["sim-point"].target, label=None) == "the point"
    with pytest.raises(ValueError, match="role: expected a colour of the theme"):
        theme.color_name("ghost_alpha")
    assert fill_words("Go to {goal}. {other} stays.", goal="the red point") == "Go to the red point. {other} stays."


def test_guidance_never_says_within_0_degrees():
    assert "less than 1&deg; off" in explain_difference([1.0, 0.004], [1.0, 0.0], "N")
    assert "3&deg; off" in explain_difference([1.0, np.tan(np.radians(3))], [1.0, 0.0], "N")
    for angle in np.linspace(-4.9, 4.9, 41):
        text = explain_difference([np.cos(np.radians(angle)), np.sin(np.radians(angle))], [1.0, 0.0], "N")
        assert "within" not in text and "Direction: good" in text


WORDS_PROTOCOL = protocol_toml(
    "words",
    [phase_table("P1", "sim-point", instructions="Skill 1: bring the tip of the arm to {goal} and stop there."),
     phase_table("P2", "sim-line", instructions="Skill 2: bring the tip of the arm onto {goal} and stop there.")],
    seed=3, texts={"instructions": "The goal of the robot is {goal}."})


def test_the_paper_protocols_name_the_goal_through_the_theme_not_a_colour():
    from mt_widgets.study import load_protocol

    for name in ("paper-sim", "paper-uarm"):
        protocol = load_protocol(name)
        for phase in protocol.phases:
            assert "{goal}" in phase.instructions and not re.search(r"\bred\b", phase.instructions), phase.id


def primary_button(app):
    from ipywidgets import Button

    found, pending = [], list(app.body.children)
    while pending:
        widget = pending.pop()
        if isinstance(widget, Button) and widget.button_style == "primary":
            found.append(widget)
        pending += list(getattr(widget, "children", ()))
    return found[0]


@pytest.mark.parametrize("theme, colour", [(None, "red-orange"), ("paper", "red")])
def test_the_study_pages_words_name_the_goal_as_drawn_in_the_theme_in_use(tmp_path, theme, colour):
    path = tmp_path / "words.toml"
    path.write_text(WORDS_PROTOCOL, encoding="utf-8")
    app = StudyApp(protocol=str(path), log_folder=tmp_path / "logs", theme=theme)
    app.start_lesson("control")
    seen = []
    for _ in range(100):
        step = app.session.current_step()
        seen.append(" ".join(participant_texts(app.participant_view)))
        if step.kind == "phase_intro" and step.phase == "P2":
            break
        if step.kind in ("demonstration", "episode_end"):
            if app.episode.phase == "guidance":
                app.episode.next()
            else:
                app.episode.demonstrate(SKILLS[step.skill].target_actions(step.state[None])[0])
        elif step.kind == "reproduction":
            app._continue.disabled = False
            app._continue.click()
        else:
            primary_button(app).click()
    text = " ".join(seen)
    assert f"The goal of the robot is the {colour} point marked goal." in text
    assert f"to the {colour} point marked goal and stop" in text
    assert f"onto the {colour} vertical line marked goal and stop" in text
    assert "{goal}" not in text


def test_the_teaching_legend_lists_every_mark_the_canvas_draws():
    episode = EpisodeWidget("sim-point", seed=0, guidance=True)
    legend = episode.teaching.view.legend
    assert legend.marks == ("target", "base", "links", "robot", "velocity", "user_arrow")
    value = legend.value
    for words in ("goal: the red-orange point to reach", "the robot's fixed base", "the arm (white square",
                  "the robot's hand (the yellow dot)", "its velocity (green arrow)", "your action (solid)"):
        assert words in value, words
    theme = episode.theme
    for colour in (theme.target, theme.end_effector, theme.velocity_arrow.color, theme.user_arrow.color, theme.arm):
        assert colour in value
    assert "optimal" not in value, "no guidance shown yet"
    episode.demonstrate(episode.optimal[0] * 0.5)
    assert "optimal action (dashed)" in legend.value and theme.optimal_arrow.color in legend.value


def test_the_uarm_legend_has_its_outline_and_reach_line_and_no_velocity():
    view = ArmView(SKILLS["uarm-line"])
    assert view.legend.marks == ("target", "base", "links", "outline", "robot")
    value = view.legend.value
    assert "which way the arm reaches" in value and "where the arm can reach" in value
    assert "velocity" not in value, "the uArm is at rest at every state: no velocity arrow, no entry"
    assert "the red-orange line" in value and "the robot's position (the black dot)" in value


def test_the_reproduction_legend_explains_its_paths_and_a_divergence():
    skill = SKILLS["sim-point"]
    player = ReproductionPlayer(skill)
    player.play(skill.reproduce(skill.theta, duration=0.5), ghost=skill.reproduce(skill.theta, duration=0.5))
    assert {"learnt", "ghost"} <= set(player.view.legend.marks) and "diverged" not in player.view.legend.marks
    player.play(skill.reproduce(-5 * skill.theta, duration=5.0))
    assert "diverged" in player.view.legend.marks and "ghost" not in player.view.legend.marks
    assert "left its safe range" in player.view.legend.value


def test_an_optimal_arrow_aligned_with_the_users_is_drawn_beside_it_and_last(recorder):
    from mt_widgets.widgets import TeachingCanvas

    skill = SKILLS["sim-point"]
    teach = TeachingCanvas(skill, skill.query_states(seed=0))
    view, theme = teach.view, teach.theme
    origin = skill.end_effector(teach.current_state[None])[0][0]
    optimal = np.array([1.0, 1.5])
    for user, aligned in ((1.6 * optimal, True), (0.5 * optimal, True), (np.array([1.5, -1.0]), False)):
        teach.set_action(user)
        recorder.clear()
        teach.show_guidance(optimal)
        commands = recorder.on(view.layer("arrows"))
        colours = [a[1] for n, a in commands if n == "set" and a[1] in (theme.user_arrow.color,
                                                                       theme.optimal_arrow.color)]
        assert colours[-1] == theme.optimal_arrow.color, "the optimal arrow is drawn last"
        last = max(k for k, (n, a) in enumerate(commands) if n == "set" and a[1] == theme.optimal_arrow.color)
        optimal_points = np.array([a[:2] for n, a in commands[last:] if n in ("moveTo", "lineTo")], dtype=float)
        start = view.transform.to_pixel(origin)
        tip = view.transform.action_tip(origin, optimal)
        along = (tip - start) / np.hypot(*(tip - start))
        sideways = (optimal_points - start) @ np.array([along[1], -along[0]])
        if aligned:
            # The optimal shaft moved sideways (perpendicular to the arrows) by more than the
            # shafts' half-widths, so the two do not overlap; its start still on the hand marker.
            shaft = sideways[0]
            assert (theme.user_arrow.width + theme.optimal_arrow.width) / 2 < shaft < 8
        else:
            assert abs(sideways[0]) < 0.1, "not aligned: both start at the hand"


def test_the_readout_and_the_reproduction_name_marks_in_the_theme_colours():
    arm = EpisodeWidget("sim-point", seed=0, guidance=False, duration=0.5)
    assert "press on the robot's hand (the yellow dot)" in arm.teaching.readout.value
    uarm = EpisodeWidget("uarm-point", seed=0, guidance=False, theme="paper-uarm")
    assert "press on the robot's hand (the black dot)" in uarm.teaching.readout.value
    for action in arm.optimal:
        arm.demonstrate(action)
    status = arm.player.status.value
    assert "from the red-orange point marked goal" in status
    assert "path is the sky-blue line" in status and "faint dashed pink line is the skill's own motion" in status
    paper = ReproductionPlayer(SKILLS["sim-line"], theme="paper")
    paper.play(SKILLS["sim-line"].reproduce(SKILLS["sim-line"].theta, duration=0.5))
    assert "from the red vertical line marked goal" in paper.status.value
    diverging = ReproductionPlayer(SKILLS["sim-point"])
    diverging.play(SKILLS["sim-point"].reproduce(-5 * SKILLS["sim-point"].theta, duration=5.0))
    assert "(red-orange cross)" in diverging.status.value
