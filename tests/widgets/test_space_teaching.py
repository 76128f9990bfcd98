"""Kernel-free: a 3-D demonstration drawn in the top and side views, by mouse, finger, keys and numbers.

The front end's part (events from Chromium, touch, screenshots) is tests/browser/test_space_teaching.py.
"""

import numpy as np
import pytest

from mt_widgets.core import SKILLS, TeachingEpisode
from mt_widgets.widgets.space_teaching import COMPONENTS, HAND_RADIUS_PX, SpaceTeachingCanvas, check_space_action

from .conftest import key, pointer


def touch(multicanvas, event, points):
    multicanvas[-1]._handle_frontend_event(
        None, {"event": event, "touches": [{"x": x, "y": y} for x, y in points]}, [])


@pytest.fixture(scope="module")
def skill():
    return SKILLS["ur5-reach"]


@pytest.fixture
def widget(skill, recorder):
    return SpaceTeachingCanvas(TeachingEpisode(skill, seed=0), play=False)


def drag_action(widget, top_delta, side_delta, event_kind="mouse"):
    """Drags from the tool by ``top_delta`` px in the top view, then by ``side_delta`` px in the side view."""
    for view, delta in (("top", top_delta), ("side", side_delta)):
        start = widget.tool_pixel(view)
        end = start + np.asarray(delta, dtype=float)
        if event_kind == "mouse":
            pointer(widget.canvas, "mouse_down", *start)
            pointer(widget.canvas, "mouse_move", *(start + np.asarray(delta) / 2))
            pointer(widget.canvas, "mouse_up", *end)
        else:
            touch(widget.canvas, "touch_start", [start])
            touch(widget.canvas, "touch_move", [start + np.asarray(delta) / 2])
            touch(widget.canvas, "touch_move", [end])
            touch(widget.canvas, "touch_end", [])


@pytest.mark.parametrize("event_kind", ["mouse", "touch"])
def test_a_drag_in_top_then_side_view_gives_the_3d_action_the_episode_records(widget, event_kind):
    scale_top, scale_side = widget.panel("top").scale, widget.panel("side").scale
    drag_action(widget, (40.0, -20.0), (-10.0, -30.0), event_kind)
    length = widget.action_length
    # Top: right is +x, up is +y; side: right is +x (shared: the side drag moves it on by its own
    # sideways travel), up is +z.
    expected = np.array([(40.0 / scale_top - 10.0 / scale_side) / length, 20.0 / scale_top / length,
                         30.0 / scale_side / length])
    np.testing.assert_allclose(widget.pending_action, expected, rtol=1e-9)
    key(widget.canvas, "Enter")
    demonstration = widget.episode.demonstrations[0]
    np.testing.assert_allclose(demonstration.action, expected)
    assert demonstration.method == "pointer" and demonstration.guidance_shown
    assert demonstration.redraws == 2
    # Guidance: the words give both arrows, and the canvas drew a dashed (optimal) arrow in each panel.
    assert "optimal arrow (dashed)" in widget.describe()
    assert widget.showing_guidance and widget.next_button.layout.display is None


def test_guidance_draws_the_user_and_the_dashed_optimal_arrow_in_all_three_views(widget, recorder):
    recorder.clear()
    widget.set_action([0.1, 0.0, 0.0])
    # Before the confirmation only the user's (solid) arrow is drawn.
    assert not [args for name, args in recorder.on(widget.plant_layer) if name == "setLineDash" and args[0]]
    recorder.clear()
    widget.confirm()
    commands = recorder.on(widget.plant_layer)
    dashed = [args for name, args in commands if name == "setLineDash" and args[0]]
    # The same dashed arrow (its white outline, then its shaft) in each of the three views.
    assert len(dashed) == 6 and all(d == [list(widget.theme.optimal_arrow.dash)] for d in dashed), dashed
    # Each view's optimal arrow starts at the tool and points where the optimal action says.
    optimal = widget.episode.optimal_actions[0]
    for name in ("top", "side", "perspective"):
        tip = widget.panel(name).pixels(widget._tool() + widget.action_length * optimal)
        assert np.all(np.isfinite(tip))
    key(widget.canvas, "Enter")
    assert not widget.showing_guidance and widget.episode.next_index == 1


def test_keyboard_nudges_the_active_component_and_space_moves_on(widget):
    key(widget.canvas, "ArrowUp")
    first = widget.pending_action.copy()
    assert first[0] > 0 and first[1] == 0 and first[2] == 0
    key(widget.canvas, " ")
    assert widget.active_component == "y"
    key(widget.canvas, "ArrowDown")
    key(widget.canvas, "z")
    key(widget.canvas, "ArrowUp", shift=True)
    action = widget.pending_action
    assert action[1] == -first[0] and 0 < action[2] < first[0]
    key(widget.canvas, "Enter")
    assert widget.episode.demonstrations[0].method == "keyboard"
    np.testing.assert_allclose(widget.episode.demonstrations[0].action, action)


