"""The participant app: the study runner's session engine shown with the teaching widgets.

``StudyApp`` starts with an experimenter panel (protocol, log folder, participant ID, group
assignment, new / resume / unlogged lesson). Once a participant starts, the panel is removed
from the page and only the participant view remains: welcome and consent, practice, the
protocol's phases, the reproduction after every episode, and a thank-you screen.

The steps around the task come from the protocol too (``mt_widgets.study.steps``): an
instruction video (watched to the end before Continue when the protocol asks, with a replay),
the information sheet, consent with "I agree" and "I do not agree", an eligibility screener,
demographics and questionnaires. Every participant page carries "Withdraw from the study"
(with a confirmation); a withdrawal is logged and the page ends.

Single-blind: the participant view shows only the protocol's texts (the same for every
group), the teaching widgets, and the guidance where the protocol gives it to the
participant's group, in the protocol's modality (the paper's: the arrows only, no words).
The group, the teaching error and the target skill's own motion are
never shown (the paper's participants saw the robot's reproduction only).

Every demonstration is handed to ``Session.submit_demonstration`` inside the widget's
confirmation callback, so it is on disk before the view moves on; a reload (a new kernel)
resumes at the first missing demonstration with the experimenter's "Resume". Any error in a
participant step (the log cannot be written, the session refuses a call) stops the page with a
call for the experimenter, and the episode does not count a demonstration the log refused.
"""

from __future__ import annotations

import asyncio
import base64
import html
import logging
import math
import os
import time
from pathlib import Path

import numpy as np
from ipywidgets import HTML, Button, Combobox, Dropdown, HBox, Layout, RadioButtons, Text, Textarea, VBox

from mt_widgets.core import TeachingEpisode
from mt_widgets.study import (
    BUILTIN_PROTOCOLS,
    LogError,
    LogFolderError,
    ParticipantIdError,
    ProtocolError,
    Session,
    StudyFolder,
    load_protocol,
)
from mt_widgets.widgets import EpisodeWidget, TeachingCanvas, get_theme, stop_animations
from mt_widgets.widgets.theme import fill_words

_log = logging.getLogger(__name__)

#: Environment variable naming the default log folder (the notebook and the experimenter's
#: field start from it).
LOG_FOLDER_VARIABLE = "MT_WIDGETS_STUDY_LOGS"


def default_log_folder(protocol_name: str = "paper-sim") -> Path:
    """$MT_WIDGETS_STUDY_LOGS, else ~/mt-widgets-studies/<protocol name>."""
    configured = os.environ.get(LOG_FOLDER_VARIABLE, "").strip()
    if configured:
        return Path(configured).expanduser()
    return Path.home() / "mt-widgets-studies" / protocol_name


def _kernel_loop():
    """The kernel's running asyncio loop (timers in Voila and Lab), or None in a plain script."""
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        pass
    try:
        loop = asyncio.get_event_loop_policy().get_event_loop()
    except RuntimeError:
        return None
    return loop if loop.is_running() else None


#: The group dropdown's value for "randomised": a Dropdown whose value is None shows nothing.
RANDOMISED = "randomised"


def _paragraphs(text: str) -> str:
    """Protocol text (paragraphs separated by blank lines) as escaped HTML paragraphs."""
    blocks = [" ".join(block.split()) for block in text.strip().split("\n\n") if block.strip()]
    return "".join(f"<p style='max-width:760px;font-size:1.1em;line-height:1.45'>{html.escape(b)}</p>"
                   for b in blocks)


