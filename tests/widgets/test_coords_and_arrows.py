import numpy as np
import pytest

from mt_widgets.widgets import ViewTransform, draw_arrow
from mt_widgets.widgets.coords import nice_ticks
from mt_widgets.widgets.theme import DEFAULT_THEME, PAPER_THEME, get_theme

from .conftest import path_points


def test_world_to_pixel_and_back_is_the_identity_with_y_up():
    t = ViewTransform((-2.2, 2.2), (-2.2, 2.2), 480, 480, margin=34, action_length=0.35)
    world = np.array([[0.0, 0.0], [0.8, 1.2], [-2.2, -2.2], [2.2, 2.2]])
    pixels = t.to_pixel(world)
    assert np.allclose(pixels[0], [240, 240])
    assert pixels[1, 1] < pixels[0, 1], "world y up is pixel y down"
    assert np.allclose(pixels[2], [34, 446]) and np.allclose(pixels[3], [446, 34])
    assert np.allclose(t.to_world(pixels), world)


def test_non_square_world_keeps_equal_scale_and_centres_the_slack():
    t = ViewTransform((0.0, 32.0), (-28.0, 28.0), 300, 480, margin=10)
    a, b = t.to_pixel([[0.0, 0.0], [1.0, 1.0]])
    assert np.isclose(b[0] - a[0], a[1] - b[1])
    left, right = t.to_pixel([[0.0, 0.0], [32.0, 0.0]])[:, 0]
    assert np.isclose(left, t.width - right)


def test_a_drag_gives_back_the_action_whose_arrow_ends_there():
    t = ViewTransform((-2.2, 2.2), (-2.2, 2.2), 480, 480, action_length=0.35)
    origin, action = np.array([0.5, -0.3]), np.array([1.7, -2.4])
    tip = t.action_tip(origin, action)
    assert np.allclose(t.action_from_drag(origin, tip), action)
    assert np.isclose(np.hypot(*(tip - t.to_pixel(origin))), np.hypot(*action) * t.pixels_per_action)


@pytest.mark.parametrize("kwargs, word", [(dict(xlim=(1, 1)), "xlim"), (dict(width=20), "width"),
                                          (dict(action_length=0), "action_length")])
def test_bad_transforms_name_their_argument(kwargs, word):
    args = dict(xlim=(-1, 1), ylim=(-1, 1), width=200, height=200) | kwargs
    with pytest.raises(ValueError, match=word):
        ViewTransform(**args)


def test_ticks_are_round_and_cover_the_range():
    ticks = nice_ticks(-2.2, 2.2)
    assert list(ticks) == pytest.approx([-2, -1.5, -1, -0.5, 0, 0.5, 1, 1.5, 2]) or list(ticks) == pytest.approx(
        [-2, -1, 0, 1, 2])
    assert len(nice_ticks(0, 32)) <= 9


def test_arrow_draws_shaft_from_start_and_head_at_tip(recorder):
    from ipycanvas import Canvas
    canvas = Canvas(width=100, height=100)
    recorder.clear()
    assert draw_arrow(canvas, (10, 20), (80, 20), DEFAULT_THEME.optimal_arrow)
    commands = recorder.on(canvas)
    points = path_points(commands)
    assert points[0] == (10.0, 20.0) and (80.0, 20.0) in points
    dashes = [args for name, args in commands if name == "setLineDash"]
    assert dashes[0] == [list(DEFAULT_THEME.optimal_arrow.dash)], "the optimal arrow's shaft is dashed"
    assert dashes[1] == [[]], "and the dash is reset before the head"



def test_a_zero_arrow_is_a_dot():
    from ipycanvas import Canvas
    assert not draw_arrow(Canvas(width=10, height=10), (5, 5), (5.5, 5), DEFAULT_THEME.user_arrow)


def test_default_theme_tells_arrows_apart_by_line_style_and_paper_theme_uses_greens():
    assert DEFAULT_THEME.user_arrow.dash == () and DEFAULT_THEME.optimal_arrow.dash != ()
    assert DEFAULT_THEME.user_arrow.color != DEFAULT_THEME.optimal_arrow.color
    assert get_theme("paper") is PAPER_THEME and PAPER_THEME.user_arrow.color == "#006400"
    with pytest.raises(ValueError, match="theme"):
        get_theme("rainbow")
