"""The visitors' demo: one page, no code, an episode with a skill chooser and a guidance switch.

``notebooks/demo.ipynb`` shows a ``DemoPage`` and nothing else, so Voila (or Binder with
``?urlpath=voila/render/notebooks/demo.ipynb``) gives a one-click page. The page only
composes ``EpisodeWidget``, for every arm (it draws a plant in space in 3-D itself): choosing an
arm or a skill, switching guidance or asking for new states starts a fresh episode (a guidance
switch keeps the arrows given so far, on any arm); the teaching error comes from the episode's
result.

The visitor picks the arm first (``DEMO_ARMS``: the paper's planar arms, or the UR5 in 3-D); the
skill chooser then offers that arm's skills.
"""

from __future__ import annotations

from ipywidgets import HTML, Box, Button, Checkbox, HBox, ToggleButtons, ToggleButtonsStyle, VBox

from mt_widgets.arms import CHAIN_ARMS
from mt_widgets.core import SKILLS, Skill
from mt_widgets.core.validation import as_bool

from .animation import retire
from .episode import EpisodeResult, EpisodeWidget
from .looks import plain, shared_layout, shared_style

#: The four skills of the paper, as a visitor reads them on the chooser.
DEMO_SKILLS = (
    ("Arm: reach a point", "sim-point"),
    ("Arm: reach a line", "sim-line"),
    ("uArm: reach a point", "uarm-point"),
    ("uArm: reach a line", "uarm-line"),
)

#: The UR5's production-line skills (issue 31), taught in 3-D.
UR5_DEMO_SKILLS = (
    ("UR5: reach the part", "ur5-reach"),
    ("UR5: place it", "ur5-place"),
    ("UR5: follow the conveyor", "ur5-conveyor"),
)

#: The arms a visitor picks from, each with the skills the chooser then offers.
DEMO_ARMS = (
    ("Planar arms", DEMO_SKILLS),
    ("UR5 arm (3-D)", UR5_DEMO_SKILLS),
    *CHAIN_ARMS,
)

WELCOME = (
    "<h2 style='margin:2px 0'>Teach a robot by showing it what to do</h2>"
    "<div style='max-width:1100px'>At each state, press on the robot's hand and drag an arrow: the push you "
    "would give it there. After your last arrow the robot learns from them and shows what it learnt. With "
    "guidance on, you also see the best arrow after each of yours.</div>"
)


def _key_of(skill) -> str:
    return skill if isinstance(skill, str) else skill.key


def _chooser_skills(skills) -> dict[str, Skill]:
    """{key: Skill} from (label, Skill or key of SKILLS) pairs, checked."""
    chosen: dict[str, Skill] = {}
    for entry in skills:
        if not (isinstance(entry, tuple) and len(entry) == 2 and isinstance(entry[0], str)):
            raise ValueError(f"skills: expected (label, skill) pairs, got {entry!r}")
        skill = entry[1]
        if isinstance(skill, str):
            skill = SKILLS[skill]  # a KeyError naming the known skills
        if not isinstance(skill, Skill):
            raise TypeError(f"skills: expected a Skill or a key of SKILLS in {entry!r}, got {type(skill).__name__}")
        if skill.key in chosen:
            raise ValueError(f"skills: expected distinct skill keys, got {skill.key!r} twice")
        chosen[skill.key] = skill
    if not chosen:
        raise ValueError("skills: expected at least one (label, skill) pair, got none")
    return chosen


