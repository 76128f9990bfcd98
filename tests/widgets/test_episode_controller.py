"""The episode's one state machine (mt_widgets/widgets/episode_controller.py), without a kernel or a view.

And the one ``EpisodeWidget`` over it: a planar and a 3-D arm give the same events, callbacks and traits.
"""

import ast
from pathlib import Path

import numpy as np
import pytest

from mt_widgets.core import SKILLS, EpisodeResult, TeachingEpisode
from mt_widgets.widgets import EpisodeWidget, SpaceTeachingCanvas, TeachingCanvas
from mt_widgets.widgets.episode_controller import EVENTS, EpisodeController

WIDGETS = Path(__file__).resolve().parents[2] / "mt_widgets" / "widgets"


def watched(controller):
    """A list the controller's events (with the phase and the state shown) are appended to."""
    seen = []
    controller.observe(lambda event: seen.append((event, controller.phase, controller.state_index)))
    return seen


def expected_events(n, pause):
    """The events of an episode of ``n`` states driven through to the end, from ``resume``."""
    events = [("state", "teaching", 0)]
    for index in range(n):
        events.append(("recorded", "teaching", index + 1))
        last = index == n - 1
        if pause:
            events.append(("guidance", "guidance", index))
        events += [("reproduce", "finished", n), ("finished", "finished", n)] if last else \
            [("state", "teaching", index + 1)]
    return events


def test_the_controller_imports_no_widget_library():
    # Pure Python: a page, a test or a script drives an episode without ipywidgets or ipycanvas.
    for name in ("episode_controller.py", "callbacks.py"):
        tree = ast.parse((WIDGETS / name).read_text())
        imported = {alias.name.split(".")[0] for node in ast.walk(tree) if isinstance(node, ast.Import)
                    for alias in node.names}
        imported |= {(node.module or "").split(".")[0] for node in ast.walk(tree)
                     if isinstance(node, ast.ImportFrom) and node.level == 0}
        assert not imported & {"ipywidgets", "ipycanvas", "traitlets", "IPython"}, (name, imported)


@pytest.mark.parametrize("pause", [True, False])
def test_callbacks_run_before_the_record_and_every_demonstration_carries_the_episode_index(pause):
    episode = TeachingEpisode(SKILLS["sim-point"], seed=1)
    controller = EpisodeController(episode, guidance=pause, episode_index=3)
    order = []

    def logged(demonstration):
        # The durable writer sees the demonstration before the episode counts it.
        order.append(("logged", demonstration.index, len(episode.demonstrations), demonstration.episode_index))
    controller.on_demonstration(logged)
    controller.observe(lambda event: order.append((event, len(episode.demonstrations))))
    controller.resume()
    for index in range(episode.n_states):
        controller.hold(episode.optimal_actions[index] + 0.1, method="keyboard")
        demonstration = controller.confirm()
        assert demonstration.episode_index == 3 and demonstration.guidance_shown is pause
        assert demonstration.method == "keyboard" and demonstration.redraws == 1
        if pause:
            controller.next()
    logs = [entry for entry in order if entry[0] == "logged"]
    assert logs == [("logged", i, i, 3) for i in range(episode.n_states)]
    for index in range(episode.n_states):
        # each logged before its "recorded" event, which comes once the episode holds it
        assert order.index(("logged", index, index, 3)) < order.index(("recorded", index + 1))
    assert [d.episode_index for d in episode.demonstrations] == [3] * episode.n_states


