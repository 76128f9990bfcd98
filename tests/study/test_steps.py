"""The steps around the task, withdrawal and balanced assignment, as the protocol says them."""

import re

import numpy as np
import pytest

from blinding_support import participant_texts
from mt_widgets.apps import StudyApp
from mt_widgets.core import SKILLS
from mt_widgets.study import (
    LogError,
    ProtocolError,
    Session,
    SessionStateError,
    StudyFolder,
    load_protocol,
    parse_protocol,
    read_events,
    read_study,
)
from mt_widgets.study.session import timeline
from mt_widgets.study.study_folder import OUTCOME_FILE

from .scripted import (
    STEPS,
    VIDEO,
    _with_steps,
    run_to_end,
    run_to_end_one,
    steps_protocol,
)

# -- protocol input ----------------------------------------------------------------------------------

def _error(text: str) -> ProtocolError:
    with pytest.raises(ProtocolError) as caught:
        parse_protocol(text, "bad.toml")
    return caught.value


def _line_of(text: str, pattern: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), start=1) if re.search(pattern, line))


def test_an_unknown_step_kind_is_refused_with_file_line_and_field():
    text = _with_steps(STEPS.replace('kind = "information"', 'kind = "slideshow"'))
    error = _error(text)
    assert error.field == "before[1].kind" and error.line == _line_of(text, r'kind = "slideshow"')
    assert "bad.toml" in str(error) and "slideshow" in str(error)


def test_a_video_file_that_does_not_exist_is_refused():
    text = _with_steps(STEPS.replace(str(VIDEO), "/nowhere/intro.webm"))
    error = _error(text)
    assert error.field == "before[0].file" and error.line == _line_of(text, "nowhere") and "no video file" in str(error)


def test_a_questionnaire_without_items_is_refused():
    text = _with_steps(STEPS.split("[[after.items]]")[0])
    error = _error(text)
    assert error.field == "after[0].items" and error.line == _line_of(text, r'id = "tlx"') - 1
    assert "at least one item" in str(error)


def test_a_likert_item_with_one_level_is_refused():
    text = _with_steps(STEPS.replace('levels = ["1", "2", "3", "4", "5", "6", "7"]', 'levels = ["only"]'))
    error = _error(text)
    assert error.field == "after[0].items[0].levels" and error.line == _line_of(text, r'levels = \["only"\]')


def test_the_shipped_paper_protocols_use_arrows_a_neutral_practice_and_the_papers_steps():
    for name in ("paper-sim", "paper-uarm"):
        protocol = load_protocol(name)
        assert protocol.guidance_modality == "arrows"
        assert protocol.practice.skill not in {phase.skill for phase in protocol.phases}
        assert not protocol.practice.reproduction
        practice_goal = protocol.skill(protocol.practice.skill).target.point
        assert all(protocol.skill(p.skill).target.point != practice_goal for p in protocol.phases)
        assert [s.kind for s in protocol.before] == ["video", "information", "consent", "eligibility",
                                                     "demographics"]
        assert {i.id for i in protocol.step("demographics").items} == {"age", "sex"}
        assert protocol.step("video").require_watched and protocol.step("video").video.endswith(".webm")


# -- the session through the steps ---------------------------------------------------------------------

def test_every_step_is_logged_in_the_protocols_order(tmp_path):
    protocol = steps_protocol()
    slots = timeline(protocol)
    assert [s.kind for s in slots[:7]] == ["welcome", "step", "step", "step", "step", "step", "instructions"]
    study = StudyFolder.create(tmp_path / "s", protocol)
    session = Session.start(study, "P01", group="target")
    run_to_end(session)
    assert session.completed
    events, _ = read_events(study.log_path("P01"))
    done = {e["step"]: e for e in events if e["type"] == "step_done"}
    assert done["video"]["watched_to_end"] is True and done["video"]["plays"] == 2
    assert done["screen"]["answers"] == {"background": "no"} and done["screen"]["eligible"] is True
    assert done["about"]["answers"] == {"age": 30, "sex": "female"}
    assert done["tlx"]["answers"] == {"effort": "5", "hours": 7.0, "notes": None}
    assert [e["step"] for e in events if e["type"] == "consent_given"] == ["consent"]
    started = [e for e in events if e["type"] == "episode_started"]
    assert {e["guidance_modality"] for e in started} == {"arrows"}
    order = [e["step"] for e in events if e["type"] in ("step_done", "consent_given")]
    assert order == ["video", "info", "consent", "screen", "about", "tlx"]


