"""A scripted participant: deterministic actions, so two runs must log identical demonstrations."""

from __future__ import annotations

import time

import numpy as np

from mt_widgets import SKILLS
from mt_widgets.study import Session, StudyFolder, load_protocol, parse_protocol
from mt_widgets.study.protocol import PROTOCOL_FOLDER

#: A short protocol with every kind of step (practice, phases with and without guidance,
#: several episodes): the engine knows no more than this file, so it is enough to test it.
SHORT_PROTOCOL = """
format = 1
name = "short"
lambda = 0.01
seed = 11
[assignment]
block_size = 2
seed = 3
[texts]
welcome = "Welcome."
consent = "Consent."
instructions = "Instructions."
reproduction = "Reproduction."
thank_you = "Thank you."
[practice]
skill = "uarm-point"
duration_s = 5
text = "Practice."
[[phases]]
id = "A"
skill = "uarm-point"
episodes = 1
instructions = "Phase A."
[[phases]]
id = "B"
skill = "uarm-line"
episodes = 3
guidance = ["target"]
instructions = "Phase B."
[[phases]]
id = "C"
skill = "uarm-point"
episodes = 1
instructions = "Phase C."
"""


def short_protocol():
    return parse_protocol(SHORT_PROTOCOL, "short.toml")


def scripted_action(step) -> np.ndarray:
    """The skill's own action plus noise seeded by where the step is: same step, same action."""
    skill = SKILLS[step.skill]
    rng = np.random.default_rng([step.phase_index, step.episode, step.index])
    target = skill.target_actions(step.state[None])[0]
    return target + rng.normal(0.0, 0.2 * (1 + np.abs(target)), size=target.shape)


def run(session, stop_after: int | None = None) -> int:
    """Drives ``session`` to the end (or for ``stop_after`` calls); returns the calls made."""
    calls = 0
    while not session.finished and (stop_after is None or calls < stop_after):
        step = session.current_step()
        if step.kind == "practice":
            session.finish_practice(duration_s=5.0)
        elif step.kind == "demonstration":
            session.submit_demonstration(scripted_action(step), {"time_to_first_input_s": 0.5,
                                                                 "drawing_duration_s": 0.25}, index=step.index)
        elif step.kind == "episode_end":
            session.finish_episode()
        else:
            session.advance()
        calls += 1
    return calls


def demonstrations(events) -> list[tuple]:
    """The demonstrations of a log, as comparable tuples (where, state, action)."""
    return [(e["phase"], e["episode"], e["index"], tuple(e["state"]), tuple(e["action"]))
            for e in events if e["type"] == "demonstration"]


# -- a protocol with every kind of step around the task (tests/study/test_steps.py, test_bids.py) ----

VIDEO = PROTOCOL_FOLDER / "media" / "instructions.webm"

STEPS = f"""
withdrawal = "exclude"
guidance_modality = "arrows"

[[before]]
id = "video"
kind = "video"
file = "{VIDEO}"

[[before]]
id = "info"
kind = "information"
text = "What the study is."

[[before]]
id = "consent"
kind = "consent"
text = "Do you agree?"

[[before]]
id = "screen"
kind = "eligibility"

[[before.items]]
id = "background"
kind = "choice"
prompt = "Robotics before?"
options = ["no", "yes"]
eligible = ["no"]

[[before]]
id = "about"
kind = "demographics"

[[after]]
id = "tlx"
kind = "questionnaire"

[[after.items]]
id = "effort"
kind = "likert"
prompt = "How hard did you work?"
levels = ["1", "2", "3", "4", "5", "6", "7"]

[[after.items]]
id = "hours"
kind = "number"
prompt = "Hours of sleep"
minimum = 0
maximum = 24

[[after.items]]
id = "notes"
kind = "text"
prompt = "Anything else?"
required = false
"""


