"""An instruction video with a replay; Continue once it has really played to the end (if required)."""

from __future__ import annotations

import base64
from pathlib import Path

import anywidget
import traitlets
from ipywidgets import HTML, VBox

from .controls import Choice

#: The share of the video's length that must have played (the browser's ``video.played``
#: ranges) for an "ended" to count as watched: scrubbing to the last seconds does not.
WATCHED_FRACTION = 0.95


class VideoPlayer(anywidget.AnyWidget):
    """The video, played in the browser (ipywidgets' Video widget reports no playback): its front end
    (an anywidget ES module, ``video.js`` beside this file) sends ``{"event": "played"}`` on every
    start and ``{"event": "ended", "whole": bool}`` at the end, ``whole`` when the ranges the browser
    really played cover at least ``watched_fraction`` of the duration (not when it got there by
    scrubbing); a "Play again from the start" button below it."""

    _esm = Path(__file__).parent / "video.js"
    src = traitlets.Unicode("").tag(sync=True)
    watched_fraction = traitlets.Float(WATCHED_FRACTION).tag(sync=True)


class VideoStep(VBox):
    """The video plays in the browser (``VideoPlayer``); Continue once it has played to the end, if
    the protocol requires it. A local file is sent inline (a data URL), so it plays wherever the page
    is served from.

    Args:
        study_step: the protocol's video ``StudyStep``.
        on_done: ``callback(watched_to_end, plays)`` when the participant continues (once).
    """

    def __init__(self, study_step, on_done):
        self.study_step = study_step
        self.watched_to_end = False
        self.plays = 0
        self._on_done = on_done
        source = study_step.video if study_step.video_is_url else _data_url(study_step.video)
        self.player = VideoPlayer(src=source)
        self.player.on_msg(self._on_player)
        self._choice = Choice()
        self.continue_button = self._choice.button("Continue", self._continue)
        self.continue_button.disabled = study_step.require_watched
        self.note = HTML("<small>Continue becomes available once the video has played to the end.</small>"
                         if study_step.require_watched else "")
        super().__init__([self.player, self.continue_button, self.note])
        self.add_class("mt-video-step")

    def _on_player(self, _, content, buffers) -> None:
        if content.get("event") == "played":
            self.mark_played()
        elif content.get("event") == "ended" and content.get("whole") is True:
            self.mark_ended()
        elif content.get("event") == "ended":
            self.mark_skipped()

    def mark_played(self) -> None:
        self.plays += 1

    def mark_ended(self) -> None:
        self.watched_to_end = True
        self.plays = max(self.plays, 1)
        if not self._choice.made:
            self.continue_button.disabled = False
        self.note.value = ""

    def mark_skipped(self) -> None:
        if self.watched_to_end or not self.study_step.require_watched:
            return
        self.note.value = ("<small role='status'>The video was skipped ahead to its end. Please watch it all: "
                           "press \u201cPlay again from the start\u201d.</small>")

    def _continue(self) -> None:
        self._on_done(self.watched_to_end, self.plays)


def _data_url(path: str) -> str:
    data = Path(path).read_bytes()
    kind = {".webm": "video/webm", ".mp4": "video/mp4", ".ogv": "video/ogg", ".ogg": "video/ogg"}.get(
        Path(path).suffix.lower(), "application/octet-stream")
    return f"data:{kind};base64," + base64.b64encode(data).decode()
