"""The session engine: the protocol's timeline, guidance only where it says, resume, export."""

import csv
import json

import numpy as np
import pytest

from mt_widgets import SKILLS, analyse_demonstrations
from mt_widgets.study import (
    DEMONSTRATION_COLUMNS,
    EPISODE_COLUMNS,
    Session,
    SessionStateError,
    StudyFolder,
    export_study,
    read_study,
)

from .scripted import run, scripted_action, short_protocol


@pytest.fixture
def study(tmp_path):
    return StudyFolder.create(tmp_path / "study", short_protocol())


def kinds_until_end(session):
    kinds = []
    while not session.finished:
        step = session.current_step()
        kinds.append(step.kind if step.kind != "demonstration" else f"demo{step.index}")
        run(session, stop_after=1)
    return kinds


def test_the_session_follows_the_protocol_step_by_step(study):
    session = Session.start(study, "P01")
    kinds = kinds_until_end(session)
    episode = ["demo0", "demo1", "demo2", "episode_end", "reproduction"]
    assert kinds == (["welcome", "consent", "instructions", "practice", "phase_intro"] + episode
                     + ["phase_intro"] + episode * 3 + ["phase_intro"] + episode)
    assert session.current_step().text == "Thank you."
    assert session.events[-1]["type"] == "session_finished"
    session.close()


@pytest.mark.parametrize("group", ["target", "control"])
def test_guidance_comes_only_where_the_protocol_gives_it_to_the_group(study, group):
    session = Session.start(study, f"P-{group}", group=group)
    shown = {}
    while not session.finished:
        step = session.current_step()
        if step.kind == "demonstration":
            feedback = session.submit_demonstration(scripted_action(step))
            shown[(step.phase, step.episode, step.index)] = feedback.optimal is not None
            assert feedback.guidance == step.guidance
        else:
            run(session, stop_after=1)
    expected = {key: key[0] == "B" and group == "target" for key in shown}
    assert shown == expected
    # The log says what was shown, and always holds the optimal action for the analysis.
    logged = [e for e in session.events if e["type"] == "demonstration"]
    assert all(len(e["optimal"]) == 2 for e in logged)
    assert [e["guidance_shown"] for e in logged] == list(expected.values())
    session.close()


def test_the_optimal_action_shown_is_the_one_that_teaches_theta(study):
    session = Session.start(study, "P01", group="target")
    while session.current_step().phase != "B" or session.current_step().kind != "demonstration":
        run(session, stop_after=1)
    step = session.current_step()
    optimal = []
    for _ in range(step.n_demonstrations):
        optimal.append(session.submit_demonstration([0.0, 0.0]).optimal)
    skill = SKILLS[step.skill]
    analysis = analyse_demonstrations(skill.features(step.query_states), np.array(optimal), skill.theta, 0.01)
    assert analysis.risk < 1e-9
    session.close()


def test_calls_out_of_turn_are_refused(study):
    session = Session.start(study, "P01")
    expected = "submit_demonstration: expected the current step to be demonstration, it is welcome"
    with pytest.raises(SessionStateError, match=expected):
        session.submit_demonstration([1.0, 0.0])
    with pytest.raises(SessionStateError, match="finish_episode"):
        session.finish_episode()
    while session.current_step().kind != "demonstration":
        run(session, stop_after=1)
    session.submit_demonstration([1.0, 0.0], index=0)
    with pytest.raises(SessionStateError, match="index: expected the current demonstration 1, got 0"):
        session.submit_demonstration([1.0, 0.0], index=0)
    with pytest.raises(ValueError, match="action: expected 2 finite numbers"):
        session.submit_demonstration([np.nan, 0.0])
    with pytest.raises(ValueError, match="time_to_first_input_s"):
        session.submit_demonstration([1.0, 0.0], {"time_to_first_input_s": -1})
    with pytest.raises(SessionStateError, match="advance"):
        session.advance()
    assert len([e for e in session.events if e["type"] == "demonstration"]) == 1
    session.close()


@pytest.mark.parametrize("timings", [[("method", "pointer")], "fast", 1.5, ["time_to_first_input_s"]])
def test_timings_that_are_not_a_mapping_are_refused_by_name_and_nothing_is_logged(study, timings):
    session = Session.start(study, "P01")
    while session.current_step().kind != "demonstration":
        run(session, stop_after=1)
    n_events = len(session.events)
    with pytest.raises(ValueError, match=rf"timings: expected a mapping .*, got {type(timings).__name__}"):
        session.submit_demonstration([1.0, 0.0], timings)
    with pytest.raises(ValueError, match=r"timings\['method'\]: expected JSON-like data .*, got object"):
        session.submit_demonstration([1.0, 0.0], {"method": object()})
    assert len(session.events) == n_events and session.current_step().index == 0
    session.submit_demonstration([1.0, 0.0], None)  # None: no timings known
    session.close()