def test_typed_numbers_set_the_arrow_and_bad_numbers_are_refused(widget):
    for entry, value in zip(widget.entries, (0.1, -0.2, 0.05)):
        entry.value = value
    widget.set_button.click()
    np.testing.assert_allclose(widget.pending_action, [0.1, -0.2, 0.05])
    widget.entries[1].value = float("nan")
    widget.set_button.click()
    assert "three finite numbers" in widget.hint.value
    np.testing.assert_allclose(widget.pending_action, [0.1, -0.2, 0.05])  # unchanged
    widget.confirm_button.click()
    assert widget.episode.demonstrations[0].method == "numeric"
    widget.next_button.click()
    assert [entry.value for entry in widget.entries] == [0.0, 0.0, 0.0]  # the next state starts empty


@pytest.mark.parametrize("bad", [[0.1, 0.2], [0.1, float("inf"), 0.0], [True, 0.0, 0.0], "abc", [1, 2, 3, 4]])
def test_an_action_that_is_not_three_finite_numbers_is_refused_naming_it(widget, bad):
    with pytest.raises(ValueError, match=r"action: expected 3 finite numbers \(x, y, z\), got"):
        widget.set_action(bad)
    assert widget.pending_action is None


def test_bad_skill_and_options_are_refused_naming_the_argument():
    with pytest.raises(TypeError, match="expected a plant drawn in space"):
        SpaceTeachingCanvas("sim-point")
    with pytest.raises(ValueError, match="skill: expected one of"):
        SpaceTeachingCanvas("ur5-nowhere")
    with pytest.raises(TypeError, match="guidance"):
        SpaceTeachingCanvas("ur5-reach", seed=0, guidance="yes")
    with pytest.raises(TypeError, match="action: expected 3 finite numbers"):
        check_space_action(3.0)


def test_dragging_in_the_perspective_view_orbits_it_and_keys_do_too(widget):
    azimuth, elevation = widget.azimuth_deg, widget.elevation_deg
    panel = widget.panel("perspective")
    before = widget.tool_pixel("perspective")
    centre = (panel.left + panel.size / 2, panel.top + panel.size / 2)
    pointer(widget.canvas, "mouse_down", *centre)
    pointer(widget.canvas, "mouse_up", centre[0] + 40, centre[1] - 20)
    assert widget.azimuth_deg == pytest.approx((azimuth - 20.0) % 360)
    assert widget.elevation_deg == pytest.approx(elevation - 10.0)
    assert not np.allclose(widget.tool_pixel("perspective"), before)
    assert widget.pending_action is None  # an orbit draws no arrow
    key(widget.canvas, "d")
    assert widget.azimuth_deg == pytest.approx((azimuth - 10.0) % 360)
    for _ in range(20):
        key(widget.canvas, "w")
    assert widget.elevation_deg == 89.0  # never over the top


def test_a_press_away_from_the_hand_draws_nothing_and_says_where_to_press(widget):
    start = widget.tool_pixel("top")
    pointer(widget.canvas, "mouse_down", start[0] + 80, start[1] + 80)
    pointer(widget.canvas, "mouse_up", start[0] + 100, start[1] + 100)
    assert widget.pending_action is None
    assert "Press on the robot's hand" in widget.hint.value


def test_the_text_alternative_names_the_views_the_hand_the_goal_and_the_arrow(widget):
    words = widget.describe()
    tool = widget._tool()
    assert "from the top, from the side and in 3-D" in words
    assert f"height {tool[2]:.2f} m" in words and "red-orange point marked goal" in words
    assert widget.description.text == words
    # Grab zones: the hand in the top and side views (where a finger starts a drag), and the 3-D panel.
    zones = np.array(widget.description.grab_zones)
    np.testing.assert_allclose(zones[0, :2], widget.tool_pixel("top"), atol=0.05)
    np.testing.assert_allclose(zones[1, :2], widget.tool_pixel("side"), atol=0.05)
    widget.set_action([0.1, 0.0, -0.2])
    assert "Your arrow: x +0.100, y +0.000, height -0.200 m/s" in widget.description.text


def test_a_whole_episode_ends_in_the_reproduction_played_in_one_batch_with_sleeps(skill, recorder):
    widget = SpaceTeachingCanvas(TeachingEpisode(skill, seed=0), guidance=False)
    for action in widget.episode.optimal_actions:
        widget.set_action(action)
        widget.confirm()
    assert widget.episode.complete and widget.animation is not None and widget.animation.done
    commands = recorder.on(widget.plant_layer)
    sleeps = [args for name, args in commands if name == "sleep"]
    assert len(sleeps) == widget.animation.n_frames - 1
    assert sleeps[0][0] == pytest.approx(1000.0 / 60, abs=0.01)  # sent at 60 fps
    assert "replays what it learnt" in widget.describe()
    # Every frame draws the chain in each of the three views with one command, and the three hands with another.
    arms = [args for name, args in commands if name == "strokeLineSegments"]
    hands = [args for name, args in commands if name == "fillCircles"]
    # Each frame once, then the final picture: the tool's path and the last frame again.
    assert len(arms) == widget.animation.n_frames + 2 and len(hands) == widget.animation.n_frames + 1
    assert all(args[0] == 3 for args in arms)   # three polylines: one per view
    assert len(COMPONENTS) == 3