def test_a_video_must_play_to_the_end_and_answers_are_checked(tmp_path):
    session = Session.start(StudyFolder.create(tmp_path / "s", steps_protocol()), "P01")
    session.advance()
    with pytest.raises(SessionStateError, match="watched to the end"):
        session.finish_video(False, 1)
    session.finish_video(True, 1)
    session.advance()
    session.advance()
    with pytest.raises(ValueError, match=r"answers\['background'\]: expected one of"):
        session.submit_answers({"background": "maybe"})
    with pytest.raises(ValueError, match="unknown items"):
        session.submit_answers({"background": "no", "shoe_size": 42})
    session.submit_answers({"background": "no"})
    with pytest.raises(ValueError, match=r"answers\['age'\]: expected a whole number"):
        session.submit_answers({"age": 30.5, "sex": "male"})
    with pytest.raises(ValueError, match=r"answers\['age'\]"):
        session.submit_answers({"age": 12, "sex": "male"})


def test_declining_consent_or_an_ineligible_answer_ends_the_session_and_keeps_it_out(tmp_path):
    study = StudyFolder.create(tmp_path / "s", steps_protocol())
    declined = Session.start(study, "P01")
    declined.advance()
    declined.finish_video(True, 1)
    declined.advance()
    step = declined.decline_consent()
    assert step.kind == "ended" and declined.ended == "declined" and declined.finished and not declined.completed
    with pytest.raises(SessionStateError, match="ended"):
        declined.advance()
    declined.close()
    screened = Session.start(study, "P02")
    screened.advance()
    screened.finish_video(True, 1)
    screened.advance()
    screened.advance()
    assert screened.submit_answers({"background": "yes"}).ended == "ineligible"
    screened.close()
    assert {p: r["outcome"] for p, r in study.outcomes().items()} == {"P01": "declined", "P02": "ineligible"}
    with pytest.raises(LogError, match="declined consent"):
        Session.resume(study, "P01")


def test_a_withdrawn_participant_is_kept_out_logged_and_cannot_be_resumed(tmp_path):
    study = StudyFolder.create(tmp_path / "s", steps_protocol())
    for pid in ("P01", "P02"):
        run_to_end(Session.start(study, pid, group="target"))
    session = Session.start(study, "P03", group="control")
    while session.current_step().kind != "episode_end":
        run_step = session.current_step()
        if run_step.phase == "B":
            break
        run_to_end_one(session)
    step = session.withdraw("changed my mind")
    assert step.kind == "ended" and "withdrawn" in step.text
    session.close()
    events, _ = read_events(study.log_path("P03"))  # kept: the protocol says "exclude"
    assert events[-1]["type"] == "withdrawn" and events[-1]["data"] == "exclude"
    episodes, demonstrations = read_study(study.folder)
    assert {e["participant"] for e in episodes} == {"P01", "P02"}
    assert "P03" not in {d["participant"] for d in demonstrations}
    with pytest.raises(LogError, match="withdrew from the study.*cannot be resumed"):
        Session.resume(study, "P03")
    assert [r["state"] for r in study.status()] == ["completed", "completed", "withdrawn"]


