"""Animations in a kernel (a running event loop): sent in short chunks, stoppable, and a replaced
view is closed only after the browser has played what it holds.

The browser's canvas manager plays every canvas's commands from one queue and stops for good
after a command for a closed canvas; these tests hold the kernel side to what avoids both.
"""

import asyncio
import threading

import pytest

from mt_widgets.widgets import DemoPage, EpisodeWidget, animation, stop_animations
from mt_widgets.widgets.receipt import Receipts

REAL_KERNEL_LOOP = animation.kernel_loop


@pytest.fixture(autouse=True)
def kernel_like(monkeypatch):
    """The tests' own loop stands for a kernel's (there is no IPython kernel under pytest)."""
    def running_loop():
        try:
            return asyncio.get_running_loop()
        except RuntimeError:
            return None
    monkeypatch.setattr(animation, "kernel_loop", running_loop)
    # Each test stands for a fresh page: the estimate of the browser's queue starts empty, not
    # behind the animations earlier tests of the run sent (a whole study app's would push every
    # chunk here minutes into the future).
    monkeypatch.setattr(animation._Queue, "free_at", 0.0)


def run_in_a_kernel_like_loop(scenario):
    """Runs the coroutine function ``scenario`` on a fresh event loop of its own thread, as a kernel's.

    A thread of its own: the test process may already run a loop in the main thread (Playwright's
    sync API does, in a run with the browser tests), and asyncio.run refuses to nest.
    """
    outcome = {}

    def run():
        try:
            outcome["value"] = asyncio.run(scenario())
        except BaseException as error:  # noqa: BLE001 - re-raised in the test's thread
            outcome["error"] = error

    thread = threading.Thread(target=run)
    thread.start()
    thread.join(60)
    if thread.is_alive():
        pytest.fail("the scenario did not finish within 60 s")
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]


def _robot_messages(recorder, layer):
    """Indices of the messages that draw on ``layer`` (a canvas or its model id), and the sleeps (ms) each holds."""
    model_id = layer if isinstance(layer, str) else layer.model_id
    found = []
    for index in range(len(recorder.messages)):
        commands = [(name, args) for canvas, name, args in recorder.commands(index) if canvas == model_id]
        if commands:
            found.append((index, [args[0] for name, args in commands if name == "sleep"]))
    return found


def _finished_episode(recorder, duration=2.0):
    episode = EpisodeWidget("sim-point", seed=0, guidance=False, duration=duration)
    for action in episode.optimal[:-1]:
        episode.demonstrate(action)
    recorder.clear()
    episode.demonstrate(episode.optimal[-1])
    return episode


def test_without_a_kernel_the_animation_is_one_message(recorder, monkeypatch):
    monkeypatch.setattr(animation, "kernel_loop", REAL_KERNEL_LOOP)  # no IPython kernel here, whatever loop runs
    episode = _finished_episode(recorder)
    messages = _robot_messages(recorder, episode.player.view.layer("robot"))
    n_frames = len(animation.frame_times(0.0, float(episode.result.trajectory.times[-1]), 60.0))
    assert len(messages) == 1 and len(messages[0][1]) == n_frames - 1


def test_in_a_kernel_the_animation_goes_in_short_chunks_just_ahead_of_playback(recorder):
    async def scenario():
        loop = asyncio.get_running_loop()
        started = loop.time()
        episode = _finished_episode(recorder)
        layer = episode.player.view.layer("robot")
        sent_at = {}
        while not animation._PLAYING[layer].done:
            for index, _ in _robot_messages(recorder, layer):
                sent_at.setdefault(index, loop.time() - started)
            await asyncio.sleep(0.02)
        return episode, layer, sent_at

    episode, layer, sent_at = run_in_a_kernel_like_loop(scenario)
    messages = _robot_messages(recorder, layer)
    n_frames = len(animation.frame_times(0.0, float(episode.result.trajectory.times[-1]), 60.0))
    assert sum(len(sleeps) for _, sleeps in messages) == n_frames - 1, "every frame is sent, once"
    assert len(messages) >= 7, "a 2 s animation goes in chunks of a quarter of a second"
    assert all(sum(sleeps) <= 1000 * animation.CHUNK_S + 20 for _, sleeps in messages)
    # Paced: the last chunk leaves well after the first, and never far ahead of playback.
    times = sorted(sent_at.values())
    assert times[-1] - times[0] >= 2.0 - animation.CHUNK_S - animation.AHEAD_S - 0.2


def test_a_stopped_animation_sends_nothing_more_and_a_retired_view_closes_once_the_page_has_drawn(
        recorder, monkeypatch):
    monkeypatch.setattr(animation, "CLOSE_MARGIN_S", 0.2)
    receipts = Receipts()
    monkeypatch.setattr(animation, "RECEIPTS", receipts)

    async def scenario():
        page = DemoPage(duration=3.0)
        episode = page.episode
        for action in episode.optimal:
            episode.demonstrate(action)
            episode.next()
        layer = episode.player.view.layer("robot").model_id
        await asyncio.sleep(0.5)
        sent_before = len(_robot_messages(recorder, layer))
        page.new_states_button.click()          # "Try again" while the reproduction plays
        await asyncio.sleep(1.2)                # past the kernel's own estimate of the playback
        sent_after = len(_robot_messages(recorder, layer))
        # No page has answered the receipt: the browser may still be drawing on the old canvases.
        open_before_answer = episode.player.view.canvas.comm is not None
        # The page (simulated: the receipt canvas's client_ready, then its picture) answers.
        receipts.canvas._handle_frontend_event(None, {"event": "client_ready"}, [])
        answered = asyncio.get_running_loop().time()
        receipts.answered(receipts.issued)
        while episode.player.view.canvas.comm is not None:
            await asyncio.sleep(0.05)
        closed_after = asyncio.get_running_loop().time() - answered
        return sent_before, sent_after, open_before_answer, closed_after, episode

    sent_before, sent_after, open_before_answer, closed_after, episode = run_in_a_kernel_like_loop(scenario)
    assert sent_after == sent_before, "the replaced episode's animation went on sending frames"
    assert sent_before >= 2
    assert open_before_answer, "closed before the page confirmed it had drawn what it held"
    # Closed once the page answered (tests/widgets/test_retire_receipt.py covers the fallback).
    assert closed_after <= 0.5
    assert episode.teaching.view.canvas.comm is None and episode.teaching.view.canvas[0].comm is None


def test_stop_animations_shows_nothing_more_and_replay_replaces_a_playing_animation(recorder):
    async def scenario():
        episode = _finished_episode(recorder, duration=3.0)
        layer = episode.player.view.layer("robot")
        await asyncio.sleep(0.3)
        episode.player.replay()                 # Replay while playing: the first one stops
        first = animation._PLAYING[layer]
        await asyncio.sleep(0.3)
        stop_animations(episode)
        count = len(_robot_messages(recorder, layer))
        await asyncio.sleep(0.6)
        return first, count, len(_robot_messages(recorder, layer))

    first, count, later = run_in_a_kernel_like_loop(scenario)
    assert first.cancelled and count == later


@pytest.mark.parametrize("show_final", [True, False])
def test_a_cancelled_animation_can_show_its_final_picture(recorder, show_final):
    async def scenario():
        episode = _finished_episode(recorder, duration=3.0)
        layer = episode.player.view.layer("robot")
        await asyncio.sleep(0.1)
        recorder.clear()
        animation.stop_animation(layer, show_final=show_final)
        return recorder.on(layer)

    drawn = run_in_a_kernel_like_loop(scenario)
    assert bool(drawn) == show_final
    assert not [args for name, args in drawn if name == "sleep"]