def _dashed_shafts(commands) -> list[tuple[np.ndarray, np.ndarray]]:
    """(start, end) pixels of each dashed shaft drawn (the optimal arrow's outline, then its shaft)."""
    shafts, dashed = [], False
    for index, (name, args) in enumerate(commands):
        if name == "setLineDash":
            dashed = bool(args[0])
        elif name == "moveTo" and dashed and commands[index + 1][0] == "lineTo":
            shafts.append((np.array(args[:2], dtype=float), np.array(commands[index + 1][1][:2], dtype=float)))
    return shafts


def test_a_short_optimal_arrow_shows_beyond_the_hand_and_its_true_size_is_stated(widget, recorder):
    # The UR5's first query state (seed 0): the optimal action is 0.06 long, 3-5 px in the three views,
    # which drawn to scale sat under the hand's 6 px dot. It is drawn at a visible length instead.
    optimal = widget.episode.optimal_actions[0]
    tool = widget._tool()
    to_scale = [np.hypot(*(widget.panel(n).pixels(tool + widget.action_length * optimal) - widget.tool_pixel(n)))
                for n in ("top", "side", "perspective")]
    assert max(to_scale) < HAND_RADIUS_PX
    widget.set_action([0.0, 0.0, -0.3])   # the user's arrow points away: the optimal one is not moved aside
    recorder.clear()
    widget.confirm()
    shafts = _dashed_shafts(recorder.on(widget.plant_layer))
    assert len(shafts) == 6, shafts   # outline and shaft in each of the three views
    for (start, end), name in zip(shafts, ("top", "top", "side", "side", "perspective", "perspective")):
        np.testing.assert_allclose(start, widget.tool_pixel(name), atol=0.06)
        # The shaft alone reaches past the dot; the head is beyond it.
        assert np.hypot(*(end - start)) > HAND_RADIUS_PX + 2, (name, start, end)
        # In the optimal action's direction, as projected in that view.
        direction = widget.panel(name).pixels(tool + widget.action_length * optimal) - widget.tool_pixel(name)
        cosine = np.dot(end - start, direction) / np.hypot(*(end - start)) / np.hypot(*direction)
        assert cosine > 0.99, (name, cosine)
    size = float(np.linalg.norm(optimal))
    words = widget.describe()
    assert f"drawn longer than to scale so that it shows; its size is {size:.3f}" in words, words
    texts = " ".join(args[0] for name, args in recorder.on(widget.plant_layer) if name == "fillText")
    assert "drawn longer so that it shows: its size is " + f"{size:.3f}" in texts, texts


def test_a_long_optimal_arrow_is_drawn_to_scale(skill, recorder):
    widget = SpaceTeachingCanvas(TeachingEpisode(skill, seed=0), play=False)
    widget.set_action([0.0, 0.0, 0.3])
    widget.confirm()
    widget.advance()   # state 2: the optimal arrow is 24-38 px long in every view
    widget.set_action([0.0, 0.0, 0.3])
    recorder.clear()
    widget.confirm()
    optimal, tool = widget.episode.optimal_actions[1], widget._tool()
    shafts = _dashed_shafts(recorder.on(widget.plant_layer))
    head = widget.theme.optimal_arrow.head
    for (start, end), name in zip(shafts[1::2], ("top", "side", "perspective")):
        tip = widget.panel(name).pixels(tool + widget.action_length * optimal)
        assert np.hypot(*(tip - start)) > 20
        # The shaft stops 0.9 of a head short of the true tip.
        assert abs(np.hypot(*(tip - start)) - np.hypot(*(end - start)) - 0.9 * head) < 0.2, name
    assert "longer than to scale" not in widget.describe()


def test_a_drag_in_the_side_view_keeps_the_x_the_top_view_set(widget):
    # A drag from the hand straight up in the side view sets the height only: x stays what the top
    # view's drag set (it used to be reset to where the pointer was pressed, 0).
    scale_top, scale_side, length = widget.panel("top").scale, widget.panel("side").scale, widget.action_length
    drag_action(widget, (40.0, -20.0), (0.0, -30.0))
    np.testing.assert_allclose(widget.pending_action,
                               [40.0 / scale_top / length, 20.0 / scale_top / length, 30.0 / scale_side / length],
                               rtol=1e-9)
    # Pressing on the arrow's tip in the side view and moving it right moves x by as much.
    tip = widget.panel("side").pixels(widget._tool() + length * widget.pending_action)
    pointer(widget.canvas, "mouse_down", *tip)
    pointer(widget.canvas, "mouse_up", *(tip + [12.0, 0.0]))
    np.testing.assert_allclose(widget.pending_action[0], (40.0 / scale_top + 12.0 / scale_side) / length, rtol=1e-9)
