import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.widgets import ArmView, EpisodeWidget, ReproductionPlayer, TeachingCanvas

from .conftest import client_ready, key, near, path_points, pointer


def _cross(a, b) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


def test_background_is_drawn_once_and_shows_the_point_target(recorder):
    skill = SKILLS["sim-point"]
    view = ArmView(skill)
    background = recorder.on(view.layer("background"))
    target_px = view.transform.to_pixel(skill.target.point)
    circles = [args for name, args in background if name == "fillCircle"]
    assert any(np.allclose(args[:2], target_px) for args in circles), "a dot at the target point"
    texts = [args[0] for name, args in background if name == "fillText"]
    assert "positions in m" in texts and any(t.startswith("arrows: ") and t.endswith(" N") for t in texts)
    recorder.clear()
    view.show_state(skill.start)
    assert recorder.on(view.layer("background")) == [], "showing a state leaves the background alone"


def test_line_target_and_uarm_workspace_are_drawn(recorder):
    skill = SKILLS["uarm-line"]
    view = ArmView(skill)
    background = recorder.on(view.layer("background"))
    lines = [args for name, args in background if name == "strokeLine"]
    point, direction = np.array(skill.target.point), np.array(skill.target.direction)
    on_line = []
    for x1, y1, x2, y2 in lines:
        a, b = view.transform.to_world([[x1, y1], [x2, y2]])
        if abs(_cross(a - point, direction)) < 1e-6 and abs(_cross(b - point, direction)) < 1e-6 \
                and np.linalg.norm(b - a) > 20:
            on_line.append((a, b))
    assert on_line, "a long stroke along the target line r1 = 2 r2"
    # The uArm's reachable sector is outlined: a path along both of its arcs, within its bearings.
    sector = skill.plant.workspace
    outline = view.transform.to_world(np.array(path_points(background), dtype=float))
    radius = np.hypot(outline[:, 0], outline[:, 1])
    bearing = np.degrees(np.arctan2(outline[:, 1], outline[:, 0]))
    on_arc = (np.abs(radius - sector.r_max) < 0.05) | (np.abs(radius - sector.r_min) < 0.05)
    assert on_arc.sum() > 100 and np.all(np.abs(bearing[on_arc]) <= sector.max_yaw_deg + 0.1), \
        "the uArm's reachable sector is outlined"
    assert np.any(np.abs(radius - sector.r_max) < 0.05) and np.any(np.abs(radius - sector.r_min) < 0.05)


def test_sim_arm_is_drawn_through_its_joints_in_the_given_state(recorder):
    skill = SKILLS["sim-point"]
    view = ArmView(skill)
    state = np.array([0.4, 0.9, 0.5, -0.2])
    recorder.clear()
    view.show_state(state)
    commands = recorder.on(view.layer("robot"))
    joints = view.transform.to_pixel(skill.plant.arm.joint_positions(state[:2]))
    points = path_points(commands)
    assert all(near(points, joint) for joint in joints)
    assert ("fillCircle", [*np.round(joints[2], 6).tolist(), 8.0]) in [
        (n, [round(v, 6) for v in a]) for n, a in commands if n == "fillCircle"], "end-effector marker"


def test_uarm_state_is_a_black_dot_at_its_position(recorder):
    skill = SKILLS["uarm-point"]
    view = ArmView(skill)
    recorder.clear()
    view.show_state([22.0, -5.0])
    commands = recorder.on(view.layer("robot"))
    assert ("set", [0, "#000000"]) in commands
    dots = [a for n, a in commands if n == "fillCircle"]
    assert np.allclose(dots[-1][:2], view.transform.to_pixel([22.0, -5.0]))


def test_every_layer_repaints_itself_when_a_new_view_attaches_issue_322(recorder):
    skill = SKILLS["sim-point"]
    view = ArmView(skill)
    view.show_state(skill.start)
    first_background = recorder.on(view.layer("background"))
    recorder.clear()
    # The manager still believes it is drawing on the robot layer (what breaks #322) ...
    import ipycanvas
    ipycanvas.canvas._CANVAS_MANAGER._current_canvas = view.layer("background")
    client_ready(view.layer("background"))
    # ... yet the repaint names its canvas first, and draws the same background again.
    first = recorder.messages[0][0]
    assert first[0][0] == ipycanvas.canvas.COMMANDS["switchCanvas"]
    assert recorder.on(view.layer("background")) == first_background
    recorder.clear()
    client_ready(view.layer("robot"))
    assert path_points(recorder.on(view.layer("robot"))), "the robot layer redraws the arm"


