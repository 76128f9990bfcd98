"""An instruction video with a replay; Continue once it has really played to the end (if required)."""

from __future__ import annotations

import base64
import html
from pathlib import Path

from ipywidgets import HTML, Button, Layout, VBox

from .controls import Choice

#: The share of the video's length that must have played (the browser's ``video.played``
#: ranges) for an "ended" to count as watched: scrubbing to the last seconds does not.
WATCHED_FRACTION = 0.95


class VideoStep(VBox):
    """The video plays in the browser; ipywidgets' Video widget reports no playback, so the
    player's own events click hidden buttons: "played" on every start, and on "ended" either
    "ended" (the ``played`` ranges cover at least ``WATCHED_FRACTION`` of the duration) or
    "skipped" (it reached the end by scrubbing). A local file is sent inline (a data URL), so it
    plays wherever the page is served from.

    Args:
        study_step: the protocol's video ``StudyStep``.
        on_done: ``callback(watched_to_end, plays)`` when the participant continues (once).
    """

    def __init__(self, study_step, on_done):
        self.study_step = study_step
        self.watched_to_end = False
        self.plays = 0
        self._on_done = on_done
        self.ended_button = self._hidden("video ended", "mt-video-ended", self.mark_ended)
        self.skipped_button = self._hidden("video skipped", "mt-video-skipped", self.mark_skipped)
        self.played_button = self._hidden("video played", "mt-video-played", self.mark_played)
        source = study_step.video if study_step.video_is_url else _data_url(study_step.video)
        # The handlers look for the hidden buttons next to the player (in this step's box).
        click = "this.closest('.mt-video-step').querySelector('.{0} button, button.{0}').click()"
        # played: the ranges the browser really played (seeking skips them), in seconds.
        ended = ("(function(v){let s=0;for(let i=0;i<v.played.length;i++){s+=v.played.end(i)-v.played.start(i);}"
                 f"const whole=isFinite(v.duration)&&v.duration>0&&s>={WATCHED_FRACTION}*v.duration;"
                 "v.closest('.mt-video-step').querySelector(whole?'.mt-video-ended button, button.mt-video-ended'"
                 ":'.mt-video-skipped button, button.mt-video-skipped').click();})(this)")
        self.player = HTML(
            f"<video class='mt-video' src='{html.escape(source, quote=True)}' controls preload='auto' "
            f"style='max-width:720px;width:100%' onplay=\"{click.format('mt-video-played')}\" "
            f"onended=\"{ended}\"></video>"
            f"<div><button class='mt-video-replay' onclick=\"const v=this.closest('.mt-video-step')"
            f".querySelector('video'); v.currentTime=0; v.play();\">Play again from the start</button></div>")
        self._choice = Choice()
        self.continue_button = self._choice.button("Continue", self._continue)
        self.continue_button.disabled = study_step.require_watched
        self.note = HTML("<small>Continue becomes available once the video has played to the end.</small>"
                         if study_step.require_watched else "")
        super().__init__([self.player, self.continue_button, self.note, self.ended_button, self.skipped_button,
                          self.played_button])
        self.add_class("mt-video-step")

    @staticmethod
    def _hidden(description: str, css_class: str, action) -> Button:
        button = Button(description=description, layout=Layout(display="none"))
        button.add_class(css_class)
        button.on_click(lambda _: action())
        return button

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