def test_a_protocol_that_says_delete_deletes_the_log_and_records_the_withdrawal(tmp_path):
    study = StudyFolder.create(tmp_path / "s", steps_protocol(STEPS.replace('"exclude"', '"delete"')))
    session = Session.start(study, "P01")
    session.advance()
    session.withdraw()
    assert not study.log_path("P01").exists()
    record = study.outcomes()["P01"]
    assert record["outcome"] == "withdrawn" and record["data"] == "delete"
    assert (study.folder / OUTCOME_FILE).read_text().count("P01") == 1
    with pytest.raises(LogError, match="withdrew"):
        Session.resume(study, "P01")


# -- balanced assignment --------------------------------------------------------------------------------

def test_places_freed_by_those_who_leave_go_to_the_next_enrolled_so_completers_stay_balanced(tmp_path):
    study = StudyFolder.create(tmp_path / "s", steps_protocol())
    first = [study.enrol(f"P{i:02d}")["group"] for i in range(8)]
    assert first.count("target") == first.count("control") == 4
    lost = [f"P{i:02d}" for i, g in enumerate(first) if g == "target"][:2]
    for pid in lost:
        study.record_outcome(pid, "withdrawn", data="exclude")
    dropped = [f"P{i:02d}" for i, g in enumerate(first) if g == "control"][0]
    study.mark_dropped_out(dropped, "no show")
    replacements = [study.enrol(f"R{i}") for i in range(3)]
    assert [r["method"] for r in replacements] == ["replacement"] * 3
    # Each freed place is taken in enrolment order of those who left, in their group.
    freed = sorted(lost + [dropped])
    assert [r["replaces"] for r in replacements] == freed
    assert [r["group"] for r in replacements] == [first[int(p[1:])] for p in freed]
    after = study.enrol("N1")
    assert after["method"] == "block" and after["block_slot"] == 8
    status = study.group_status()
    assert status["target"]["withdrawn"] == 2 and status["control"]["dropped_out"] == 1
    staying = {g: status[g]["enrolled"] - status[g]["withdrawn"] - status[g]["dropped_out"] for g in status}
    assert staying["target"] - staying["control"] == (1 if after["group"] == "target" else -1)
    assert "withdrawn" in study.status_report().splitlines()[0]


def test_an_experimenter_assignment_frees_no_randomised_place(tmp_path):
    study = StudyFolder.create(tmp_path / "s", steps_protocol())
    study.enrol("E1", group="target")
    study.record_outcome("E1", "withdrawn")
    assert study.enrol("P01")["method"] == "block"


# -- in the app -----------------------------------------------------------------------------------------

# The words of guidance (how the arrow differs from the optimal one), not the legend naming the arrows.
GUIDANCE_WORDS = re.compile(r"(off by|too long|too short|direction: |size: |&deg; off|° off)", re.IGNORECASE)


def test_the_app_shows_arrows_only_to_the_target_group_when_the_protocol_says_arrows(tmp_path):
    path = tmp_path / "steps.toml"
    path.write_text(_with_steps())
    app = StudyApp(protocol=str(path), log_folder=tmp_path / "logs")
    app.start_participant("P01", group="target")
    seen_arrows = False
    while not app.session.finished:
        step = app.session.current_step()
        if step.kind == "video":
            assert app.video.continue_button.disabled
            app.video.player._handle_custom_msg({"event": "ended", "whole": True}, [])
            app.video.continue_button.click()
        elif step.kind in ("eligibility", "demographics", "questionnaire"):
            values = {"background": "no", "age": "31", "sex": "male", "effort": "3", "hours": "8"}
            for item_id, field in app.form.fields.items():
                field.value = values.get(item_id, "")
            app.form.continue_button.click()
        elif step.kind == "practice":
            from mt_widgets.widgets import EpisodeWidget, TeachingCanvas
            # drawing only: no reproduction
            assert isinstance(app.episode, EpisodeWidget) and not app.episode.reproduce
            assert isinstance(app.episode.teaching, TeachingCanvas)
            app._practice_done.disabled = False
            app._practice_done.click()
        elif step.kind in ("demonstration", "episode_end"):
            if app.episode.phase == "guidance":
                assert app.episode.teaching._guidance is not None  # the optimal arrow is drawn
                assert not GUIDANCE_WORDS.search(" ".join(participant_texts(app)))
                assert app.episode.guidance_panel.value == ""
                seen_arrows = True
                app.episode.next()
            else:
                app.episode.demonstrate(SKILLS[step.skill].target_actions(step.state[None])[0] + 0.3)
        elif step.kind == "reproduction":
            app._continue.click()
        else:
            buttons = [w for w in app.body.children if getattr(w, "button_style", None) == "primary"]
            buttons[0].click()
    assert seen_arrows and app.session.completed
    events, _ = read_events(tmp_path / "logs" / "P01.jsonl")
    answers = {e["step"]: e.get("answers") for e in events if e["type"] == "step_done"}
    assert answers["about"] == {"age": 31, "sex": "male"} and answers["tlx"]["hours"] == 8.0