def test_pointer_drag_from_the_end_effector_gives_the_action_within_a_pixel(recorder):
    skill = SKILLS["sim-point"]
    states = skill.query_states(seed=3)
    teach = TeachingCanvas(skill, states)
    view = teach.view
    ee = view.end_effector_pixel(states[0])
    target = ee + np.array([47.3, -21.8])
    pointer(view.canvas, "mouse_down", *ee)
    recorder.clear()
    pointer(view.canvas, "mouse_move", *(ee + [20, -10]))
    assert len(recorder.messages) == 1, "one message per drag move"
    assert recorder.on(view.layer("arrows")) and not recorder.on(view.layer("robot")), "only the arrow layer"
    pointer(view.canvas, "mouse_up", *target)
    expected = view.transform.action_from_drag(skill.end_effector(states[:1])[0][0], target)
    assert np.allclose(teach.pending_action, expected)
    one_pixel = 1.0 / view.transform.pixels_per_action
    tip = view.transform.action_tip(skill.end_effector(states[:1])[0][0], teach.pending_action)
    assert np.hypot(*(tip - target)) < 1e-9
    assert abs(teach.pending_action[0] - 47.3 * one_pixel) < one_pixel
    assert abs(teach.pending_action[1] - 21.8 * one_pixel) < one_pixel, "pixel y down is world y up"
    assert "State 1 of 5" in teach.readout.value and "N" in teach.readout.value


def test_moves_without_a_press_send_nothing_and_presses_away_from_the_marker_do_not_draw(recorder):
    skill = SKILLS["sim-point"]
    teach = TeachingCanvas(skill, skill.query_states(seed=0))
    ee = teach.view.end_effector_pixel(teach.current_state)
    recorder.clear()
    for dx in range(30):
        pointer(teach.view.canvas, "mouse_move", ee[0] + dx, ee[1])
    assert recorder.messages == []
    pointer(teach.view.canvas, "mouse_down", ee[0] + 100, ee[1] + 100)
    pointer(teach.view.canvas, "mouse_move", ee[0] + 120, ee[1] + 100)
    assert teach.pending_action is None and "robot's hand" in teach.hint.value


def test_an_arrow_can_be_redrawn_before_it_is_confirmed_and_then_the_next_state_shows():
    skill = SKILLS["uarm-point"]
    teach = TeachingCanvas(skill, skill.query_states(seed=1))
    ee = teach.view.end_effector_pixel(teach.current_state)
    for end in (ee + [30, 0], ee + [0, 40]):
        pointer(teach.view.canvas, "mouse_down", *ee)
        pointer(teach.view.canvas, "mouse_up", *end)
    assert teach.pending_action[0] == pytest.approx(0.0, abs=1e-9) and teach.pending_action[1] < 0
    confirmed = teach.confirm()
    assert confirmed.method == "pointer" and confirmed.redraws == 2
    assert confirmed.time_to_first_input_s >= 0 and confirmed.drawing_duration_s >= 0
    assert teach.state_index == 1 and teach.demonstrations == [list(confirmed.action)]
    assert teach.pending_action is None


def test_keyboard_and_numeric_entry_set_the_same_kind_of_action():
    skill = SKILLS["sim-line"]
    teach = TeachingCanvas(skill, skill.query_states(seed=0))
    step = teach.view.transform.nice_action_step() / 10
    for name in ("ArrowRight", "ArrowRight", "ArrowUp"):
        key(teach.view.canvas, name)
    assert np.allclose(teach.pending_action, [2 * step, step])
    key(teach.view.canvas, "Escape")
    assert teach.pending_action is None
    teach.entry_mode.value = "polar"
    teach.first_entry.value, teach.second_entry.value = 90.0, 2.0
    teach.set_button.click()
    assert np.allclose(teach.pending_action, [0.0, 2.0], atol=1e-12)
    key(teach.view.canvas, "Enter")
    assert teach.state_index == 1 and np.allclose(teach.demonstrations[0], [0.0, 2.0], atol=1e-12)


