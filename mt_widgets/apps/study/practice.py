"""The practice step: free drawing for the protocol's time, a clock that survives a reload."""

from __future__ import annotations

import datetime as _dt
import math
import time

from ipywidgets import HTML, HBox

from mt_widgets.widgets import EpisodeWidget
from mt_widgets.widgets.animation import kernel_loop

from .controls import Choice, enable_after


def practice_elapsed_s(events, now: float | None = None) -> float:
    """Seconds since the practice first began in this participant's log (0 if it did not).

    A reload starts a new kernel and logs ``practice_started`` again; the clock runs from the
    first one, so the time left continues instead of starting over (the seconds the reload
    took count as practice: the log cannot tell when the old page went away).
    """
    started = [e for e in events if e.get("type") == "practice_started"]
    if not started:
        return 0.0
    first = _dt.datetime.fromisoformat(started[0]["time"].replace("Z", "+00:00")).timestamp()
    return max(0.0, (time.time() if now is None else now) - first)


class PracticeStep:
    """Shows the practice in ``view`` (a ``ParticipantView``) and runs its clock.

    Args:
        view: the participant view (its body, heading, session, episode builder).
        step: the session's practice ``Step``.
        seeds: the practice's ``SeedSequence`` (a new round spawns one).
    """

    def __init__(self, view, step, seeds):
        self.view, self.step, self.seeds = view, step, seeds
        self._timer = None
        view.heading.value = "<h3 style='margin:4px 0'>Practice</h3>"
        # Measured as the log says (monotonic within this kernel): a resumed practice continues.
        self.started = time.monotonic() - practice_elapsed_s(view.session.events)
        self.left = HTML()
        self.done_button = Choice().button("Continue to the study", view.finish_practice)
        self.done_button.disabled = True
        self.again_button = None
        self.text = HTML(view.text(step.text, step.skill))
        self.new_round()
        self.tick()

    def new_round(self) -> None:
        view = self.view
        seed = self.seeds.spawn(1)[0]
        shown = view.episode
        skill = view.session.protocol.skill(self.step.skill)
        states = skill.query_states(seed=seed)
        self.again_button = Choice().button("Practise again", lambda: view.safely(self.new_round), "")
        self.again_button.layout.display = "none"
        if self.step.practice_reproduction:
            episode = view.build_episode(self.step.skill, states, guidance=False, index=0, total=1)
            episode.on_finished(lambda _: self._round_over())
        else:
            # Drawing only (any arm): nothing is learnt or played back; once the last arrow is
            # confirmed the round is over and a new one starts.
            episode = EpisodeWidget(skill, states, guidance=False, theme=view.theme, title="", show_description=False,
                                    reproduce=False, ghost=False, target_label="goal")
            episode.observe(self._drawn, names="phase")
        view.episode = episode
        view.body.children = [self.text, self.left, HBox([self.done_button, self.again_button]), episode]
        view.retire_replaced(shown)

    def _drawn(self, change) -> None:
        if change["new"] == "finished" and change["owner"] is self.view.episode:
            self.new_round()

    def _round_over(self) -> None:
        self.again_button.layout.display = None
        result = getattr(self.view.episode, "result", None)
        enable_after(self.again_button, float(result.trajectory.times[-1]) if result else 0.0)

    @property
    def elapsed_s(self) -> float:
        return time.monotonic() - self.started

    def tick(self) -> None:
        left = self.step.duration_s - self.elapsed_s
        if left <= 0:
            self.left.value = "<b>Practice time is over.</b> Continue when you are ready."
            self.done_button.disabled = False
            return
        shown = int(math.ceil(left))  # never "0:00" while time is left
        self.left.value = f"<b role='timer'>Practice time left: {shown // 60}:{shown % 60:02d}</b>"
        loop = kernel_loop()
        if loop is None:  # no kernel event loop (a script): the button stays for code to press
            return
        self._timer = loop.call_later(min(1.0, left - math.floor(left) or 1.0), self.tick)

    def cancel(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