class DemoPage(VBox):
    """A welcome line, an arm chooser, a skill chooser, a guidance switch, an episode and a "try again" button.

    Args:
        skill: Key of the first skill shown (one of the arms' skills; default the first arm's first).
        guidance: Whether guidance starts on.
        seed: Seed of the first query states; "Try again with new states" adds one.
        skills: (label, skill) pairs for the chooser, a skill being a ``Skill`` (a user's own,
            on any plant) or a key of ``SKILLS``: one arm's, and no arm chooser. Default: the arms
            of ``arms``.
        arms: (label, skills) pairs for the arm chooser, ``skills`` as above; default ``DEMO_ARMS``
            (the paper's planar arms, the UR5 in 3-D) when ``skills`` is not given.
        episode_options: Further keyword arguments for every ``EpisodeWidget`` (e.g. ``duration``;
            the planar views' own, such as ``ghost``, do not change a 3-D episode).
    """

    def __init__(self, skill: str | None = None, guidance: bool = True, seed: int = 0, skills=None, arms=None,
                 **episode_options):
        if skills is not None and arms is not None:
            raise ValueError("skills, arms: expected one of them (skills: one arm's), got both")
        if arms is None:
            arms = DEMO_ARMS if skills is None else (("", skills),)
        if not isinstance(arms, (tuple, list)) or not arms or not all(
                isinstance(a, tuple) and len(a) == 2 and isinstance(a[0], str) for a in arms):
            raise ValueError(f"arms: expected (label, skills) pairs, got {arms!r}"[:200])
        #: {arm label: {key: Skill}}, in the chooser's order.
        self.arms = {label: _chooser_skills(arm_skills) for label, arm_skills in arms}
        self.skills = {}
        for arm in self.arms.values():
            for key, value in arm.items():
                if key in self.skills:
                    raise ValueError(f"arms: expected each skill in one arm, got {key!r} twice")
                self.skills[key] = value
        keys = list(self.skills)
        skill = keys[0] if skill is None else skill
        if skill not in keys:
            raise ValueError(f"skill: expected one of {keys}, got {skill!r}")
        self._labels = {_key_of(value): label for _, arm_skills in arms for label, value in arm_skills}
        arm = next(label for label, arm_skills in self.arms.items() if skill in arm_skills)
        self.seed = int(seed)
        self.episode_options = episode_options
        self.errors: list[tuple[str, bool, float]] = []
        self._switching_arm = False
        # The page's parts share their layouts and styles (looks.py): none of them changes its own.
        self.arm_chooser = plain(ToggleButtons, options=list(self.arms), value=arm,
                                 style=shared_style(ToggleButtonsStyle, button_width="auto"),
                                 tooltips=[f"Teach the {label}" for label in self.arms],
                                 layout=shared_layout() if len(self.arms) > 1 else shared_layout(display="none"))
        self.skill_chooser = plain(ToggleButtons, options=self._skill_options(arm), value=skill,
                                   style=shared_style(ToggleButtonsStyle, button_width="auto"),
                                   tooltips=[s.title for s in self.arms[arm].values()])
        self.guidance_switch = plain(Checkbox, value=as_bool("guidance", guidance),
                                     description="Guidance: show the best arrow", indent=False,
                                     layout=shared_layout(width="auto"))
        self.new_states_button = plain(Button, description="Try again with new states", icon="refresh",
                                       layout=shared_layout(width="auto"))
        self.result_line = plain(HTML, value="")
        self.episode_slot = plain(Box)
        self.episode: EpisodeWidget | None = None
        self.arm_chooser.observe(lambda _: self._on_arm_chosen(), names="value")
        self.skill_chooser.observe(lambda _: None if self._switching_arm else self.start_episode(), names="value")
        self.guidance_switch.observe(lambda _: self._on_guidance_switched(), names="value")
        self.new_states_button.on_click(lambda _: self.start_episode(new_states=True))
        # The choices on one line, so the episode's canvas starts high on the page; the result and
        # "try again" go beside the canvas (the episode's next_actions), where the visitor is
        # looking when the reproduction plays.
        choices = plain(HBox, [self.arm_chooser, self.skill_chooser, self.guidance_switch],
                        layout=shared_layout(flex_flow="row wrap", align_items="center", grid_gap="2px 16px"))
        super().__init__([plain(HTML, WELCOME), choices, self.episode_slot])
        self.add_class("mt-focus")  # a visible focus on each control (canvas_access.py)
        self.start_episode()

    def _skill_options(self, arm: str) -> list[tuple[str, str]]:
        return [(self._labels[key], key) for key in self.arms[arm]]

    def _on_arm_chosen(self) -> None:
        """Another arm: the chooser offers its skills, and its first skill's episode starts (once)."""
        arm = self.arm_chooser.value
        self._switching_arm = True
        try:
            # Options, value and tooltips in one message: the chooser never shows an arm's labels
            # with another's value.
            with self.skill_chooser.hold_sync():
                self.skill_chooser.options = self._skill_options(arm)
                self.skill_chooser.tooltips = [s.title for s in self.arms[arm].values()]
                self.skill_chooser.value = next(iter(self.arms[arm]))
        finally:
            self._switching_arm = False
        self.start_episode()

    def start_episode(self, new_states: bool = False, keep=None) -> EpisodeWidget:
        """Replace the episode with a fresh one for the chosen skill and guidance setting.

        ``keep``: (k, R) demonstrations already given on the same states, shown as given (the
        guidance switched mid-episode keeps the arrows).
        """
        if as_bool("new_states", new_states):
            self.seed += 1
        shown = self.episode
        if shown is not None:
            # The page's own widgets move to the next episode.
            shown.next_actions.children = []
        skill = self.skills[self.skill_chooser.value]
        self.episode = EpisodeWidget(skill, seed=self.seed, guidance=self.guidance_switch.value,
                                     demonstrations=keep, on_finished=self._on_finished, **self.episode_options)
        self.episode.next_actions.children = [self.result_line, self.new_states_button]
        self.episode_slot.children = [self.episode]
        if shown is not None:
            # The rest leaves the kernel too (a kiosk page may run for hours), once the browser has
            # played what it holds for it; after the new one is shown, which stays open.
            retire(shown, keep=self)
        self.result_line.value = ""
        return self.episode

    def _on_guidance_switched(self) -> None:
        """Guidance on or off: the same states again, with every arrow confirmed so far (and the one
        drawn) kept, and a word saying so; after a finished episode, a fresh one."""
        old = self.episode
        if old is None or old.phase == "finished" or not old.demonstrations:
            self.start_episode()
            return
        kept = [list(a) for a in old.demonstrations]
        pending = old.pending_action if old.phase == "teaching" else None
        episode = self.start_episode(keep=kept)
        if pending is not None and episode.phase == "teaching":
            episode.set_action(pending, method="code")
        n = len(kept)
        self.result_line.value = (f"<div style='margin:6px 0;max-width:400px'>Guidance is now "
                                  f"{'on' if self.guidance_switch.value else 'off'}; your {n} "
                                  f"arrow{'s' if n != 1 else ''} so far {'are' if n != 1 else 'is'} kept.</div>")

    def _on_finished(self, result: EpisodeResult) -> None:
        guided = self.guidance_switch.value
        # The measure the episode has, by its own name: Theta's error where the learner has a Theta.
        has_theta = result.theta_error is not None
        error = result.theta_error if has_theta else result.policy_risk
        units = "" if has_theta else f" {result.episode.skill.action_units}"
        measure = ("&Theta;'s error ||&Theta;&#770; &minus; &Theta;||, the distance between what the robot learnt "
                   "and the skill" if has_theta else "the policy risk, the distance between the learnt actions "
                   "and the skill's")
        self.errors.append((result.skill_key, guided, error))
        earlier = [value for key, with_guidance, value in self.errors[:-1]
                   if key == result.skill_key and with_guidance == guided]
        history = (f" Your best before on this skill ({'with' if guided else 'without'} guidance): "
                   f"{min(earlier):.3f}." if earlier else "")
        advice = ("Switch guidance off and try again: can you teach as well without help?" if guided
                  else "Switch guidance on to see the best arrow after each of yours.")
        self.result_line.value = (
            f"<div style='font-size:1.15em;margin:6px 0;max-width:400px'><b>Your teaching error: "
            f"{error:.3f}{units}</b> ({measure}; 0 means the robot learnt the skill exactly).{history} "
            f"{advice}</div>")