def test_code_can_set_an_action_and_bad_actions_are_refused():
    skill = SKILLS["sim-point"]
    teach = TeachingCanvas(skill, skill.query_states(seed=0))
    teach.set_action([0.5, -1.0])
    assert teach.pending_action == [0.5, -1.0]
    with pytest.raises(ValueError, match="action"):
        teach.set_action([1.0, float("nan")])
    with pytest.raises(ValueError, match="query_states"):
        TeachingCanvas(skill, np.zeros((3, 2)))


def test_reproduction_is_one_message_with_a_frame_per_sixtieth_of_a_second(recorder):
    skill = SKILLS["sim-point"]
    player = ReproductionPlayer(skill)
    trajectory = skill.reproduce(skill.theta * 0.5)
    recorder.clear()
    player.play(trajectory, theta_error=0.5, ghost=skill.reproduce(skill.theta))
    assert len(recorder.messages) == 1
    sleeps = [a[0] for c, n, a in recorder.commands(0) if n == "sleep"]
    assert len(sleeps) == round(trajectory.times[-1] * 60) and sleeps[0] == pytest.approx(1000 / 60, abs=0.01)
    assert recorder.message_bytes(0) <= 150_000
    robot = recorder.on(player.view.layer("robot"))
    final_tip = player.view.transform.to_pixel(trajectory.positions[-1])
    assert near([a[:2] for n, a in robot[-12:] if n == "fillCircle"], final_tip, 0.01), "ends at the last state"
    assert "0.5" in player.error_label.value and not player.replay_button.disabled
    recorder.clear()
    player.replay_button.click()
    assert len(recorder.messages) == 1


def test_a_diverging_skill_is_shown_as_diverged(recorder):
    skill = SKILLS["sim-point"]
    player = ReproductionPlayer(skill)
    unstable = -5.0 * np.asarray(skill.theta)
    trajectory = skill.reproduce(unstable)
    assert trajectory.diverged, "precondition: this policy pushes the arm away"
    player.play(trajectory, theta_error=10.0)
    assert "diverged" in player.status.value
    strokes = [a for n, a in recorder.on(player.view.layer("robot")) if n == "strokeLine"]
    assert len(strokes) >= 2, "a cross at the point of divergence"


def test_canvas_text_keeps_its_size_on_screen_when_the_canvas_is_shown_smaller(recorder):
    # 480 canvas pixels shown 360 px wide: text drawn at 12 px would read as 9 px.
    skill = SKILLS["sim-point"]
    fonts = {}
    for css_width in (None, "360px"):
        recorder.clear()
        view = ArmView(skill, css_width=css_width)
        fonts[css_width] = {args[1] for name, args in recorder.on(view.layer("background"))
                            if name == "set" and isinstance(args[1], str) and args[1].endswith("px sans-serif")}
    assert fonts[None] == {"12px sans-serif", "13px sans-serif"}
    assert fonts["360px"] == {"16px sans-serif", "17px sans-serif"}          # 12 and 13 px times 480 / 360


def _canvas_texts(recorder) -> list[str]:
    return [str(args[0]) for _, name, args in recorder.commands() if name in ("fillText", "strokeText")]


def test_the_canvas_never_writes_a_group_word_and_the_label_can_go(recorder):
    # "target" also names a study group: a blinded participant must not read it on the canvas.
    from mt_widgets.widgets import EpisodeWidget

    EpisodeWidget("sim-point", seed=0)
    texts = _canvas_texts(recorder)
    assert "goal" in texts and not any("target" in t.lower() for t in texts)
    recorder.clear()
    EpisodeWidget("uarm-line", seed=0, target_label=None)
    texts = _canvas_texts(recorder)
    assert texts and "goal" not in texts and not any("target" in t.lower() for t in texts)
    with pytest.raises(ValueError, match="target_label"):
        EpisodeWidget("sim-point", seed=0, target_label=3)


