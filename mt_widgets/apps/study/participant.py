"""The participant's view: a thin dispatcher from the session's current step to its step view.

It shows only the protocol's texts (the same for every group), the teaching widgets, and the
guidance where the protocol gives it to the participant's group, in the protocol's modality.
It holds no experimenter control and nothing about other participants, so a page built from it
alone (the online page, a reloaded lab page) exposes nothing else, not even through its
widgets' state. Every page carries "Withdraw from the study" (with a confirmation) until the
session is over. Every button acts once (``controls.Choice``): a double click never runs a
step twice.

Any error in a participant step (the log cannot be written, the session refuses a call) stops
the page with a call for the experimenter, and the episode does not count a demonstration the
log refused. A step that could not be saved (the study folder's disk is full, a quota, an I/O
error: ``NotSavedError``) holds the participant instead: the page says so and offers "Try again",
which continues from the log's last saved step in this same kernel once there is room
(docs/guide/faults.md).
"""

from __future__ import annotations

import html
import logging
from collections.abc import Callable

import numpy as np
from ipywidgets import HTML, Button, HBox, Layout, VBox

from mt_widgets.study import NotSavedError, Session
from mt_widgets.study.log import ContinuedElsewhereError
from mt_widgets.widgets import EpisodeWidget, retire

from .controls import Choice
from .episode_step import EpisodeStep, build_episode
from .forms import QuestionForm
from .practice import PracticeStep
from .texts import paragraphs, protocol_text
from .video import VideoStep

_log = logging.getLogger(__name__)

#: The screens of the timeline that are a text and one button (two for consent).
_SCREEN_BUTTONS = {"welcome": "Continue", "consent": "I agree", "phase_intro": "Start"}