def test_a_failing_callback_records_nothing_and_keeps_the_arrow_pending():
    episode = TeachingEpisode(SKILLS["uarm-line"], seed=0)
    controller = EpisodeController(episode, guidance=True, episode_index=1)
    seen = watched(controller)
    controller.resume()
    failing = [True]

    def log(demonstration):
        if failing[0]:
            raise OSError("disk full")
    controller.on_demonstration(log)
    controller.hold([1.0, -2.0], method="pointer")
    with pytest.raises(OSError, match="disk full"):
        controller.confirm()
    assert episode.demonstrations == [] and controller.phase == "teaching" and controller.state_index == 0
    np.testing.assert_array_equal(controller.pending_action, [1.0, -2.0])
    assert seen == [("state", "teaching", 0)]             # no guidance, no next state
    failing[0] = False
    demonstration = controller.confirm()                  # the same arrow, once the log works again
    assert episode.demonstrations == [demonstration] and demonstration.episode_index == 1
    assert controller.phase == "guidance" and seen[-1] == ("guidance", "guidance", 0)


@pytest.mark.parametrize("key", ["sim-point", "uarm-point", "ur5-reach", "ur5-conveyor"])
@pytest.mark.parametrize("pause", [True, False])
def test_every_arm_gives_the_same_events_in_the_same_order(key, pause):
    episode = TeachingEpisode(SKILLS[key], seed=0)
    controller = EpisodeController(episode, guidance=pause)
    seen = watched(controller)
    results = []
    controller.on_finished(results.append)
    controller.resume()
    for index in range(episode.n_states):
        controller.hold(episode.optimal_actions[index])
        controller.confirm()
        if pause:
            controller.next()
    assert seen == expected_events(episode.n_states, pause)
    assert set(event for event, _, _ in seen) <= set(EVENTS)
    assert len(results) == 1 and isinstance(results[0], EpisodeResult) and results[0] is controller.result
    assert results[0].theta_error < 1e-9          # the optimal arrows teach the skill exactly
    assert controller.current_state is None and not controller.accepting


def test_restore_takes_logged_demonstrations_without_callbacks_and_finishes_when_all_are_there():
    skill = SKILLS["sim-line"]
    logged = TeachingEpisode(skill, seed=4)
    actions = logged.optimal_actions + 0.2
    controller = EpisodeController(TeachingEpisode(skill, seed=4), guidance=True, episode_index=2)
    called, finished = [], []
    controller.on_demonstration(called.append)
    controller.on_finished(finished.append)
    seen = watched(controller)
    controller.restore(actions[:2])                       # a reload mid-way: on disk already
    assert called == [] and seen == [("state", "teaching", 2)] and controller.phase == "teaching"
    np.testing.assert_array_equal(controller.current_state, controller.episode.query_states[2])
    assert controller.demonstrations == [list(a) for a in actions[:2]]
    with pytest.raises(ValueError, match="demonstrations: expected the 2 actions the episode holds first"):
        controller.restore(actions[1:3])                  # never rewrites what it holds
    controller.restore(actions)                           # all given: what was learnt, at once
    assert called == [] and controller.phase == "finished" and len(finished) == 1
    assert [event for event, _, _ in seen[1:]] == ["reproduce", "finished"]
    assert finished[0].theta_error == pytest.approx(controller.episode.theta_error)


def test_the_moves_out_of_turn_are_refused_and_drawing_only_finishes_without_a_result():
    episode = TeachingEpisode(SKILLS["sim-point"], seed=0)
    controller = EpisodeController(episode, guidance=False, reproduce=False)
    finished = []
    controller.on_finished(finished.append)
    controller.resume()
    with pytest.raises(RuntimeError, match="confirm: draw an arrow first"):
        controller.confirm()
    with pytest.raises(RuntimeError, match="next: expected phase 'guidance'"):
        controller.next()
    with pytest.raises(RuntimeError, match="finish: expected 5 demonstrations, got 0"):
        controller.finish()
    with pytest.raises(ValueError, match=r"action: expected 2 finite numbers in N"):
        controller.hold([1.0, float("inf")])
    for index in range(episode.n_states):
        controller.hold(episode.optimal_actions[index])
        controller.confirm()
    assert controller.phase == "finished" and controller.result is None and finished == []
    with pytest.raises(RuntimeError, match="set_action: no query state awaits a demonstration"):
        controller.hold([0.0, 0.0])
    with pytest.raises(RuntimeError, match="confirm: input is locked"):
        controller.confirm()
    with pytest.raises(TypeError, match="episode: expected a TeachingEpisode, got str"):
        EpisodeController("sim-point")
    with pytest.raises(TypeError, match="guidance"):
        EpisodeController(episode, guidance="yes")