def _with_steps(extra: str = STEPS, base: str = SHORT_PROTOCOL) -> str:
    # Top-level keys go before the first table; the step tables at the end; practice draws only.
    base = base.replace('text = "Practice."', 'text = "Practice."\nreproduction = false')
    head, tables = extra.split("[[before]]", 1) if "[[before]]" in extra else (extra, "")
    first = base.index("[assignment]")
    return base[:first] + head + base[first:] + ("\n[[before]]" + tables if tables else "")


def steps_protocol(extra: str = STEPS):
    return parse_protocol(_with_steps(extra), "steps.toml")


def run_to_end(session, answers=None):
    """Drives ``session`` to its end: every video watched (twice), the forms answered with ``answers``."""
    answers = answers or {"screen": {"background": "no"}, "about": {"age": 30, "sex": "female"},
                          "tlx": {"effort": "5", "hours": 7}}
    while not session.finished:
        run_to_end_one(session, answers, plays=2)


def run_to_end_one(session, answers=None, plays: int = 1):
    """One step of ``run_to_end`` (by default: the video played once, the forms before the task answered)."""
    answers = answers or {"screen": {"background": "no"}, "about": {"age": 30, "sex": "male"}}
    step = session.current_step()
    if step.kind == "video":
        session.finish_video(True, plays)
    elif step.kind in ("eligibility", "demographics", "questionnaire"):
        session.submit_answers(answers[step.study_step.id])
    elif step.kind == "practice":
        session.finish_practice(1.0)
    elif step.kind == "demonstration":
        session.submit_demonstration(scripted_action(step))
    elif step.kind == "episode_end":
        session.finish_episode()
    else:
        session.advance()


__all__ = ["FOLLOWUP_SESSION", "SHORT_PROTOCOL", "STEPS", "VIDEO", "_with_steps", "act", "click_primary",
           "demonstrations", "followup_protocol", "load_protocol", "run", "run_all", "run_to_end", "run_to_end_one",
           "scripted_action", "short_protocol", "steps_protocol", "ONLINE", "PROLIFIC", "online_protocol"]


#: A follow-up session a week (to two weeks) after SHORT_PROTOCOL's main session: retention of
#: skill A and transfer to skill B, with its own questionnaire.
FOLLOWUP_SESSION = """
[[sessions]]
id = "followup-1w"
welcome = "Welcome back."
instructions = "As last time."
thank_you = "Thank you, that was the last session."

[sessions.window]
earliest = "7d"
latest = "14d"
too_early = "refuse"
too_late = "{late}"
too_early_text = "Too early: come back on {{opens}}."

[[sessions.phases]]
id = "F1"
skill = "uarm-point"
episodes = 1
instructions = "Retention."

[[sessions.phases]]
id = "F2"
skill = "uarm-line"
episodes = 1
instructions = "Transfer."

[[sessions.after]]
id = "followup_tlx"
kind = "questionnaire"

[[sessions.after.items]]
id = "effort"
kind = "likert"
prompt = "How hard did you work?"
levels = ["1", "2", "3", "4", "5"]
"""


def followup_protocol(late: str = "refuse"):
    """SHORT_PROTOCOL with FOLLOWUP_SESSION (too late: ``late``, "refuse" or "flag")."""
    return parse_protocol(SHORT_PROTOCOL + FOLLOWUP_SESSION.replace("{late}", late).replace("{{", "{")
                          .replace("}}", "}"), "short-followup.toml")


def run_all(session) -> None:
    """Drives ``session`` to its end, answering every question with its first option."""
    while not session.finished:
        step = session.current_step()
        if step.kind in ("questionnaire", "demographics", "eligibility"):
            session.submit_answers({item.id: item.choices[0] for item in step.study_step.items})
        else:
            run(session, stop_after=1)


# -- a participant through the study app's widgets (tests/study/test_app.py, test_rolled_out_once.py) ---

def click_primary(app):
    """Clicks the page's one primary button (a consent page also offers "I do not agree")."""
    from ipywidgets import Button

    found, pending = [], list(app.body.children)
    while pending:
        widget = pending.pop()
        if isinstance(widget, Button) and widget.button_style == "primary":
            found.append(widget)
        pending += list(getattr(widget, "children", ()))
    assert len(found) == 1, found
    found[0].click()