class ExperimenterPanel(VBox):
    """What the experimenter sets before a participant starts; removed from the page after."""

    def __init__(self, protocol: str, log_folder, group_options):
        self.protocol = Combobox(value=protocol, options=sorted(BUILTIN_PROTOCOLS), description="Protocol",
                                 placeholder="paper-sim, paper-uarm or a .toml/.json file",
                                 layout=Layout(width="520px"), ensure_option=False)
        self.log_folder = Text(value=str(log_folder), description="Log folder", layout=Layout(width="520px"))
        self.participant = Text(value="", description="Participant", placeholder="pseudonymous code, e.g. P07",
                                layout=Layout(width="320px"))
        self.group = Dropdown(options=group_options, value=RANDOMISED, description="Group",
                              layout=Layout(width="320px"))
        wide = dict(width="auto")
        self.start_button = Button(description="Start new participant", button_style="primary", icon="play",
                                   layout=Layout(**wide))
        self.resume_button = Button(description="Resume participant", icon="repeat", layout=Layout(**wide))
        self.lesson_button = Button(description="Lesson (not logged)", icon="graduation-cap", layout=Layout(**wide))
        self.list_button = Button(description="List participants", icon="list", layout=Layout(**wide))
        self.message = HTML()
        self.listing = HTML()
        super().__init__([
            HTML("<h3 style='margin:4px 0'>Experimenter</h3><small>Only you see this panel: it disappears when "
                 "the participant starts. For the next participant, reload the page.</small>"),
            self.protocol, self.log_folder, self.participant, self.group,
            HBox([self.start_button, self.resume_button, self.lesson_button, self.list_button]),
            self.message, self.listing,
        ], layout=Layout(border="2px dashed #888", padding="8px", max_width="820px"))

    def say(self, text: str, error: bool = False) -> None:
        colour = "#b00020" if error else "#1b5e20"
        self.message.value = f"<div style='color:{colour};max-width:760px'>{html.escape(text)}</div>"


