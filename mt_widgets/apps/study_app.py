"""The participant app: the study runner's session engine shown with the teaching widgets.

``StudyApp`` starts with an experimenter panel (protocol, log folder, participant ID, group
assignment, new / resume / unlogged lesson). Once a participant starts, the panel is removed
from the page and only the participant view remains: welcome and consent, practice, the
protocol's phases, the reproduction after every episode, and a thank-you screen.

Single-blind: the participant view shows only the protocol's texts (the same for every
group), the teaching widgets, and the guidance arrows where the protocol gives them to the
participant's group. The group, the teaching error and the target skill's own motion are
never shown (the paper's participants saw the robot's reproduction only).

Every demonstration is handed to ``Session.submit_demonstration`` inside the widget's
confirmation callback, so it is on disk before the view moves on; a reload (a new kernel)
resumes at the first missing demonstration with the experimenter's "Resume". Any error in a
participant step (the log cannot be written, the session refuses a call) stops the page with a
call for the experimenter, and the episode does not count a demonstration the log refused.
"""

from __future__ import annotations

import asyncio
import html
import logging
import math
import os
import time
from pathlib import Path

import numpy as np
from ipywidgets import HTML, Button, Combobox, Dropdown, HBox, Layout, Text, VBox

from mt_widgets.core import SKILLS, running_under_test
from mt_widgets.study import (BUILTIN_PROTOCOLS, LogError, LogFolderError, ParticipantIdError, ProtocolError,
                              Session, StudyFolder, load_protocol)
from mt_widgets.widgets import EpisodeWidget, stop_animations

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
        self.group = Dropdown(options=group_options, value=None, description="Group", layout=Layout(width="320px"))
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
        self.body = VBox(layout=Layout(max_width="1000px"))
        self.participant_view = VBox([self.heading, self.body], layout=Layout(padding="4px"))
        groups = [("randomised (block randomisation)", None)]
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
        self.experimenter.group.options = [("randomised (block randomisation)", None)] + \
                                          [(g, g) for g in protocol.groups]
        self.experimenter.group.value = None
        self.experimenter.say(f"Protocol {protocol.name!r}: {len(protocol.phases)} phases, "
                              f"{protocol.n_episodes} episodes.")

    def _study(self) -> StudyFolder:
        protocol = load_protocol(self.experimenter.protocol.value.strip())
        # Refuses an unwritable folder (and one running another protocol) before anyone starts.
        return StudyFolder.create(self.experimenter.log_folder.value.strip(), protocol)

    def _start_from_panel(self) -> None:
        self.start_participant(self.experimenter.participant.value, group=self.experimenter.group.value)

    def _resume_from_panel(self) -> None:
        self.resume_participant(self.experimenter.participant.value)

    def _lesson_from_panel(self) -> None:
        self.start_lesson(self.experimenter.group.value)

    def _list_participants(self) -> None:
        study = self._study()
        rows = "".join(f"<tr><td>{html.escape(r['participant'])}</td><td>{r['group']}</td><td>{r['method']}</td>"
                       f"<td>{'finished' if r['finished'] else 'in progress'}</td><td>{r['events']}</td></tr>"
                       for r in study.status())
        self.experimenter.listing.value = (f"<small>{html.escape(str(study.folder))}</small><table><tr><th>ID</th>"
                                           f"<th>group</th><th>assigned</th><th>state</th><th>events</th></tr>"
                                           f"{rows}</table>")

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
        button = Button(description=description, button_style=style, layout=Layout(width="auto", min_width="160px"))

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
        if self.episode is not None and step.kind not in ("demonstration", "episode_end", "reproduction"):
            # The episode leaves the page: a replay still playing must not hold up what comes next.
            stop_animations(self.episode)
        if step.kind in ("welcome", "consent", "instructions", "phase_intro", "thank_you"):
            self.episode = None
            if step.kind == "phase_intro":
                self.heading.value = (f"<h3 style='margin:4px 0'>Part {step.phase_index + 1} of "
                                      f"{len(protocol.phases)}</h3>")
            else:
                self.heading.value = ""
            labels = {"welcome": "Continue", "consent": "I agree", "instructions": "Start the practice"
                      if protocol.practice.duration_s > 0 else "Start", "phase_intro": "Start"}
            children = [HTML(_paragraphs(step.text))]
            if step.kind in labels:
                children.append(self._button(labels[step.kind], self._advance))
            self.body.children = children
        elif step.kind == "practice":
            self._show_practice(step)
        elif step.kind in ("demonstration", "episode_end", "reproduction"):
            self._show_episode(step)

    def _advance(self) -> None:
        self.session.advance()
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
        self._practice_text = HTML(_paragraphs(step.text))
        self._new_practice_round(step)
        self._tick(step.duration_s)

    def _new_practice_round(self, step) -> None:
        seed = self._practice_seed.spawn(1)[0]
        self._practice_round += 1
        if self.episode is not None:
            stop_animations(self.episode)
        episode = self._episode_widget(step.skill, SKILLS[step.skill].query_states(seed=seed), guidance=False,
                                       index=0, total=1)
        episode.on_finished(lambda _: self._practice_round_over())
        self.episode = episode
        self._practice_again.layout.display = "none"
        self._practice_again.disabled = False
        self.body.children = [self._practice_text, self._practice_left,
                              HBox([self._practice_done, self._practice_again]), episode]

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
    def _episode_widget(self, skill: str, states, guidance: bool, index: int, total: int,
                        on_demonstration=None, on_finished=None) -> EpisodeWidget:
        protocol = self.session.protocol
        # ghost=False: the target skill's own motion would show the participant the answer.
        # Blinding: no group word on the canvas ("target" names a group), and neither the skill's
        # formula (the answer), the target skill's ghost, nor the teaching error and distance to the
        # goal, none of which the paper's participants saw.
        episode = EpisodeWidget(skill, query_states=states, guidance=guidance, lam=protocol.lam, theme=self.theme,
                                duration=protocol.reproduction_duration_s, ghost=False, target_label="goal",
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
            instructions = HTML(_paragraphs(self.session.protocol.phase(step.phase).instructions))
            self.episode = self._episode_widget(step.skill, step.query_states, step.guidance,
                                                step.episode - 1, step.n_episodes, self._on_demonstration,
                                                self._on_episode_finished)
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
        self._reproduction_text.value = _paragraphs(self.session.protocol.texts["reproduction"])
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


__all__ = ["ExperimenterPanel", "LOG_FOLDER_VARIABLE", "StudyApp", "default_log_folder", "participant_texts",
           "running_under_test"]