def act(app):
    """One participant action through the widgets, as the buttons and the canvas would do it."""
    step = app.session.current_step()
    if step.kind in ("welcome", "consent", "instructions", "phase_intro"):
        click_primary(app)
    elif step.kind == "practice":
        # The practice cannot be skipped before its time (a cold first run may have used it up).
        assert app._practice_done.disabled or time.monotonic() - app._practice_started >= step.duration_s
        app._practice_done.disabled = False
        app._practice_done.click()
    elif step.kind in ("demonstration", "episode_end"):
        if app.episode.phase == "guidance":
            app.episode.next()
        else:
            app.episode.demonstrate(SKILLS[step.skill].target_actions(step.state[None])[0] + 0.3)
    elif step.kind == "reproduction":
        app._continue.click()


# -- an online protocol: SHORT_PROTOCOL with Prolific's [online] table (test_online.py, test_privacy.py) --

PROLIFIC = "https://app.prolific.com/submissions/complete?cc={code}"
ONLINE = f"""
[online]
identify = "prolific"
[online.completion.completed]
url = "{PROLIFIC}"
code = "C1MPL3T3"
[online.completion.screened_out]
url = "{PROLIFIC}"
code = "SCR33N"
[online.completion.declined]
url = "{PROLIFIC}"
code = "D3CL1N3D"
[online.completion.withdrawn]
url = "https://example.org/left?code={{code}}&x=1"
code = "W1THDR4WN"
"""


def online_protocol(text=ONLINE):
    return parse_protocol(SHORT_PROTOCOL + text, "online.toml")


#: Answers to the forms of the shipped paper-like protocols (industrial-sim, paper-so101), by step id.
PAPER_FORM_ANSWERS = {"eligibility": {"robotics_background": "no"}, "demographics": {"age": 30, "sex": "female"},
                      "questionnaire": {"difficulty": "easy", "comments": ""}}


class LearningTeacher:
    """A scripted participant whose arrows stray from the skill's own by a seeded relative noise that
    shrinks by ``learning`` after every optimal arrow they are shown (the target group's guidance).
    ``skills``: where the steps' skills are found (a protocol's own, for an arm it names); ``floor``:
    the noise's absolute part, per action component."""

    def __init__(self, seed: int, noise: float = 0.6, learning: float = 0.93, skills=None, floor: float = 0.05):
        self.rng = np.random.default_rng(seed)
        self.noise, self.learning = noise, learning
        self.skills, self.floor = SKILLS if skills is None else skills, floor

    def act(self, step) -> np.ndarray:
        target = self.skills[step.skill].target_actions(step.state[None])[0]
        return target + self.rng.normal(0.0, self.noise * (self.floor + np.abs(target)), size=target.shape)

    def run(self, session) -> None:
        while not session.finished:
            step = session.current_step()
            if step.kind in PAPER_FORM_ANSWERS:
                session.submit_answers(PAPER_FORM_ANSWERS[step.kind])
            elif step.kind == "practice":
                session.finish_practice(duration_s=120.0)
            elif step.kind == "demonstration":
                feedback = session.submit_demonstration(self.act(step), {"time_to_first_input_s": 1.0,
                                                                         "drawing_duration_s": 2.0}, index=step.index)
                if feedback.optimal is not None:
                    self.noise *= self.learning
            elif step.kind == "episode_end":
                session.finish_episode()
            else:
                session.advance()


def scripted_study(root, protocol: str, participants: int, learning: float = 0.93):
    """A study folder of a shipped protocol under ``root`` with ``participants`` scripted learning teachers,
    alternately of the target and the control group, each run to the end; the folder."""
    folder = StudyFolder.create(root / "study", load_protocol(protocol))
    for number in range(participants):
        session = Session.start(folder, f"P{number + 1:02d}", group=("target", "control")[number % 2])
        LearningTeacher(seed=number, learning=learning).run(session)
        assert session.completed
        session.close()
    return folder