def test_in_the_app_a_participant_withdraws_after_confirming(tmp_path):
    path = tmp_path / "steps.toml"
    path.write_text(_with_steps())
    app = StudyApp(protocol=str(path), log_folder=tmp_path / "logs")
    app.start_participant("P01")
    app.withdraw_button.click()
    assert app.session.ended is None  # a first click only asks
    no = [w for w in app.withdraw_box.children[1].children if w.description.startswith("No")][0]
    no.click()
    assert app.withdraw_box.children == (app.withdraw_button,)
    app.withdraw_button.click()
    [w for w in app.withdraw_box.children[1].children if w.description == "Yes, withdraw"][0].click()
    assert app.session.ended == "withdrawn" and app.withdraw_box.layout.display == "none"
    assert "withdrawn" in " ".join(participant_texts(app.body))
    assert StudyFolder(tmp_path / "logs").outcomes()["P01"]["outcome"] == "withdrawn"


def test_the_widget_shows_words_only_or_nothing_when_told():
    from mt_widgets.widgets import EpisodeWidget
    skill = SKILLS["sim-point"]
    for modality, arrow, words in (("words", False, True), ("arrows+words", True, True), ("arrows", True, False)):
        widget = EpisodeWidget(skill, guidance=True, guidance_modality=modality)
        widget.demonstrate(np.array([0.5, 0.5]))
        assert (widget.teaching._guidance is not None) == arrow
        assert bool(GUIDANCE_WORDS.search(widget.guidance_panel.value)) == words
    none = EpisodeWidget(skill, guidance=True, guidance_modality="none")
    none.demonstrate(np.array([0.5, 0.5]))
    assert none.phase == "teaching" and none.state_index == 1
    with pytest.raises(ValueError, match="guidance_modality"):
        EpisodeWidget(skill, guidance_modality="sparkles")


def test_a_lesson_runs_the_task_without_the_steps_around_it():
    session = Session.lesson(steps_protocol(), group="target")
    kinds = []
    while not session.finished:
        kinds.append(session.current_step().kind)
        run_to_end_one(session)
    assert kinds[:3] == ["welcome", "consent", "instructions"] and session.completed
    assert not {"video", "information", "eligibility", "demographics", "questionnaire"} & set(kinds)


def test_the_experimenter_panel_says_why_a_withdrawn_participant_cannot_be_resumed(tmp_path):
    path = tmp_path / "steps.toml"
    path.write_text(_with_steps())
    first = StudyApp(protocol=str(path), log_folder=tmp_path / "logs")
    first.start_participant("P01")
    first.withdraw()
    again = StudyApp(protocol=str(path), log_folder=tmp_path / "logs")
    again.experimenter.participant.value = "P01"
    again.experimenter.resume_button.click()
    assert again.session is None and again.children == (again.experimenter,)
    assert "withdrew from the study" in again.experimenter.message.value
    assert "cannot be resumed" in again.experimenter.message.value
