"""``StudyApp``: the experimenter's panel, then the participant's view (a lab's study page).

Code can drive it as the buttons do: ``app.start_participant("P07")``,
``app.resume_participant("P07")``, ``app.start_lesson("control")``; ``app.session`` is the
``Session`` and ``app.participant_view`` what the participant sees. Once a participant starts,
the panel is closed (its widgets leave the kernel) and only the participant view remains.
The lab page (``LabStudyPage``) builds this app only after the experimenter's code, and a
reload of a participant's page resumes the participant without it.
"""

from __future__ import annotations

import os
from pathlib import Path

from ipywidgets import VBox

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
from mt_widgets.study.study_folder import STUDY_FILE
from mt_widgets.widgets import EpisodeWidget

from .panel import RANDOMISED, ExperimenterPanel
from .participant import ParticipantView

#: Environment variable naming the default log folder (the notebook and the experimenter's
#: field start from it).
LOG_FOLDER_VARIABLE = "MT_WIDGETS_STUDY_LOGS"

#: What the panel reports instead of raising: the experimenter's input, not a fault.
_PANEL_ERRORS = (ProtocolError, ParticipantIdError, LogFolderError, LogError, FileNotFoundError, ValueError)


def default_log_folder(protocol_name: str = "paper-sim") -> Path:
    """$MT_WIDGETS_STUDY_LOGS, else ~/mt-widgets-studies/<protocol name>."""
    configured = os.environ.get(LOG_FOLDER_VARIABLE, "").strip()
    if configured:
        return Path(configured).expanduser()
    return Path.home() / "mt-widgets-studies" / protocol_name


class StudyApp(VBox):
    """The study page: an experimenter panel, then the participant view.

    Args:
        protocol: a shipped protocol name ("paper-sim", "paper-uarm") or a protocol file path.
        log_folder: where the study folder goes (default ``default_log_folder``).
        theme: the widgets' theme (None: the colour-blind-safe default; "paper" for the paper's).
        practice_seed: seed of the practice states (practice is not part of the results).
        on_begin: ``callback(session)`` when a participant's session begins (the lab page puts
            the participant in the page's address, so a reload resumes them).
    """

    def __init__(self, protocol: str = "paper-sim", log_folder=None, theme=None, practice_seed: int = 12345,
                 on_begin=None):
        self.theme = theme
        self._on_begin = on_begin
        self.participant_view = ParticipantView(theme, practice_seed, prepare_episode=self.prepare_episode)
        self.experimenter = ExperimenterPanel(protocol, log_folder if log_folder is not None
                                              else default_log_folder(protocol if protocol in BUILTIN_PROTOCOLS
                                                                      else "custom"))
        panel = self.experimenter
        panel.protocol.observe(self._on_protocol, names="value")
        panel.start_button.on_click(lambda _: self._guarded(self._start_from_panel))
        panel.resume_button.on_click(lambda _: self._guarded(self._resume_from_panel))
        panel.lesson_button.on_click(lambda _: self._guarded(self._lesson_from_panel))
        panel.list_button.on_click(lambda _: self._guarded(self._list_participants))
        self._on_protocol({"new": protocol})
        super().__init__([panel])

    # -- what the participant view holds, under the app's names -----------------------------------------
    session = property(lambda self: self.participant_view.session)
    episode = property(lambda self: self.participant_view.episode)
    stopped_by = property(lambda self: self.participant_view.stopped_by)
    heading = property(lambda self: self.participant_view.heading)
    body = property(lambda self: self.participant_view.body)
    withdraw_box = property(lambda self: self.participant_view.withdraw_box)
    withdraw_button = property(lambda self: self.participant_view.withdraw_button)
    video = property(lambda self: self.participant_view.video)
    form = property(lambda self: self.participant_view.form)
    _practice_done = property(lambda self: self.participant_view.practice.done_button)
    _practice_started = property(lambda self: self.participant_view.practice.started)
    _continue = property(lambda self: self.participant_view._episode_step.continue_button)

    def show_step(self) -> None:
        self.participant_view.show_step()

    def withdraw(self, reason: str = "") -> None:
        self.participant_view.withdraw(reason)

    def stop_for_experimenter(self, error: BaseException) -> None:
        self.participant_view.stop_for_experimenter(error)

    def prepare_episode(self, episode: EpisodeWidget) -> EpisodeWidget:
        """Called with every episode (practice included) once it is built; returns the one to show.

        The hook for apps built on this one: the uArm app wires each episode to the arm here.
        The default shows the episode as it is.
        """
        return episode

    # -- experimenter actions --------------------------------------------------------------------------
    def _guarded(self, action) -> None:
        if self.session is not None:  # a second press of Start / Resume after the participant began
            return
        try:
            action()
        except _PANEL_ERRORS as error:
            self.experimenter.say(str(error), error=True)

    def _on_protocol(self, change) -> None:
        try:
            protocol = load_protocol(change["new"])
        except (ProtocolError, FileNotFoundError, ValueError) as error:
            self.experimenter.say(str(error), error=True)
            return
        self.experimenter.show_groups(protocol.groups)
        self.experimenter.say(f"Protocol {protocol.name!r}: {len(protocol.phases)} phases, "
                              f"{protocol.n_episodes} episodes.")

    def _list_participants(self) -> None:
        """Lists the study in the panel's log folder, read as it is (a full disk, which ``_study`` refuses
        to start a participant on, is shown in the listing instead of hiding it); a folder without a
        study stays as it is (the study is made when the first participant starts, with the protocol
        chosen then)."""
        folder = Path(self.experimenter.log_folder.value.strip()).expanduser()
        if not (folder / STUDY_FILE).is_file():
            self.experimenter.listing.value = ""
            self.experimenter.say(f"No study in {folder} yet: it is made when the first participant starts.")
            return
        self.experimenter.list_study(StudyFolder(folder))

    def _study(self) -> StudyFolder:
        protocol = load_protocol(self.experimenter.protocol.value.strip())
        # Refuses an unwritable folder (and one running another protocol) before anyone starts.
        return StudyFolder.create(self.experimenter.log_folder.value.strip(), protocol)

    def _chosen_group(self) -> str | None:
        choice = self.experimenter.group.value
        return None if choice == RANDOMISED else choice

    def _start_from_panel(self) -> None:
        chosen = self._chosen_group()
        session = self.start_participant(self.experimenter.participant.value, group=chosen)
        # What the start did stays in the (closed) panel for code to read; the page no longer
        # shows it (single blind).
        how = "by block randomisation" if chosen is None else "as chosen"
        self.experimenter.say(f"{session.participant}: assigned to the {session.group} group {how}.")

    def _resume_from_panel(self) -> None:
        self.resume_participant(self.experimenter.participant.value)

    def _lesson_from_panel(self) -> None:
        self.start_lesson(self._chosen_group())

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
        # The experimenter panel leaves the page and the kernel's comms: from here on the
        # participant sees, and their page can reach, only their own view.
        self.children = [self.participant_view]
        self.experimenter.close_all()
        self.participant_view.begin(session)
        if self._on_begin is not None:
            self._on_begin(session)