class StudyApp(VBox):
    """The study page: an experimenter panel, then the participant view.

    Args:
        protocol: a shipped protocol name ("paper-sim", "paper-uarm") or a protocol file path.
        log_folder: where the study folder goes (default ``default_log_folder``).
        theme: the widgets' theme (None: the colour-blind-safe default; "paper" for the paper's).
        practice_seed: seed of the practice states (practice is not part of the results).

    Code can drive it as the buttons do: ``app.start_participant("P07")``,
    ``app.resume_participant("P07")``, ``app.start_lesson("control")``; ``app.session`` is the
    ``Session`` and ``app.participant_view`` what the participant sees.
    """

    def __init__(self, protocol: str = "paper-sim", log_folder=None, theme=None, practice_seed: int = 12345):
        self.theme = theme
        self.session: Session | None = None
        #: The error that stopped the participant flow, or None (see ``stop_for_experimenter``).
        self.stopped_by: BaseException | None = None
        self.episode: EpisodeWidget | None = None
        self._episode_key = None
        self._practice_seed = np.random.SeedSequence(practice_seed)
        self._practice_round = 0
        self._timer = None
        self.heading = HTML()
        # Wide enough for an episode's canvas and its side column side by side (widgets/episode.py).
        self.body = VBox(layout=Layout(max_width="1280px"))
        self.withdraw_button = Button(description="Withdraw from the study", icon="sign-out",
                                      layout=Layout(width="auto", margin="24px 0 0 0", align_self="flex-start"))
        self.withdraw_button.on_click(lambda _: self._safely(self._ask_withdraw))
        self.withdraw_box = VBox([self.withdraw_button])
        self.participant_view = VBox([self.heading, self.body, self.withdraw_box], layout=Layout(padding="4px"))
        groups = [("randomised (block randomisation)", RANDOMISED)]
        self.experimenter = ExperimenterPanel(protocol, log_folder if log_folder is not None
                                              else default_log_folder(protocol if protocol in BUILTIN_PROTOCOLS
                                                                      else "custom"), groups)
        self.experimenter.protocol.observe(self._on_protocol, names="value")
        self.experimenter.start_button.on_click(lambda _: self._guarded(self._start_from_panel))
        self.experimenter.resume_button.on_click(lambda _: self._guarded(self._resume_from_panel))
        self.experimenter.lesson_button.on_click(lambda _: self._guarded(self._lesson_from_panel))
        self.experimenter.list_button.on_click(lambda _: self._guarded(self._list_participants))
        self._on_protocol({"new": protocol})
        super().__init__([self.experimenter])

    # -- experimenter actions --------------------------------------------------------------------------
    def _guarded(self, action) -> None:
        try:
            action()
        except (ProtocolError, ParticipantIdError, LogFolderError, LogError, FileNotFoundError, ValueError) as error:
            self.experimenter.say(str(error), error=True)

    def _on_protocol(self, change) -> None:
        try:
            protocol = load_protocol(change["new"])
        except (ProtocolError, FileNotFoundError, ValueError) as error:
            self.experimenter.say(str(error), error=True)
            return
        self.experimenter.group.options = [("randomised (block randomisation)", RANDOMISED)] + \
                                          [(g, g) for g in protocol.groups]
        self.experimenter.group.value = RANDOMISED
        self.experimenter.say(f"Protocol {protocol.name!r}: {len(protocol.phases)} phases, "
                              f"{protocol.n_episodes} episodes.")

    def _study(self) -> StudyFolder:
        protocol = load_protocol(self.experimenter.protocol.value.strip())
        # Refuses an unwritable folder (and one running another protocol) before anyone starts.
        return StudyFolder.create(self.experimenter.log_folder.value.strip(), protocol)

    def _chosen_group(self) -> str | None:
        choice = self.experimenter.group.value
        return None if choice == RANDOMISED else choice

    def _start_from_panel(self) -> None:
        session = self.start_participant(self.experimenter.participant.value, group=self._chosen_group())
        # The panel leaves the page while the participant works (single blind); what the start did
        # waits in it for the experimenter, beside the participant list.
        how = "by block randomisation" if self._chosen_group() is None else "as chosen"
        self.experimenter.say(f"{session.participant}: assigned to the {session.group} group {how}.")

    def _resume_from_panel(self) -> None:
        self.resume_participant(self.experimenter.participant.value)

    def _lesson_from_panel(self) -> None:
        self.start_lesson(self._chosen_group())

    def _list_participants(self) -> None:
        study = self._study()
        rows = "".join(f"<tr><td>{html.escape(r['participant'])}</td><td>{r['group']}</td><td>{r['method']}</td>"
                       f"<td>{html.escape(r['state'])}</td><td>{r['events']}</td></tr>"
                       for r in study.status())
        counts = study.group_status()
        columns = list(next(iter(counts.values())))
        summary = "".join(f"<tr><td>{html.escape(group)}</td>" + "".join(f"<td>{row[c]}</td>" for c in columns)
                          + "</tr>" for group, row in counts.items())
        self.experimenter.listing.value = (f"<small>{html.escape(str(study.folder))}</small><table><tr><th>ID</th>"
                                           f"<th>group</th><th>assigned</th><th>state</th><th>events</th></tr>"
                                           f"{rows}</table><table><tr><th>group</th>"
                                           + "".join(f"<th>{c}</th>" for c in columns) + f"</tr>{summary}</table>")

    def start_participant(self, participant_id: str, group: str | None = None) -> Session:
        """Enrols a new participant (group None: randomised) and shows them the study."""
        session = Session.start(self._study(), participant_id, group=group)
        self._begin(session)
        return session

    def resume_participant(self, participant_id: str) -> Session:
        """Continues an enrolled participant at their first missing step."""
        session = Session.resume(self._study(), participant_id)
        self._begin(session)
        return session

    def start_lesson(self, group: str | None = None) -> Session:
        """Runs the protocol unlogged, e.g. as a guided lesson (group None: the first group)."""
        session = Session.lesson(load_protocol(self.experimenter.protocol.value.strip()), group=group)
        self._begin(session)
        return session

    def _begin(self, session: Session) -> None:
        self.session = session
        # The experimenter panel leaves the page: from here on the participant sees only their view.
        self.children = [self.participant_view]
        self.show_step()

    # -- the participant view ------------------------------------------------------------------------------
    def _button(self, description: str, on_click, style: str = "primary") -> Button:
        # align_self: a button keeps its own width in the page's column instead of spanning it.
        button = Button(description=description, button_style=style,
                        layout=Layout(width="auto", min_width="160px", align_self="flex-start"))

        def clicked(_):
            button.disabled = True  # one click, one step: a double click cannot skip a screen
            self._safely(on_click)

        button.on_click(clicked)
        return button

    def _safely(self, action, reraise: bool = False) -> None:
        """Runs a participant action; any error stops the participant flow (``stop_for_experimenter``).

        Args:
            action: what a button or a widget callback does (log, then show).
            reraise: re-raise the error after stopping, for a widget callback whose widget must
                not move on (a demonstration that is not on disk is neither counted nor shown
                guidance).
        """
        if self.stopped_by is not None:
            if reraise:
                raise RuntimeError("the participant flow is stopped (the experimenter was called); nothing more "
                                   "is recorded in this page") from self.stopped_by
            return
        try:
            action()
        except Exception as error:  # noqa: BLE001 - any error: what is shown may not be on disk
            self.stop_for_experimenter(error)
            if reraise:
                raise

    def stop_for_experimenter(self, error: BaseException) -> None:
        """Stops the participant flow and asks for the experimenter.

        Whatever error a step raised (the log could not be written, or the session refused the
        call), going on could show the participant something that is not on disk, or leave the
        view and the session out of step. Everything logged so far stays; the log is closed,
        and the experimenter continues with a reload and "Resume participant".
        """
        _log.error("participant flow stopped", exc_info=(type(error), error, error.__traceback__))
        self.stopped_by = error
        self._cancel_timer()
        participant = self.session.participant if self.session is not None else ""
        if self.session is not None:
            try:
                self.session.close()
            except OSError:
                pass
        self.heading.value = ""
        self.body.children = [HTML(
            f"<div style='color:#b00020;font-size:1.2em;max-width:760px'><b>Please call the experimenter.</b>"
            f"<br><small>For the experimenter: the study stopped here; everything recorded so far is saved. "
            f"Reload the page and resume participant {html.escape(participant)} to continue."
            f"<br>{html.escape(type(error).__name__)}: {html.escape(str(error))}</small></div>")]

    def show_step(self) -> None:
        """Shows the session's current step (nothing once the flow is stopped)."""
        if self.stopped_by is not None:
            return
        step = self.session.current_step()
        protocol = self.session.protocol
        self._cancel_timer()
        if isinstance(self.episode, EpisodeWidget) and step.kind not in ("demonstration", "episode_end",
                                                                          "reproduction"):
            # The episode leaves the page: a replay still playing must not hold up what comes next.
            stop_animations(self.episode)
        # Withdrawing is offered on every page of a logged session until it is over.
        self.withdraw_box.layout.display = "none" if self.session.finished or self.session.folder is None else None
        self._reset_withdraw()
        if step.kind == "ended":
            self.episode = None
            self.heading.value = ""
            self.body.children = [HTML(_paragraphs(step.text))]
        elif step.study_step is not None:
            self.episode = None
            self._show_study_step(step)
        elif step.kind in ("welcome", "consent", "instructions", "phase_intro", "thank_you"):
            self.episode = None
            if step.kind == "phase_intro":
                self.heading.value = (f"<h3 style='margin:4px 0'>Part {step.phase_index + 1} of "
                                      f"{len(protocol.phases)}</h3>")
            else:
                self.heading.value = ""
            labels = {"welcome": "Continue", "consent": "I agree", "instructions": "Start the practice"
                      if protocol.practice.duration_s > 0 else "Start", "phase_intro": "Start"}
            children = [HTML(self._text(step.text, step.skill))]
            if step.kind in labels:
                children.append(self._button(labels[step.kind], self._advance))
            if step.kind == "consent":
                # Both answers are offered alike, one under the other.
                children.append(self._button("I do not agree", self._decline, ""))
            self.body.children = children
        elif step.kind == "practice":
            self._show_practice(step)
        elif step.kind in ("demonstration", "episode_end", "reproduction"):
            self._show_episode(step)

    def _advance(self) -> None:
        self.session.advance()
        self.show_step()

    def _text(self, text: str, skill: str | None) -> str:
        """Protocol text as HTML, its "{goal}" in the words of what the canvas draws (the skill's
        target in this theme's colours); texts outside a phase name the first phase's target."""
        protocol = self.session.protocol
        target = protocol.skills[skill or protocol.phases[0].skill].target
        goal = get_theme(self.theme).target_words(target, "goal") if target is not None else "the goal"
        return _paragraphs(fill_words(text, goal=goal))

    def _decline(self) -> None:
        self.session.decline_consent()
        self.show_step()

    # -- withdrawing ------------------------------------------------------------------------------------------
    def _reset_withdraw(self) -> None:
        self.withdraw_button.disabled = False
        self.withdraw_box.children = [self.withdraw_button]

    def _ask_withdraw(self) -> None:
        """First click: ask to confirm (a withdrawal cannot be undone)."""
        confirm = self._button("Yes, withdraw", self.withdraw, "danger")
        back = self._button("No, continue the study", self._reset_withdraw, "")
        self.withdraw_box.children = [HTML(
            "<p style='max-width:760px'>Do you want to withdraw from the study? Nothing more will be recorded, and "
            "what you have given so far will be left out of the results. This cannot be undone.</p>"),
            HBox([confirm, back])]

    def withdraw(self, reason: str = "") -> None:
        """The participant withdraws (the session logs it and applies the protocol's data policy)."""
        self._cancel_timer()
        self.session.withdraw(reason)
        self.show_step()

    # -- steps around the task ---------------------------------------------------------------------------------
    def _show_study_step(self, step) -> None:
        study_step = step.study_step
        self.heading.value = (f"<h3 style='margin:4px 0'>{html.escape(study_step.title)}</h3>"
                              if study_step.title else "")
        text = HTML(_paragraphs(step.text)) if step.text.strip() else HTML()
        if study_step.kind in ("text", "information"):
            self.body.children = [text, self._button("Continue", self._advance)]
        elif study_step.kind == "consent":
            self.body.children = [text, self._button(study_step.agree_label, self._advance),
                                  self._button(study_step.decline_label, self._decline, "")]
        elif study_step.kind == "video":
            self.video = VideoStep(study_step, self._finish_video)
            self.body.children = [text, self.video]
        else:
            self.form = QuestionForm(study_step, lambda answers: self._safely(lambda: self._submit(answers)))
            self.body.children = [text, self.form]

    def _finish_video(self, watched_to_end: bool, plays: int) -> None:
        self._safely(lambda: (self.session.finish_video(watched_to_end, plays), self.show_step()))

    def _submit(self, answers: dict) -> None:
        try:
            checked = self.session.current_step().study_step.check_answers(answers)
        except ValueError as error:  # the participant's input, not a fault: say what to fix
            self.form.say(str(error))
            return
        self.session.submit_answers(checked)
        self.show_step()

    # -- practice --------------------------------------------------------------------------------------------
    def _show_practice(self, step) -> None:
        self.heading.value = "<h3 style='margin:4px 0'>Practice</h3>"
        self._practice_started = time.monotonic()
        self._practice_left = HTML()
        self._practice_done = self._button("Continue to the study", self._finish_practice)
        self._practice_done.disabled = True
        self._practice_again = self._button("Practise again", lambda: self._new_practice_round(step), "")
        self._practice_again.layout.display = "none"
        self._practice_text = HTML(self._text(step.text, step.skill))
        self._new_practice_round(step)
        self._tick(step.duration_s)

    def _new_practice_round(self, step) -> None:
        seed = self._practice_seed.spawn(1)[0]
        self._practice_round += 1
        if self.episode is not None:
            stop_animations(self.episode)
        skill = self.session.protocol.skill(step.skill)
        states = skill.query_states(seed=seed)
        if step.practice_reproduction:
            episode = self._episode_widget(step.skill, states, guidance=False, index=0, total=1)
            episode.on_finished(lambda _: self._practice_round_over())
        else:
            # Drawing only: nothing is learnt or played back; after the last state a new round.
            episode = TeachingCanvas(skill, states, theme=self.theme, auto_advance=True, target_label="goal")
            episode.observe(lambda change: self._practice_drawn(step, change), names="state_index")
        self.episode = episode
        self._practice_again.layout.display = "none"
        self._practice_again.disabled = False
        self.body.children = [self._practice_text, self._practice_left,
                              HBox([self._practice_done, self._practice_again]), episode]

    def _practice_drawn(self, step, change) -> None:
        if change["new"] >= len(change["owner"].query_states):
            self._new_practice_round(step)

    def _practice_round_over(self) -> None:
        self._practice_again.layout.display = None
        result = self.episode.result if self.episode is not None else None
        self._enable_after(self._practice_again, float(result.trajectory.times[-1]) if result else 0.0)

    def _tick(self, duration_s: float) -> None:
        left = duration_s - (time.monotonic() - self._practice_started)
        if left <= 0:
            self._practice_left.value = "<b>Practice time is over.</b> Continue when you are ready."
            self._practice_done.disabled = False
            return
        shown = int(math.ceil(left))  # never "0:00" while time is left
        self._practice_left.value = f"<b>Practice time left: {shown // 60}:{shown % 60:02d}</b>"
        loop = _kernel_loop()
        if loop is None:  # no running event loop (a script): the button stays for code to press
            return
        self._timer = loop.call_later(min(1.0, left), self._tick, duration_s)

    def _cancel_timer(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _finish_practice(self) -> None:
        self.session.finish_practice(duration_s=time.monotonic() - self._practice_started)
        self.show_step()

    # -- episodes --------------------------------------------------------------------------------------------
    def _episode_widget(self, skill, states, guidance: bool, index: int, total: int,
                        on_demonstration=None, on_finished=None, guidance_modality: str = "none") -> EpisodeWidget:
        """``skill``: a skill key (with ``states``), or the session's ``TeachingEpisode`` (``states``
        None), so the episode the participant teaches is the one the log records."""
        protocol = self.session.protocol
        # ghost=False: the target skill's own motion would show the participant the answer.
        # Blinding: no group word on the canvas ("target" names a group), and neither the skill's
        # formula (the answer), the target skill's ghost, nor the teaching error and distance to the
        # goal, none of which the paper's participants saw.
        shown = skill if isinstance(skill, TeachingEpisode) else protocol.skill(skill)
        own = dict(lam=protocol.lam, duration=protocol.reproduction_duration_s, query_states=states) \
            if states is not None else {}
        episode = EpisodeWidget(shown, guidance=guidance, guidance_modality=guidance_modality, theme=self.theme,
                                ghost=False, target_label="goal", **own,
                                show_description=False, show_outcome=False,
                                episode_index=index, episodes_total=total, on_demonstration=on_demonstration,
                                on_finished=on_finished, title="")
        return self.prepare_episode(episode)

    def prepare_episode(self, episode: EpisodeWidget) -> EpisodeWidget:
        """Called with every episode (practice included) once it is built; returns the one to show.

        The hook for apps built on this one: the uArm app wires each episode to the arm here.
        The default shows the episode as it is.
        """
        return episode

    def _show_episode(self, step) -> None:
        key = (step.phase_index, step.episode)
        if self.episode is None or self._episode_key != key:
            if self.episode is not None:
                stop_animations(self.episode)
            self._episode_key = key
            self._continue = self._button("Continue", self._advance)
            self._continue.layout.display = "none"
            self._reproduction_text = HTML()
            self.heading.value = (f"<h3 style='margin:4px 0'>Part {step.phase_index + 1} of "
                                  f"{len(self.session.protocol.phases)}, round {step.episode} of "
                                  f"{step.n_episodes}</h3>")
            instructions = HTML(self._text(self.session.protocol.phase(step.phase).instructions, step.skill))
            # The session's episode: one TeachingEpisode (one SVD, one rollout) per study episode,
            # which the widget demonstrates into and the session then records.
            self.episode = self._episode_widget(step.teaching_episode, None, step.guidance,
                                                step.episode - 1, step.n_episodes, self._on_demonstration,
                                                self._on_episode_finished, step.guidance_modality)
            self.body.children = [instructions, self.episode]
            # Beside the canvas the reproduction plays in: what to do next is in view.
            self.episode.next_actions.children = [self._reproduction_text, self._continue]
            if len(step.actions):
                # Resuming: the given demonstrations are restored; if all are given the widget
                # finishes at once, and _on_episode_finished logs the end if it is not logged yet.
                self.episode.restore(np.asarray(step.actions))
        if self.session.current_step().kind == "reproduction":
            self._show_reproduction_controls()

    def _on_demonstration(self, record) -> None:
        def submit():
            self.session.submit_demonstration(
                record.action, {"time_to_first_input_s": record.time_to_first_input_s,
                                "drawing_duration_s": record.drawing_duration_s, "method": record.method,
                                "redraws": record.redraws}, index=record.index)
        # Re-raised after stopping the page: the episode then neither counts the demonstration
        # nor shows guidance for it.
        self._safely(submit, reraise=True)

    def _on_episode_finished(self, result) -> None:
        def finish():
            if self.session.current_step().kind == "episode_end":
                # The episode the participant saw is the one logged: its one reproduction
                # (already played) is what the log describes.
                self.session.finish_episode(result.episode)
            self._show_reproduction_controls()
        self._safely(finish)

    def _show_reproduction_controls(self) -> None:
        self._reproduction_text.value = self._text(self.session.protocol.texts["reproduction"],
                                                   self.session.current_step().skill)
        self._continue.layout.display = None
        trajectory = self.episode.result.trajectory if self.episode is not None and self.episode.result else None
        self._enable_after(self._continue, 0.0 if trajectory is None else float(trajectory.times[-1]))

    def _enable_after(self, button: Button, seconds: float) -> None:
        """Enables ``button`` once the reproduction has played (``seconds`` plus a margin).

        The participant watches the whole reproduction (it is the study's feedback), and the
        browser's canvas manager plays an animation's frames in order, so a new episode's
        drawing is never queued behind the old one's frames while its view is replaced.
        """
        button.disabled = True
        loop = _kernel_loop()
        if loop is None or seconds <= 0:  # code driving the app (no kernel event loop): at once
            button.disabled = False
            return
        loop.call_later(seconds + 0.75, lambda: setattr(button, "disabled", False))


class VideoStep(VBox):
    """An instruction video with a replay; Continue once it has played to the end (if required).

    The video plays in the browser; its "ended" event clicks a hidden button, which is how the
    kernel learns it was watched to the end (ipywidgets' Video widget reports no playback). A
    local file is sent inline (a data URL), so it plays wherever the page is served from.

    Args:
        study_step: the protocol's video ``StudyStep``.
        on_done: ``callback(watched_to_end, plays)`` when the participant continues.
    """

    def __init__(self, study_step, on_done):
        self.study_step = study_step
        self.watched_to_end = False
        self.plays = 0
        self._on_done = on_done
        self.ended_button = Button(description="video ended", layout=Layout(display="none"))
        self.ended_button.add_class("mt-video-ended")
        self.ended_button.on_click(lambda _: self.mark_ended())
        self.played_button = Button(description="video played", layout=Layout(display="none"))
        self.played_button.add_class("mt-video-played")
        self.played_button.on_click(lambda _: self.mark_played())
        source = study_step.video if study_step.video_is_url else _data_url(study_step.video)
        # The handlers look for the hidden buttons next to the player (in this step's box).
        find = "this.closest('.mt-video-step').querySelector('.{} button, button.{}').click()"
        self.player = HTML(
            f"<video class='mt-video' src='{html.escape(source, quote=True)}' controls preload='auto' "
            f"style='max-width:720px;width:100%' onplay=\"{find.format('mt-video-played', 'mt-video-played')}\" "
            f"onended=\"{find.format('mt-video-ended', 'mt-video-ended')}\"></video>"
            f"<div><button class='mt-video-replay' onclick=\"const v=this.closest('.mt-video-step')"
            f".querySelector('video'); v.currentTime=0; v.play();\">Play again from the start</button></div>")
        self.continue_button = Button(description="Continue", button_style="primary",
                                      disabled=study_step.require_watched,
                                      layout=Layout(width="auto", min_width="160px", align_self="flex-start"))
        self.continue_button.on_click(lambda _: self._continue())
        self.note = HTML("<small>Continue becomes available once the video has played to the end.</small>"
                         if study_step.require_watched else "")
        super().__init__([self.player, self.continue_button, self.note, self.ended_button, self.played_button])
        self.add_class("mt-video-step")

    def mark_played(self) -> None:
        self.plays += 1

    def mark_ended(self) -> None:
        self.watched_to_end = True
        self.plays = max(self.plays, 1)
        self.continue_button.disabled = False
        self.note.value = ""

    def _continue(self) -> None:
        self.continue_button.disabled = True
        self._on_done(self.watched_to_end, self.plays)


def _data_url(path: str) -> str:
    data = Path(path).read_bytes()
    kind = {".webm": "video/webm", ".mp4": "video/mp4", ".ogv": "video/ogg", ".ogg": "video/ogg"}.get(
        Path(path).suffix.lower(), "application/octet-stream")
    return f"data:{kind};base64," + base64.b64encode(data).decode()


class QuestionForm(VBox):
    """The items of an eligibility, demographics or questionnaire step, and a Continue button.

    Likert and choice items are radio buttons (nothing chosen at first), numbers and short
    answers text fields. ``answers()`` reads them; ``on_submit(answers)`` runs on Continue, and
    ``say`` shows what to fix.
    """

    def __init__(self, study_step, on_submit):
        self.study_step = study_step
        self.fields = {}
        rows = []
        for item in study_step.items:
            label = HTML(f"<b>{html.escape(item.prompt)}</b>" + ("" if item.required else " <small>(optional)"
                                                                                           "</small>"))
            if item.kind in ("likert", "choice"):
                field = RadioButtons(options=list(item.choices), value=None, layout=Layout(width="auto"))
            elif item.kind == "number":
                field = Text(placeholder="a number" + (f" ({item.units})" if item.units else ""),
                             layout=Layout(width="200px"))
            else:
                field = Textarea(layout=Layout(width="520px", height="80px"))
            field.add_class(f"mt-item-{item.id}")
            self.fields[item.id] = field
            rows.append(VBox([label, field], layout=Layout(margin="6px 0")))
        self.message = HTML()
        self.continue_button = Button(description="Continue", button_style="primary",
                                      layout=Layout(width="auto", min_width="160px", align_self="flex-start"))
        self.continue_button.on_click(lambda _: on_submit(self.answers()))
        super().__init__(rows + [self.message, self.continue_button])

    def answers(self) -> dict:
        found = {}
        for item in self.study_step.items:
            value = self.fields[item.id].value
            found[item.id] = value if value not in ("",) else None
        return found

    def say(self, text: str) -> None:
        self.message.value = f"<div style='color:#b00020'>{html.escape(text)}</div>"


def participant_texts(widget) -> list[str]:
    """Every piece of text a widget tree can show (values, descriptions, labels, options, tooltips).

    Used to check blinding: walk what the participant view holds and read what it would render.
    """
    texts: list[str] = []
    seen = set()

    def walk(node):
        if id(node) in seen:
            return
        seen.add(id(node))
        for name in ("value", "description", "placeholder", "tooltip", "button_text"):
            value = getattr(node, name, None)
            if isinstance(value, str):
                texts.append(value)
        for name in ("options", "_options_labels", "tooltips"):
            value = getattr(node, name, None)
            if isinstance(value, (list, tuple)):
                texts.extend(str(v) for v in value)
        for child in getattr(node, "children", ()) or ():
            walk(child)

    walk(widget)
    return texts


__all__ = ["ExperimenterPanel", "LOG_FOLDER_VARIABLE", "QuestionForm", "StudyApp", "VideoStep", "default_log_folder",
           "participant_texts"]