def test_a_blinded_episode_shows_neither_formula_nor_outcome(recorder):
    from mt_widgets import SKILLS
    from mt_widgets.widgets import EpisodeWidget

    skill = SKILLS["sim-point"]
    episode = EpisodeWidget(skill, seed=1, guidance=False, show_description=False, show_outcome=False, ghost=False)
    assert skill.description not in episode.header.value
    for u in skill.target_actions(episode.query_states) + 0.7:
        episode.demonstrate(u)
    episode.finish()
    assert episode.result is not None and episode.result.theta_error > 0
    shown = episode.player.error_label.value + episode.player.status.value
    assert "error" not in shown.lower() and "goal" not in shown.lower()
    assert f"{episode.result.theta_error:.3f}" not in shown
    # Without blinding the same episode states both.
    open_episode = EpisodeWidget(skill, seed=1, guidance=False)
    for u in skill.target_actions(open_episode.query_states) + 0.7:
        open_episode.demonstrate(u)
    open_episode.finish()
    assert skill.description in open_episode.header.value
    assert f"{open_episode.result.theta_error:.3f}" in open_episode.player.error_label.value


def test_enter_mid_drag_ends_the_drag_so_later_moves_draw_nothing_at_the_next_state(recorder, caplog):
    skill = SKILLS["uarm-point"]
    teach = TeachingCanvas(skill, skill.query_states(seed=1)[:2])
    canvas = teach.view.canvas
    for index in range(2):
        ee = teach.view.end_effector_pixel(teach.current_state)
        pointer(canvas, "mouse_down", *ee)
        pointer(canvas, "mouse_move", *(ee + [25, 10]))
        key(canvas, "Enter")  # confirmed mid-drag, the button still pressed
        assert teach.state_index == index + 1 and len(teach.demonstrations) == index + 1
        recorder.clear()
        pointer(canvas, "mouse_move", *(ee + [40, -30]))
        pointer(canvas, "mouse_up", *(ee + [40, -30]))
        # The next state shows no arrow from the old drag; after the last, nothing fails.
        assert teach.pending_action is None and recorder.messages == []
    assert not [r for r in caplog.records if "Exception in callback" in r.getMessage()]


def test_a_move_after_confirming_mid_drag_leaves_the_confirmed_arrow_under_guidance(recorder):
    skill = SKILLS["sim-point"]
    episode = EpisodeWidget(skill, seed=2, guidance=True)
    teach = episode.teaching
    ee = teach.view.end_effector_pixel(teach.current_state)
    pointer(teach.view.canvas, "mouse_down", *ee)
    pointer(teach.view.canvas, "mouse_move", *(ee + [25, 10]))
    key(teach.view.canvas, "Enter")
    assert episode.phase == "guidance"
    confirmed = list(teach.pending_action)
    pointer(teach.view.canvas, "mouse_move", *(ee + [-40, 30]))
    pointer(teach.view.canvas, "mouse_up", *(ee + [-40, 30]))
    assert teach.pending_action == confirmed == episode.demonstrations[0]


def test_confirm_closes_before_the_next_state_is_drawn(recorder):
    # A page showing the next state must never offer the previous arrow's Confirm: the button's
    # change reaches the browser before the new state's drawing does.
    skill = SKILLS["sim-point"]
    teach = TeachingCanvas(skill, skill.query_states(seed=0))
    ee = teach.view.end_effector_pixel(teach.current_state)
    pointer(teach.view.canvas, "mouse_down", *ee)
    pointer(teach.view.canvas, "mouse_up", ee[0] + 30, ee[1] - 20)
    assert not teach.confirm_button.disabled
    recorder.clear()
    drawn_before_closing = []
    teach.confirm_button.observe(lambda change: drawn_before_closing.append(
        bool(recorder.on(teach.view.layer("robot")))), names="disabled")
    teach.confirm_button.click()
    assert teach.state_index == 1 and teach.confirm_button.disabled
    assert drawn_before_closing == [False]
    assert recorder.on(teach.view.layer("robot"))  # and then the next state was drawn


@pytest.mark.parametrize("skill_key", ["sim-point", "uarm-line"])
def test_a_teaching_canvas_without_query_states_shows_the_skills_seeded_states(skill_key):
    # query_states defaults to None: the canvas draws the skill's S well-conditioned states of seed 0.
    skill = SKILLS[skill_key]
    teach = TeachingCanvas(skill)
    np.testing.assert_array_equal(teach.query_states, skill.query_states(seed=0))
    assert teach.n_states == skill.n_features and teach.state_index == 0
    assert f"State 1 of {skill.n_features}" in teach.readout.value