def test_resume_continues_at_the_first_missing_demonstration_with_the_same_states(study):
    session = Session.start(study, "P01")
    while not (session.current_step().kind == "demonstration" and session.current_step().phase == "B"
               and session.current_step().episode == 2 and session.current_step().index == 1):
        run(session, stop_after=1)
    before = session.current_step()
    session.close()
    resumed = Session.resume(study, "P01")
    after = resumed.current_step()
    assert (after.kind, after.phase, after.episode, after.index) == ("demonstration", "B", 2, 1)
    np.testing.assert_array_equal(after.query_states, before.query_states)
    assert len(after.actions) == 1
    run(resumed)
    resumed.close()


def test_query_states_differ_between_phases_and_episodes_but_not_between_participants(study):
    def states(pid):
        session = Session.start(study, pid)
        run(session)
        session.close()
        return [tuple(np.ravel(e["query_states"])) for e in session.events if e["type"] == "episode_started"]
    first, second = states("P01"), states("P02")
    assert len(set(first)) == len(first) == 5
    assert first == second  # query_states = "shared": pre-determined, the same for everyone


def test_per_participant_query_states_differ_between_participants(tmp_path):
    protocol = short_protocol()
    from mt_widgets.study.protocol import protocol_from_data
    varied = protocol_from_data(protocol.data | {"query_states": "per-participant"})
    study = StudyFolder.create(tmp_path / "s", varied)
    starts = []
    for pid in ("P01", "P02"):
        session = Session.start(study, pid)
        run(session, stop_after=6)
        starts.append(next(e["query_states"] for e in session.events if e["type"] == "episode_started"))
        session.close()
    assert starts[0] != starts[1]


def test_a_lesson_runs_the_same_engine_without_writing_anything(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    session = Session.lesson(short_protocol(), group="control")
    run(session)
    assert session.finished and list(tmp_path.iterdir()) == []
    assert not any(e.get("guidance_shown") for e in session.events)


def test_the_export_has_one_row_per_episode_and_per_demonstration(study, tmp_path):
    for pid in ("P01", "P02"):
        session = Session.start(study, pid)
        run(session)
        session.close()
    unfinished = Session.start(study, "P03")
    run(unfinished, stop_after=7)  # two demonstrations of the first episode
    unfinished.close()
    episodes_csv, demos_csv = export_study(study.folder, tmp_path / "out")
    with open(episodes_csv) as handle:
        episodes = list(csv.DictReader(handle))
    with open(demos_csv) as handle:
        demos = list(csv.DictReader(handle))
    assert tuple(episodes[0]) == EPISODE_COLUMNS and tuple(demos[0]) == DEMONSTRATION_COLUMNS
    assert len(episodes) == 2 * 5 and len(demos) == 2 * 15 + 2
    enrolled = {r["participant"]: r["group"] for r in study.enrolments()}
    assert all(row["group"] == enrolled[row["participant"]] for row in episodes + demos)
    assert [(r["phase"], r["phase_index"], r["episode"]) for r in episodes[:5]] == [
        ("A", "0", "1"), ("B", "1", "1"), ("B", "1", "2"), ("B", "1", "3"), ("C", "2", "1")]
    assert {r["guidance"] for r in episodes if r["phase"] != "B"} == {"0"}
    # Each episode's error can be recomputed from its demonstration rows.
    rows, demo_rows = read_study(study.folder)
    for episode in rows:
        mine = [d for d in demo_rows if (d["participant"], d["phase"], d["episode"]) ==
                (episode["participant"], episode["phase"], episode["episode"])]
        skill = SKILLS[episode["skill"]]
        Phi = skill.features(np.array([json.loads(d["state"]) for d in mine]))
        U = np.array([[d["action_1"], d["action_2"]] for d in mine])
        analysis = analyse_demonstrations(Phi, U, skill.theta, study.protocol.lam)
        assert analysis.risk == pytest.approx(episode["theta_error"], rel=1e-9)
        np.testing.assert_allclose(analysis.theta_hat, json.loads(episode["theta_hat"]), rtol=1e-9)
        assert episode["started_at"].endswith("Z") and episode["duration_s"] >= 0


def test_the_study_package_imports_no_widgets_and_no_serial():
    import subprocess
    import sys
    code = ("import sys, mt_widgets.study; bad = [m for m in sys.modules if m.split('.')[0] in "
            "('ipywidgets', 'ipycanvas', 'serial', 'pandas') or m.startswith('mt_widgets.apps')]; "
            "print(bad); sys.exit(bool(bad))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
