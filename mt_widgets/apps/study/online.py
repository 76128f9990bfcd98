"""The online participant page: enrolled from the URL, resumed on a reload, ended on a completion URL.

A participant of a pool such as Prolific opens the page with their ID in the URL
(``?PROLIFIC_PID=...&STUDY_ID=...&SESSION_ID=...``, or ``?participant=...``, as the protocol's
``[online]`` table says; ``mt_widgets.study.online``). The page then:

- refuses an unusable ID with a message meant for the participant, and writes nothing;
- turns a new arrival away in words while the server is at its configured capacity
  (``capacity.py``: participants taking part, free memory), and writes nothing (both decided by
  ``arrival.py``, which the shipped server also runs before any kernel starts);
- calls ``Session.arrive``: a new ID is enrolled and randomised by the protocol's rule (no
  group can be chosen from a URL), an enrolled one resumes where their log stops (a reload is
  a new kernel, and the same URL), a returning one gets their next session in its window;
- shows only the ``ParticipantView`` (no experimenter panel is ever built, and nothing about
  other participants is read into a widget);
- when the session ends (completed, screened out, declined, withdrawn), shows its last screen
  and the outcome's code, and sends the page to the outcome's completion URL.

Voila passes the request's query string to the kernel (``voila.utils.get_query_string``, which
also works with preheated kernels); the notebook ``notebooks/study_online.ipynb`` hands it here.
Voila lets a page send its kernel only widget messages, never code: what the page can reach is
the widgets the kernel holds, which is why none holds anything but this participant's page.
"""

from __future__ import annotations

import html
from collections.abc import Mapping
from urllib.parse import parse_qs

from ipywidgets import HTML, VBox

from mt_widgets.study import LogError, Session, StudyFolder, load_protocol
from mt_widgets.study.online import outcome_of

from .arrival import arrival_or_refusal, return_link_html, turned_away_html
from .capacity import Capacity
from .navigation import go_to
from .participant import ParticipantView

#: Seconds the last screen stays before the page goes to the completion URL.
REDIRECT_DELAY_S = 4.0


def parse_query(query) -> dict:
    """{name: [values]} of a query string ("a=1&b=2", a leading "?" allowed) or a mapping."""
    if query is None:
        return {}
    if isinstance(query, Mapping):
        return {str(k): (list(v) if isinstance(v, (list, tuple)) else [v]) for k, v in query.items()}
    if not isinstance(query, str):
        raise TypeError(f"query: expected a query string or a mapping, got {type(query).__name__}")
    return parse_qs(query.lstrip("?"), keep_blank_values=True)


def _message(text: str, role: str = "alert") -> HTML:
    return HTML(f"<div role='{role}' style='max-width:760px;font-size:1.1em;line-height:1.45'>"
                f"{html.escape(text)}</div>")


class OnlineStudyPage(VBox):
    """The page an online participant sees.

    Args:
        protocol: a protocol with an ``[online]`` table (a shipped name or a file path).
        log_folder: the study folder.
        query: the page's query string (or a mapping of URL parameters).
        theme: the widgets' theme.
        redirect_delay_s: seconds before the page goes on to the completion URL.
        capacity: the server's ``Capacity`` (None: from the environment, ``capacity.py``); a new
            arrival while it is full gets a page saying so and when to come back.

    Attributes:
        session: the participant's ``Session`` (None when the page refused the URL).
        completion: the ``Completion`` the page sent the participant to, once the session ended.
        view: the ``ParticipantView`` (None when refused).
    """

    def __init__(self, protocol, log_folder, query, theme=None, redirect_delay_s: float = REDIRECT_DELAY_S,
                 capacity: Capacity | None = None):
        super().__init__()
        self.session: Session | None = None
        self.completion = None
        self.view: ParticipantView | None = None
        self._redirect_delay_s = redirect_delay_s
        protocol = load_protocol(protocol)
        if protocol.online is None:
            raise ValueError(f"protocol: expected a protocol with an [online] table (completion URLs and codes, "
                             f"which URL parameters identify a participant), got {protocol.name!r} without one")
        self.online = protocol.online
        capacity = Capacity.from_environment() if capacity is None else capacity
        arrival, turned = arrival_or_refusal(self.online, log_folder, parse_query(query), capacity)
        if turned is not None:
            # An unusable link, or a new arrival while the server is full: words, and nothing written.
            # (The shipped server turns them away before this kernel even starts: arrival.py.)
            self.children = [HTML(turned_away_html(turned))]
            if turned.busy:
                self.add_class("mt-study-busy")
            return
        study = StudyFolder.create(log_folder, protocol)
        try:
            session = Session.arrive(study, arrival.participant_id, parameters=arrival.parameters)
        except LogError as error:
            self.children = self._refused(study, arrival.participant_id, error)
            return
        self.session = session
        self.view = ParticipantView(theme, on_end=self._ended)
        self.children = [self.view]
        self.view.begin(session)

    def _refused(self, study, participant_id: str, error: LogError) -> list:
        """A participant the study does not continue: one who already left it goes on to their
        outcome's completion URL again; any other refusal (a session's window) says why."""
        left = study.outcomes().get(participant_id)
        if left is not None and left["outcome"] != "dropped_out":
            self.completion = self.online.completion(left["outcome"])
            return [_message("You have already left this study; nothing more will be recorded.", "status"),
                    self._goodbye()]
        words = getattr(error, "message", None) or str(error).split(": ", 1)[-1]
        return [_message(words), HTML(return_link_html(self.online.return_url))]

    def _ended(self, session: Session) -> None:
        self.completion = self.online.completion(outcome_of(session))
        self.view.children = [*self.view.children, self._goodbye()]

    def _goodbye(self) -> VBox:
        completion = self.completion
        if completion.url is None:
            # No pool to go back to (a pilot's protocol gives this ending no url): the page is the end.
            return VBox([HTML(f"<p style='max-width:760px;font-size:1.1em'>Your completion code is "
                              f"<b class='mt-completion-code'>{html.escape(completion.code)}</b>. This is the end "
                              f"of the study: keep the code if you were asked for it, then you can close this "
                              f"page.</p>")])
        link = html.escape(completion.url, quote=True)
        return VBox([
            HTML(f"<p style='max-width:760px;font-size:1.1em'>Your completion code is "
                 f"<b class='mt-completion-code'>{html.escape(completion.code)}</b>. You will be taken back to the "
                 f"study's website in a few seconds; if not, <a href='{link}' class='mt-completion-link' "
                 f"style='color:#0b57d0;text-decoration:underline'>"
                 f"continue here</a>.</p>"),
            go_to(completion.url, self._redirect_delay_s)])