def test_timings_start_again_at_each_state():
    episode = TeachingEpisode(SKILLS["sim-point"], seed=0)
    controller = EpisodeController(episode)
    controller.resume()
    controller.note_input("pointer")
    controller.hold([1.0, 0.0])                           # a drag going on: no new input
    controller.hold([1.0, 1.0], method="keyboard")
    first = controller.confirm()
    assert first.method == "keyboard" and first.redraws == 2 and first.time_to_first_input_s >= 0
    controller.hold([0.5, 0.5])
    second = controller.confirm()
    assert second.method == "code" and second.redraws == 0 and second.time_to_first_input_s is None


# -- the one EpisodeWidget over it --------------------------------------------------------------------------
@pytest.mark.parametrize("guidance", [True, False])
def test_a_planar_and_a_3d_episode_widget_give_the_same_events_callbacks_and_traits(guidance, recorder):
    traces = {}
    for key, renderer in (("sim-point", TeachingCanvas), ("ur5-reach", SpaceTeachingCanvas)):
        trace = []
        widget = EpisodeWidget(key, seed=0, guidance=guidance, episode_index=4, episodes_total=6, duration=1.0)
        assert isinstance(widget.teaching, renderer) and widget.teaching.controller is widget.controller

        def logged(record, widget=widget, trace=trace):
            trace.append(("demonstration", record.index, record.episode_index, len(widget.records),
                          widget.phase, widget.state_index))
        widget.on_demonstration(logged)
        widget.on_finished(lambda result, trace=trace: trace.append(("finished", len(result.demonstrations))))
        widget.observe(lambda change, trace=trace: trace.append(("phase", change["new"])), names="phase")
        for index in range(3):
            widget.demonstrate(widget.optimal[index])
            assert widget.state_index == index + (0 if guidance else 1)
            if guidance:
                widget.next()
        trace.append(("after three", widget.state_index, widget.demonstrations == [list(a) for a in widget.optimal[:3]],
                      widget.progress.demonstrations_done))
        traces[key] = list(trace)   # the arms have their own numbers of states: the first three compared
        while widget.phase != "finished":
            if widget.phase == "guidance":
                widget.next()
            else:
                widget.demonstrate(widget.optimal[widget.state_index])
        assert widget.result is not None and widget.theta_error < 1e-9 and widget.progress.episodes_done == 5
        assert trace[-2:] == [("phase", "finished"), ("finished", widget.episode.n_states)]
    assert traces["sim-point"] == traces["ur5-reach"]
    first = traces["sim-point"][0]
    assert first == ("demonstration", 0, 4, 0, "teaching", 0)   # the index, before the record


@pytest.mark.parametrize("key", ["sim-point", "ur5-reach"])
def test_an_episode_rebuilt_after_a_reload_restores_where_it_was_on_every_arm(key, recorder):
    first = EpisodeWidget(key, seed=2, guidance=True, episode_index=1)
    log = []
    first.on_demonstration(lambda record: log.append(list(record.action)))
    for index in range(2):
        first.demonstrate(first.optimal[index] * 0.5)
        first.next()
    # The new page of a reload: the same states, the log's demonstrations.
    again = EpisodeWidget(key, seed=2, guidance=True, episode_index=1, demonstrations=log)
    assert again.demonstrations == log == first.demonstrations and again.state_index == 2
    assert again.phase == "teaching" and again.progress.demonstrations_done == 2
    np.testing.assert_array_equal(again.teaching.current_state, again.query_states[2])
    record = again.demonstrate(again.optimal[2])
    assert record.index == 2 and record.episode_index == 1
