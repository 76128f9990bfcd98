"""Teaching effort: demonstrations and episodes done against the budget."""

from __future__ import annotations

from ipywidgets import HTML, HBox, IntProgress, VBox
from traitlets import Int, observe

from mt_widgets.core.validation import as_count

from .looks import plain, shared_layout


class EffortProgress(VBox):
    """Two progress bars: demonstrations in this episode, and episodes in the phase.

    Args:
        demonstration_budget: Demonstrations per episode (S: the fewest states that teach Theta exactly).
        episode_budget: Episodes in the phase (e.g. 8 in the paper's phase 3).
        demonstrations_done: Demonstrations confirmed so far in this episode.
        episodes_done: Episodes finished before this one.
    """

    demonstrations_done = Int(0)
    episodes_done = Int(0)

    def __init__(self, demonstration_budget: int, episode_budget: int = 1, demonstrations_done: int = 0,
                 episodes_done: int = 0):
        self.demonstration_budget = as_count("demonstration_budget", demonstration_budget)
        self.episode_budget = as_count("episode_budget", episode_budget)
        bar = shared_layout(width="260px")   # shared layouts and styles: looks.py
        self.demonstration_bar = plain(IntProgress, min=0, max=self.demonstration_budget, layout=bar,
                                             description="Demos", bar_style="info")
        self.episode_bar = plain(IntProgress, min=0, max=self.episode_budget, layout=bar, description="Episodes")
        self.label = plain(HTML)
        # The bars side by side (wrapping on a narrow page): the episode's canvas stays high on the page.
        super().__init__([plain(HBox, [self.demonstration_bar, self.episode_bar],
                                layout=shared_layout(flex_flow="row wrap")),
                          self.label])
        self.demonstrations_done = as_count("demonstrations_done", demonstrations_done, minimum=0)
        self.episodes_done = as_count("episodes_done", episodes_done, minimum=0)
        self._refresh()

    @observe("demonstrations_done", "episodes_done")
    def _on_change(self, change) -> None:
        limit = self.demonstration_budget if change["name"] == "demonstrations_done" else self.episode_budget
        if not 0 <= change["new"] <= limit:
            raise ValueError(f"{change['name']}: expected 0..{limit}, got {change['new']}")
        self._refresh()

    def _refresh(self) -> None:
        if not hasattr(self, "label"):
            return
        self.demonstration_bar.value = self.demonstrations_done
        self.episode_bar.value = self.episodes_done
        self.label.value = (f"<small>Teaching effort: {self.demonstrations_done} of {self.demonstration_budget} "
                            f"demonstrations in this episode; {self.episodes_done} of {self.episode_budget} "
                            f"episodes done.</small>")