class ParticipantView(VBox):
    """The participant's page for one session.

    Args:
        theme: the widgets' theme (None: the colour-blind-safe default).
        practice_seed: seed of the practice states (practice is not part of the results).
        prepare_episode: ``callback(episode) -> episode`` for every episode built (the uArm app
            wires each to the arm); default: shown as it is.
        on_end: ``callback(session)`` once the session is over (completed, declined, screened
            out or withdrawn), after its last screen is shown: the online page sends the
            participant on to the completion URL.

    ``begin(session)`` shows the session's current step; ``show_step`` after every action.
    """

    def __init__(self, theme=None, practice_seed: int = 12345,
                 prepare_episode: Callable[[EpisodeWidget], EpisodeWidget] | None = None,
                 on_end: Callable[[Session], None] | None = None):
        super().__init__(layout=Layout(padding="4px"))
        self.theme = theme
        self.session: Session | None = None
        #: The error that stopped the participant flow, or None (see ``stop_for_experimenter``).
        self.stopped_by: BaseException | None = None
        #: The error of the step that could not be saved while the page holds the participant
        #: (``hold_unsaved``), or None.
        self.held_by: NotSavedError | None = None
        self._retried = False  # "Try again" was pressed and no step has been saved since
        self.episode = None
        self.video: VideoStep | None = None
        self.form: QuestionForm | None = None
        self.practice: PracticeStep | None = None
        self._episode_step: EpisodeStep | None = None
        self._practice_seed = np.random.SeedSequence(practice_seed)
        self._prepare_episode = prepare_episode
        self._on_end = on_end
        self._ended_reported = False
        self.heading = HTML()
        # Wide enough for an episode's canvas and its side column side by side (widgets/episode.py).
        self.body = VBox(layout=Layout(max_width="1280px"))
        self.withdraw_button = Button(description="Withdraw from the study", icon="sign-out",
                                      layout=Layout(width="auto", margin="24px 0 0 0", align_self="flex-start"))
        self.withdraw_button.on_click(self._withdraw_pressed)
        self.withdraw_box = VBox([self.withdraw_button])
        self.children = [self.heading, self.body, self.withdraw_box]
        # What leaves the body or the withdraw box leaves the page for good (a screen's text and
        # buttons, a form, a video, an episode's instructions, the practice's buttons): closed, or a
        # one-hour protocol leaves nine widgets open per phase screen (tests/study/test_long_session.py).
        self.body.observe(self._retire_left, names="children")
        self.withdraw_box.observe(self._retire_left, names="children")

    def begin(self, session: Session) -> None:
        self.session = session
        self.show_step()

    # -- building blocks the step views use ---------------------------------------------------------------
    def text(self, text: str, skill: str | None) -> str:
        return protocol_text(self.session.protocol, self.theme, text, skill)

    def build_episode(self, skill, states, guidance: bool, index: int, total: int, **options) -> EpisodeWidget:
        return self.prepare_episode(build_episode(self.session.protocol, self.theme, skill, states, guidance,
                                                  index, total, **options))

    def prepare_episode(self, episode: EpisodeWidget) -> EpisodeWidget:
        return episode if self._prepare_episode is None else self._prepare_episode(episode)

    def retire_replaced(self, episode) -> None:
        """``episode`` (an episode or practice canvas this page showed) has been replaced: it leaves
        the page for good.

        A replay still playing must not hold up what comes next, and its widgets close once the
        browser has played what it was sent (``widgets/animation.py``'s ``retire``): kept open, a
        session of twelve episodes held about 1,760 widgets in the kernel and in the browser.
        Called once the replacement is on the page, so nothing the page shows is closed.
        """
        if episode is not None and episode is not self.episode:
            retire(episode, keep=self)

    def _retire_left(self, change) -> None:
        staying = {id(child) for child in change["new"]}
        for child in change["old"]:
            if id(child) in staying or child is self.withdraw_button:  # it comes back after "No, continue"
                continue
            if isinstance(child, EpisodeWidget):
                continue  # a canvas view: ``retire_replaced`` closes it once its replacement is drawn
            # Only what the screen shows (its children, layouts and styles), never what its
            # attributes reach: a walk of those could reach parts the page still shows.
            retire(child, keep=self, shown_only=True)

    def safely(self, action, reraise: bool = False) -> None:
        """Runs a participant action; any error stops the participant flow (``stop_for_experimenter``).

        Args:
            action: what a button or a widget callback does (log, then show).
            reraise: re-raise the error after stopping, for a widget callback whose widget must
                not move on (a demonstration that is not on disk is neither counted nor shown
                guidance).
        """
        if self.stopped_by is not None or self.held_by is not None:
            if reraise:
                raise RuntimeError("the participant flow is stopped (the experimenter was called) or held (a step "
                                   "could not be saved); nothing more is recorded in this page") \
                    from (self.stopped_by or self.held_by)
            return
        try:
            action()
            self._retried = False
        except NotSavedError as error:
            if self.session is not None and self.session.folder is not None:
                self.hold_unsaved(error)
            else:
                self.stop_for_experimenter(error)
            if reraise:
                raise
        except Exception as error:  # noqa: BLE001 - any error: what is shown may not be on disk
            self.stop_for_experimenter(error)
            if reraise:
                raise

    def hold_unsaved(self, error: NotSavedError) -> None:
        """Holds the participant at a step that could not be saved, saying so, with "Try again".

        Nothing of the step is in the log (``ParticipantLog.append`` takes back what a failed write
        left), and what the page showed before it is saved. The session is closed; "Try again"
        continues the participant from the log (``Session.resume``) in this kernel, once the
        study folder has room again: the step is asked for again, as after a reload.
        """
        _log.error("a step could not be saved; the participant is held", exc_info=(type(error), error,
                                                                                   error.__traceback__))
        again = self.held_by is not None or self._retried
        self.held_by = error
        self._halt()
        still = "It still could not be saved. " if again else ""
        self.body.children = [HTML(
            f"<div role='alert' class='mt-not-saved' style='color:#b00020;font-size:1.2em;max-width:760px'>"
            f"<b>Your last step could not be saved.</b><br>{still}Please stay on this page and tell the experimenter. "
            f"Everything before this step is saved. Press <i>Try again</i> in a minute: you continue from the last "
            f"saved step, so this step may be asked of you again."
            f"<br><small>For the experimenter: the study folder could not store it ({html.escape(str(error))}). "
            f"Free space there, then press Try again; nothing needs restarting.</small></div>"),
            Choice().button("Try again", self._try_again)]

    def _try_again(self) -> None:
        held = self.session
        try:
            session = Session.resume(held.folder, held.participant, session=held.plan.id)
        except NotSavedError as error:
            self.hold_unsaved(error)
            return
        except Exception as error:  # noqa: BLE001 - as any step's error: the experimenter is called
            self.held_by = None
            self.stop_for_experimenter(error)
            return
        self.held_by = None
        self._episode_step = None
        self._retried = True
        self.begin(session)

    def _halt(self) -> None:
        """No further step: the timer off, the log closed (all it holds stays), and a page that offers
        nothing that would do nothing: no heading, no Withdraw."""
        self._cancel_timer()
        if self.session is not None:
            try:
                self.session.close()
            except OSError:
                pass
        self.heading.value = ""
        self.withdraw_box.layout.display = "none"
        self.withdraw_box.children = []

    def stop_for_experimenter(self, error: BaseException) -> None:
        """Stops the participant flow and asks for the experimenter.

        Whatever error a step raised, going on could show the participant something that is
        not on disk, or leave the view and the session out of step. Everything logged so far
        stays; the log is closed, and a reload continues the participant.
        """
        _log.error("participant flow stopped", exc_info=(type(error), error, error.__traceback__))
        self.stopped_by = error
        self._halt()
        if isinstance(error, ContinuedElsewhereError):
            # The same participant's page opened again (a second tab, another device): that page
            # goes on from the log; this one must only say so (online there is no experimenter).
            self.body.children = [HTML(
                "<div role='alert' class='mt-continued-elsewhere' style='font-size:1.2em;max-width:760px'>"
                "<b>This study is open in another tab or window.</b><br>It goes on there, from where you were: "
                "please continue in that tab and close this one. Everything you did so far is saved; nothing "
                "from this tab was recorded after the other one opened.</div>")]
            return
        self.body.children = [HTML(
            f"<div role='alert' style='color:#b00020;font-size:1.2em;max-width:760px'><b>Please call the "
            f"experimenter.</b><br><small>For the experimenter: the study stopped here; everything recorded so far "
            f"is saved. Reloading the page continues where it stopped."
            f"<br>{html.escape(type(error).__name__)}: {html.escape(str(error))}</small></div>")]

    # -- the dispatcher --------------------------------------------------------------------------------------
    def show_step(self) -> None:
        """Shows the session's current step (nothing once the flow is stopped)."""
        if self.stopped_by is not None or self.held_by is not None:
            return
        step = self.session.current_step()
        shown = self.episode
        self._cancel_timer()
        in_episode = step.kind in ("demonstration", "episode_end", "reproduction")
        if not in_episode:
            self._episode_step = None
        # Withdrawing is offered on every page of a logged session until it is over.
        self.withdraw_box.layout.display = "none" if self.session.finished or self.session.folder is None else None
        self._reset_withdraw()
        if step.kind == "ended":
            self.episode = None
            self.heading.value = ""
            self.body.children = [HTML(paragraphs(step.text))]
        elif step.study_step is not None:
            self.episode = None
            self._show_study_step(step)
        elif step.kind in ("welcome", "consent", "instructions", "phase_intro", "thank_you"):
            self.episode = None
            self._show_screen(step)
        elif step.kind == "practice":
            self.practice = PracticeStep(self, step, self._practice_seed)
        elif in_episode:
            key = (step.phase_index, step.episode)
            if self._episode_step is None or self._episode_step.key != key:
                self._episode_step = EpisodeStep(self, step)
            if self.session.current_step().kind == "reproduction":
                self._episode_step.show_reproduction_controls()
        self.retire_replaced(shown)
        if self.session.finished and not self._ended_reported:
            self._ended_reported = True
            if self._on_end is not None:
                self._on_end(self.session)

    def _show_screen(self, step) -> None:
        protocol = self.session.protocol
        self.heading.value = (f"<h3 style='margin:4px 0'>Part {step.phase_index + 1} of "
                              f"{len(self.session.plan.phases)}</h3>"
                              if step.kind == "phase_intro" else "")
        labels = dict(_SCREEN_BUTTONS, instructions="Start the practice" if protocol.practice.duration_s > 0
                      else "Start")
        children = [HTML(self.text(step.text, step.skill))]
        if step.kind == "thank_you" and step.reentry_code:
            window = (step.next_session or {}).get("window", "")
            children.append(HTML(
                f"<p style='max-width:760px;font-size:1.1em'>To come back for the next part of the study"
                f"{' (' + html.escape(window) + ')' if window else ''}, keep this code: "
                f"<b class='mt-reentry-code'>{html.escape(step.reentry_code)}</b></p>"))
        choice = Choice()
        if step.kind in labels:
            children.append(choice.button(labels[step.kind], self.advance))
        if step.kind == "consent":
            # Both answers are offered alike, one under the other.
            children.append(choice.button("I do not agree", self._decline, ""))
        self.body.children = children

    def _show_study_step(self, step) -> None:
        study_step = step.study_step
        self.heading.value = (f"<h3 style='margin:4px 0'>{html.escape(study_step.title)}</h3>"
                              if study_step.title else "")
        text = HTML(paragraphs(step.text)) if step.text.strip() else HTML()
        choice = Choice()
        if study_step.kind in ("text", "information"):
            self.body.children = [text, choice.button("Continue", self.advance)]
        elif study_step.kind == "consent":
            self.body.children = [text, choice.button(study_step.agree_label, self.advance),
                                  choice.button(study_step.decline_label, self._decline, "")]
        elif study_step.kind == "video":
            self.video = VideoStep(study_step, self._finish_video)
            self.body.children = [text, self.video]
        else:
            self.form = QuestionForm(study_step, lambda answers: self.safely(lambda: self._submit(answers)))
            self.body.children = [text, self.form]

    # -- actions ---------------------------------------------------------------------------------------------
    def advance(self) -> None:
        self.safely(lambda: (self.session.advance(), self.show_step()))

    def _decline(self) -> None:
        self.safely(lambda: (self.session.decline_consent(), self.show_step()))

    def _finish_video(self, watched_to_end: bool, plays: int) -> None:
        self.safely(lambda: (self.session.finish_video(watched_to_end, plays), self.show_step()))

    def _submit(self, answers: dict) -> None:
        self.session.submit_answers(answers)
        self.show_step()

    def finish_practice(self) -> None:
        practice = self.practice
        self.safely(lambda: (self.session.finish_practice(duration_s=practice.elapsed_s), self.show_step()))

    def _cancel_timer(self) -> None:
        if self.practice is not None:
            self.practice.cancel()

    # -- withdrawing ------------------------------------------------------------------------------------------
    def _reset_withdraw(self) -> None:
        self.withdraw_button.disabled = False
        self.withdraw_box.children = [self.withdraw_button]

    def _withdraw_pressed(self, _=None) -> None:
        if self.withdraw_button.disabled or self.stopped_by is not None or self.session is None \
                or self.session.finished:
            return
        self.withdraw_button.disabled = True
        self.safely(self._ask_withdraw)

    def _ask_withdraw(self) -> None:
        """First press: ask to confirm (a withdrawal cannot be undone)."""
        choice = Choice()
        confirm = choice.button("Yes, withdraw", self.withdraw, "danger")
        back = choice.button("No, continue the study", self._reset_withdraw, "")
        self.withdraw_box.children = [HTML(
            "<p style='max-width:760px'>Do you want to withdraw from the study? Nothing more will be recorded, and "
            "what you have given so far will be left out of the results. This cannot be undone.</p>"),
            HBox([confirm, back], layout=Layout(flex_flow="row wrap"))]

    def withdraw(self, reason: str = "") -> None:
        """The participant withdraws (the session logs it and applies the protocol's data policy).

        Once the session is over (a second "Yes, withdraw", a page already at its end) this
        does nothing: the page already shows the session's last screen.
        """
        if self.session is None or self.session.finished or self.stopped_by is not None:
            return
        self._cancel_timer()
        self.safely(lambda: (self.session.withdraw(reason), self.show_step()))
