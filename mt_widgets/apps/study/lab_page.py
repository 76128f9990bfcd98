"""The lab's study page: the experimenter's panel behind a code, and a participant's reload resumes them.

``notebooks/study_sim.ipynb`` shows this page. Without the right parameters in its address it
asks for the experimenter's code (``$MT_WIDGETS_EXPERIMENTER_CODE``; ``scripts/serve-study.sh``
makes one up and prints it when none is set) and only then builds the ``StudyApp`` with its
panel. When a participant starts, the page's address gets the participant, the protocol, the
log folder and a key (an HMAC of the three under the experimenter's code), so a reload (F5, a
crash of the tab) opens a new kernel that resumes that participant straight away: the
participant's page comes back, never the panel, and nothing else is built in that kernel.
A changed address fails the key and shows the code prompt again.
"""

from __future__ import annotations

import hashlib
import hmac
import html
import os

from ipywidgets import HTML, Button, Layout, Password, VBox

from mt_widgets.study import LogError, ParticipantIdError, ProtocolError, Session, StudyFolder, load_protocol

from .app import StudyApp
from .navigation import set_address_query
from .online import parse_query
from .participant import ParticipantView

#: Environment variable holding the experimenter's code.
EXPERIMENTER_CODE_VARIABLE = "MT_WIDGETS_EXPERIMENTER_CODE"
#: Wrong codes a page accepts before it stops asking (a reload asks again).
MAX_ATTEMPTS = 5


def resume_key(code: str, protocol: str, log_folder: str, participant: str) -> str:
    """The key in a participant's address: only the experimenter's code makes it."""
    message = "\n".join((protocol, log_folder, participant)).encode()
    return hmac.new(code.encode(), message, hashlib.sha256).hexdigest()[:32]


class LabStudyPage(VBox):
    """The lab's page (see the module docstring).

    Args:
        protocol, log_folder, theme: as for ``StudyApp`` (the panel's first values).
        query: the page's query string (``voila.utils.get_query_string()``), or a mapping.
        experimenter_code: the code (default ``$MT_WIDGETS_EXPERIMENTER_CODE``); empty: the
            panel cannot be opened.

    Attributes:
        app: the ``StudyApp`` once the experimenter opened the panel, else None.
        view: the participant's ``ParticipantView`` when the page resumed one, else None.
    """

    def __init__(self, protocol: str = "paper-sim", log_folder=None, query="", theme=None,
                 experimenter_code: str | None = None):
        super().__init__()
        self._protocol, self._log_folder, self._theme = protocol, log_folder, theme
        self._code = (os.environ.get(EXPERIMENTER_CODE_VARIABLE, "") if experimenter_code is None
                      else experimenter_code).strip()
        self.app: StudyApp | None = None
        self.view: ParticipantView | None = None
        self._attempts = 0
        if not self._resume_from_address(parse_query(query)):
            self._ask_for_code()

    @property
    def session(self) -> Session | None:
        if self.view is not None:
            return self.view.session
        return self.app.session if self.app is not None else None

    # -- a participant's reload -------------------------------------------------------------------------
    def _resume_from_address(self, query: dict) -> bool:
        names = ("participant", "protocol", "folder", "key")
        given = {name: (query.get(name) or [""])[0] for name in names}
        if not all(given.values()) or not self._code:
            return False
        expected = resume_key(self._code, given["protocol"], given["folder"], given["participant"])
        if not hmac.compare_digest(expected, given["key"]):
            return False
        self.view = ParticipantView(self._theme)
        try:
            study = StudyFolder.create(given["folder"], load_protocol(given["protocol"]))
            session = Session.resume(study, given["participant"])
        except (LogError, ParticipantIdError, ProtocolError, FileNotFoundError, ValueError) as error:
            # Nothing to resume (they withdrew, the folder is gone): the experimenter is needed.
            self.children = [HTML(f"<div role='alert' style='max-width:760px;font-size:1.1em'><b>Please call the "
                                  f"experimenter.</b><br><small>{html.escape(str(error))}</small></div>")]
            return True
        self.children = [self.view]
        self.view.begin(session)
        return True

    # -- the experimenter ---------------------------------------------------------------------------------
    def _ask_for_code(self) -> None:
        self.code_field = Password(description="Code", placeholder="the experimenter's code",
                                   layout=Layout(width="320px"))
        self.open_button = Button(description="Open the experimenter panel", button_style="primary",
                                  layout=Layout(width="auto"))
        self.message = HTML("" if self._code else
                            f"<small>No experimenter code is set on this server: set {EXPERIMENTER_CODE_VARIABLE} "
                            f"(scripts/serve-study.sh makes one up and prints it).</small>")
        self.open_button.on_click(lambda _: self.unlock(self.code_field.value))
        self.children = [HTML("<h3 style='margin:4px 0'>Study page</h3><p>The experimenter opens this page with "
                              "their code.</p>"), self.code_field, self.open_button, self.message]

    def unlock(self, code: str) -> bool:
        """Opens the experimenter panel if ``code`` is the experimenter's; returns whether it did."""
        if self.app is not None:
            return True
        if self._attempts >= MAX_ATTEMPTS or not self._code:
            return False
        if not isinstance(code, str) or not hmac.compare_digest(code.strip().encode(), self._code.encode()):
            self._attempts += 1
            left = MAX_ATTEMPTS - self._attempts
            self.message.value = (f"<div role='alert' style='color:#b00020'>That is not the experimenter's code. "
                                  f"{'Try again.' if left else 'Reload the page to try again.'}</div>")
            self.open_button.disabled = left == 0
            return False
        self.app = StudyApp(self._protocol, self._log_folder, theme=self._theme, on_begin=self._participant_began)
        for widget in (self.code_field, self.open_button, self.message):
            widget.close()
        self.children = [self.app]
        return True

    def _participant_began(self, session: Session) -> None:
        if session.folder is None:  # a lesson: nothing to resume on a reload
            return
        protocol = self.app.experimenter.protocol.value.strip()
        folder = str(session.folder.folder)
        parameters = {"participant": session.participant, "protocol": protocol, "folder": folder,
                      "key": resume_key(self._code, protocol, folder, session.participant)}
        self.app.children = [*self.app.children, set_address_query(parameters)]
