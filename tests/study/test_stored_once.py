"""A demonstration is stored once: the episode's ``TeachingEpisode`` keeps it, and the widget, its
canvas, the session, the study step and the result all read that one object (there is no second
list that could drift from it)."""

import dataclasses

import numpy as np

from mt_widgets.apps import StudyApp
from mt_widgets.core import Demonstration
from mt_widgets.study import Session, Step, read_events

from .scripted import SHORT_PROTOCOL, act


def _drawn(app):
    """Draw and confirm the next arrow on the study page's canvas, with the keyboard (a person)."""
    canvas = app.episode.teaching
    for _ in range(3):
        canvas._on_key_down("ArrowRight", False, False, False)
    canvas._on_key_down("ArrowUp", False, False, False)
    canvas._on_key_down("Enter", False, False, False)


def test_a_confirmed_demonstration_is_one_object_read_by_the_widget_the_session_and_the_step(tmp_path):
    protocol_file = tmp_path / "short.toml"
    protocol_file.write_text(SHORT_PROTOCOL)
    app = StudyApp(protocol=str(protocol_file), log_folder=tmp_path / "logs")
    app.start_participant("P01", group="target")
    while app.session.current_step().kind != "demonstration":
        act(app)
    step = app.session.current_step()
    widget = app.episode
    _drawn(app)
    (given,) = widget.records
    assert isinstance(given, Demonstration) and given.method == "keyboard" and given.redraws == 4
    after = app.session.current_step()
    # One episode object everywhere, and in it one list: the widget's records ARE its list.
    assert after.teaching_episode is step.teaching_episode is widget.episode is widget.teaching.episode
    assert widget.records is widget.episode.demonstrations
    assert after.teaching_episode.demonstrations[0] is given, "the session kept another object than the widget's"
    # The step's actions and the traits are read from it, never a list of their own.
    assert "actions" not in {f.name for f in dataclasses.fields(Step)}
    np.testing.assert_array_equal(after.actions[0], given.action)
    assert widget.demonstrations == widget.teaching.demonstrations == [list(given.action)]
    # The log wrote what the record says (format unchanged: method and redraws under "input").
    events, _ = read_events(tmp_path / "logs" / "P01.jsonl")
    (logged,) = [e for e in events if e["type"] == "demonstration"]
    np.testing.assert_allclose(logged["action"], given.action)
    assert logged["input"] == {"method": "keyboard", "redraws": 4}
    assert logged["time_to_first_input_s"] == given.time_to_first_input_s is not None
    # A change to the one record is seen by every reader: nothing re-synchronises them.
    n = len(widget.episode.demonstrations)
    while app.session.current_step().kind in ("demonstration", "episode_end"):
        act(app)
    result = app.session.current_step().result
    assert result.episode is widget.episode and widget.result.episode is widget.episode
    assert result.episode.demonstrations[0] is given and len(result.demonstrations) == step.n_demonstrations > n
    app.session.close()


def test_a_resumed_session_rebuilds_each_record_from_the_log_once(tmp_path):
    protocol_file = tmp_path / "short.toml"
    protocol_file.write_text(SHORT_PROTOCOL)
    app = StudyApp(protocol=str(protocol_file), log_folder=tmp_path / "logs")
    app.start_participant("P01", group="control")
    while not ((step := app.session.current_step()).kind == "demonstration" and step.index == 2):
        if step.kind == "demonstration":
            _drawn(app)
        else:
            act(app)
    given = list(app.episode.records)
    app.session.close()  # the kernel goes away (a reload)
    resumed = Session.resume(app._study(), "P01")
    step = resumed.current_step()
    records = step.teaching_episode.demonstrations
    assert [r.index for r in records] == [0, 1]
    np.testing.assert_array_equal(step.actions[1], records[1].action)
    for before, after in zip(given, records):
        np.testing.assert_array_equal(after.action, before.action)
        assert (after.method, after.redraws, after.time_to_first_input_s) == \
            (before.method, before.redraws, before.time_to_first_input_s)
    resumed.submit_demonstration([0.5, 0.5], {"method": "script"})
    assert resumed.current_step().teaching_episode is step.teaching_episode
    assert [r.method for r in step.teaching_episode.demonstrations] == ["keyboard", "keyboard", "script"]
    resumed.close()
