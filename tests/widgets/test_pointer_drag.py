"""The one drag mechanism both teaching canvases use (mt_widgets/widgets/pointer_drag.py): mouse, finger and keys."""

from mt_widgets.widgets.pointer_drag import PointerDrag, confirm_or_clear


def recorder(grab=10.0):
    events, accepting = [], [True]
    drag = PointerDrag(lambda x, y, radius: events.append(("press", x, y, radius)) or abs(x) <= grab,
                       lambda pointer: events.append(("move", *pointer)),
                       lambda pointer: events.append(("release", *pointer)), lambda: accepting[0])
    return drag, events, accepting


def test_a_press_off_the_grab_zone_starts_no_drag_and_later_moves_draw_nothing():
    drag, events, _ = recorder()
    drag.mouse_down(50, 0, 8.0)
    drag.mouse_move(5, 5)
    drag.mouse_up(5, 5)
    assert events == [("press", 50, 0, 8.0)] and not drag.active


def test_a_finger_draws_with_its_own_radius_and_ends_where_it_last_moved():
    drag, events, _ = recorder()
    drag.touch_start([(1, 1)], 40.0)
    drag.touch_move([(3, 4)])
    drag.touch_end([])
    assert events == [("press", 1, 1, 40.0), ("move", 3, 4), ("release", 3, 4)] and not drag.active


def test_a_second_finger_ends_the_drag_where_the_first_had_drawn_it():
    drag, events, _ = recorder()
    drag.touch_start([(1, 1)], 40.0)
    drag.touch_move([(2, 2)])
    drag.touch_start([(2, 2), (9, 9)], 40.0)
    drag.touch_move([(7, 7)])
    assert events[-1] == ("release", 2, 2) and not drag.active


def test_a_canvas_that_stops_accepting_mid_drag_ends_it_without_a_release():
    drag, events, accepting = recorder()
    drag.mouse_down(0, 0, 8.0)
    accepting[0] = False
    drag.mouse_move(4, 4)
    drag.mouse_up(4, 4)
    assert events == [("press", 0, 0, 8.0)] and not drag.active


def test_enter_confirms_only_a_drawn_arrow_and_escape_backspace_delete_clear():
    done = []
    assert not confirm_or_clear("Enter", False, lambda: done.append("confirm"), lambda: done.append("clear"))
    assert confirm_or_clear("Enter", True, lambda: done.append("confirm"), lambda: done.append("clear"))
    for key in ("Escape", "Backspace", "Delete"):
        assert confirm_or_clear(key, True, lambda: done.append("confirm"), lambda: done.append("clear"))
    assert not confirm_or_clear("a", True, lambda: done.append("confirm"), lambda: done.append("clear"))
    assert done == ["confirm", "clear", "clear", "clear"]
