"""A study episode on the participant's page: the protocol's instructions, the teaching widget,
the guidance arrow named where the protocol gives guidance, then the reproduction and Continue."""

from __future__ import annotations

from ipywidgets import HTML

from mt_widgets.core import TeachingEpisode
from mt_widgets.core.guidance import guidance_parts
from mt_widgets.widgets import EpisodeWidget, stop_animations

from .controls import Choice, enable_after
from .texts import guidance_arrow_words


def build_episode(protocol, theme, skill, states, guidance: bool, index: int, total: int, on_demonstration=None,
                  on_finished=None, guidance_modality: str = "none") -> EpisodeWidget:
    """The blinded teaching widget of a study episode (or a practice round).

    ``skill``: a skill key (with ``states``), or the session's ``TeachingEpisode`` (``states``
    None), so the episode the participant teaches is the one the log records. Blinding: no
    group word on the canvas ("target" names a group), and neither the skill's formula (the
    answer), the target skill's ghost, nor the teaching error and the distance to the goal,
    none of which the paper's participants saw. Any arm: the widget draws the plant as its
    drawing says (in 3-D for the UR5), with the same blinding.
    """
    shown = skill if isinstance(skill, TeachingEpisode) else protocol.skill(skill)
    own = dict(lam=protocol.lam, duration=protocol.reproduction_duration_s, query_states=states) \
        if states is not None else {}
    return EpisodeWidget(shown, guidance=guidance, guidance_modality=guidance_modality, theme=theme,
                         ghost=False, target_label="goal", **own, show_description=False, show_outcome=False,
                         episode_index=index, episodes_total=total, on_demonstration=on_demonstration,
                         on_finished=on_finished, title="")


class EpisodeStep:
    """One study episode in ``view`` (a ``ParticipantView``), from its first demonstration to the
    reproduction's Continue. The same object serves the episode's demonstration, episode-end
    and reproduction steps (``key``: (phase index, episode))."""

    def __init__(self, view, step):
        self.view = view
        self.key = (step.phase_index, step.episode)
        protocol = view.session.protocol
        self.continue_button = Choice().button("Continue", view.advance)
        self.continue_button.layout.display = "none"
        self.reproduction_text = HTML()
        # The session's own phases: a follow-up session's are not the protocol's first session's.
        plan = view.session.plan
        view.heading.value = (f"<h3 style='margin:4px 0'>Part {step.phase_index + 1} of {len(plan.phases)}, "
                              f"round {step.episode} of {step.n_episodes}</h3>")
        self.instructions = instructions = HTML(view.text(plan.phase(step.phase).instructions, step.skill))
        # The session's episode: one TeachingEpisode (one SVD, one rollout) per study episode,
        # which the widget demonstrates into and the session then records.
        self.widget = view.prepare_episode(build_episode(
            protocol, view.theme, step.teaching_episode, None, step.guidance, step.episode - 1, step.n_episodes,
            self._on_demonstration, None, step.guidance_modality))
        self.widget.on_finished(self._on_finished)
        # The guidance arrow is named where it appears, for the groups that see it (the others
        # never get this text): a mark on the canvas nothing explains is a puzzle, not guidance.
        self.guidance_note = HTML()
        arrows, _ = guidance_parts(step.guidance_modality)
        if step.guidance and arrows:
            self.widget.observe(self._on_phase, names="phase")
        view.episode = self.widget
        view.body.children = [instructions, self.widget]
        # Beside the canvas the reproduction plays in: what to do next is in view.
        self.widget.next_actions.children = [self.guidance_note, self.reproduction_text, self.continue_button]
        # Resuming: the session's episode already holds the logged demonstrations and the widget
        # shows them; if all are given it finished at once, and the end is logged here if the
        # log does not hold it yet (on_finished was called before this step could listen).
        if self.widget.phase == "finished":
            self._on_finished(self.widget.result)

    def _on_phase(self, change) -> None:
        self.guidance_note.value = guidance_arrow_words(self.view.theme) if change["new"] == "guidance" else ""

    def _on_demonstration(self, record) -> None:
        session = self.view.session

        def submit():
            # The widget's own record: logged, then kept by the session's episode (that object).
            session.submit_demonstration(record, index=record.index)
        # Re-raised after stopping the page: the episode then neither counts the demonstration
        # nor shows guidance for it.
        self.view.safely(submit, reraise=True)

    def _on_finished(self, result) -> None:
        def finish():
            session = self.view.session
            if session.current_step().kind == "episode_end":
                # The episode the participant saw is the one logged: its one reproduction
                # (already played) is what the log describes.
                session.finish_episode()
            self.show_reproduction_controls()
        self.view.safely(finish)

    def show_reproduction_controls(self) -> None:
        view = self.view
        self.guidance_note.value = ""
        self.reproduction_text.value = view.text(view.session.protocol.texts["reproduction"],
                                                 view.session.current_step().skill)
        self.continue_button.layout.display = None
        trajectory = self.widget.result.trajectory if self.widget.result else None
        enable_after(self.continue_button, 0.0 if trajectory is None else float(trajectory.times[-1]))

    def stop(self) -> None:
        stop_animations(self.widget)
