"""Kernel-free: a finger draws as the mouse does, Enter goes on after guidance, the canvas in words.

The front end's part (which touches reach the kernel, Tab leaving the canvas, the accessibility
tree) is tested in Chromium in tests/browser/test_touch_and_keyboard.py; here the kernel's.
"""

import re

import numpy as np
import pytest

from mt_widgets.widgets import EpisodeWidget
from mt_widgets.widgets.canvas_access import CANVAS_CLASS_PREFIX
from mt_widgets.widgets.teaching import TOUCH_RADIUS_FACTOR, arrow_in_words


def touch(canvas, event, points):
    canvas._canvases[-1]._handle_frontend_event(
        canvas._canvases[-1], {"event": event, "touches": [{"x": x, "y": y} for x, y in points]}, [])


@pytest.fixture
def episode():
    return EpisodeWidget("sim-point", guidance=True)


def test_a_finger_from_the_hand_draws_the_arrow_it_ends_on(episode, recorder):
    teaching = episode.teaching
    canvas, transform = teaching.view.canvas, teaching.view.transform
    ee = teaching.view.end_effector_pixel(episode.query_states[0])
    origin = episode.skill.end_effector(episode.query_states[:1])[0][0]
    # A finger lands 40 px off the hand: beyond the mouse's 28 px, within a finger's reach.
    touch(canvas, "touch_start", [ee + (40.0, 0.0)])
    touch(canvas, "touch_move", [ee + (30.0, -50.0)])
    touch(canvas, "touch_move", [ee + (60.0, -70.0)])
    touch(canvas, "touch_end", [])
    expected = transform.action_from_drag(origin, ee + (60.0, -70.0))
    np.testing.assert_allclose(teaching.pending_action, expected)
    assert "your arrow" in teaching.readout.value
    # The same press with the mouse is too far from the hand: it only says where to press.
    teaching.clear_action()
    teaching._on_mouse_down(*(ee + (40.0, 0.0)))
    assert teaching.pending_action is None and "Press on the robot's hand" in teaching.hint.value


def test_a_finger_away_from_the_hand_or_a_second_finger_draws_nothing_more(episode, recorder):
    teaching = episode.teaching
    canvas = teaching.view.canvas
    ee = teaching.view.end_effector_pixel(episode.query_states[0])
    touch(canvas, "touch_start", [ee + (TOUCH_RADIUS_FACTOR * teaching.grab_radius + 5, 0.0)])
    touch(canvas, "touch_move", [ee + (80.0, 80.0)])
    touch(canvas, "touch_end", [])
    assert teaching.pending_action is None
    # A drag, then a second finger (a pinch): the arrow stays where the first finger had drawn it.
    touch(canvas, "touch_start", [ee])
    touch(canvas, "touch_move", [ee + (50.0, 0.0)])
    drawn = list(teaching.pending_action)
    touch(canvas, "touch_start", [ee + (50.0, 0.0), ee + (150.0, 150.0)])
    touch(canvas, "touch_move", [ee + (90.0, 90.0), ee + (200.0, 200.0)])
    touch(canvas, "touch_end", [ee + (90.0, 90.0)])
    touch(canvas, "touch_end", [])
    assert teaching.pending_action == drawn


def test_grab_zones_follow_the_hand_and_the_tip_and_vanish_when_locked(episode, recorder):
    teaching = episode.teaching
    ee = teaching.view.end_effector_pixel(episode.query_states[0])
    (zone,) = teaching.description.grab_zones
    np.testing.assert_allclose(zone, (*ee, teaching.grab_radius, TOUCH_RADIUS_FACTOR * teaching.grab_radius),
                               atol=0.05)
    teaching.set_action([1.0, 0.5])
    assert len(teaching.description.grab_zones) == 2            # the tip can be dragged too
    teaching.confirm()                                          # guidance: locked
    assert teaching.description.grab_zones == []
    # The canvas element is linked to its description by a class, which its front end is given.
    assert CANVAS_CLASS_PREFIX + teaching.description.token in teaching.view.canvas._dom_classes
    assert teaching.description.canvas_class == CANVAS_CLASS_PREFIX + teaching.description.token


def test_enter_on_the_canvas_confirms_then_goes_on_like_next_state(episode, recorder):
    teaching = episode.teaching
    teaching._on_key_down("ArrowUp", False, False, False)
    teaching._on_key_down("Enter", False, False, False)
    assert episode.phase == "guidance" and episode.state_index == 0
    teaching._on_key_down("Enter", False, False, False)
    assert episode.phase == "teaching" and episode.state_index == 1
    for _ in range(4):
        teaching._on_key_down("ArrowRight", False, False, False)
        teaching._on_key_down("Enter", False, False, False)
        teaching._on_key_down("Enter", False, False, False)
    assert episode.phase == "finished"
    teaching._on_key_down("Enter", False, False, False)        # nothing left: no error
    assert episode.phase == "finished"


def test_the_description_says_the_state_velocity_arrow_and_guidance(episode, recorder):
    teaching = episode.teaching
    state = episode.query_states[0]
    position, velocity = teaching.view.painter.end_effector(state)
    text = teaching.description.text
    assert text.startswith("Teaching canvas, state 1 of 5")
    assert f"({position[0]:.2f}, {position[1]:.2f}) m" in text
    assert f"({velocity[0]:+.2f}, {velocity[1]:+.2f}) m/s" in text
    episode.demonstrate([1.0, -0.5])
    text = teaching.description.text
    assert "Your arrow: 1.00 N right and 0.50 N down" in text
    best = episode.optimal[0]
    assert f"The best arrow: {arrow_in_words(best, 'N')}" in text and f"{abs(best[0]):.2f} N" in text
    assert "Direction" in text and "Enter goes on" in text
    assert not re.search(r"&\w+;|<", text)                      # words, not markup
    episode.next()
    text = teaching.description.text
    assert text.startswith("Teaching canvas, state 2 of 5") and "best" not in text


def test_without_guidance_words_the_description_names_the_arrows_only(recorder):
    episode = EpisodeWidget("sim-point", guidance=True, guidance_modality="arrows")
    episode.demonstrate([1.0, -0.5])
    text = episode.teaching.description.text
    assert "The best arrow" in text and "Direction" not in text
