"""Every yes/no option of the public API takes only True or False: "no", "false", 0, 1 and None
are refused by name, never read by truthiness (guidance="no" used to switch guidance ON)."""

import numpy as np
import pytest

from mt_widgets import SKILLS, TwoLinkArm
from mt_widgets.apps.uarm_audio import AudioCues
from mt_widgets.apps.uarm_screen import ScreenGeometry, fit_episode
from mt_widgets.core import ArmPlant
from mt_widgets.widgets import EpisodeWidget, GuidancePanel, ReproductionPlayer, TeachingCanvas
from mt_widgets.widgets.demo import DemoPage

NOT_BOOLEANS = ["no", "false", "False", 0, 1, None, np.int64(1)]

SKILL = SKILLS["uarm-point"]
STATES = SKILL.query_states(seed=0)


def _episode(**options):
    return EpisodeWidget(SKILL, query_states=STATES, **options)


def _callbacks_remove(value):
    _episode().on_finished(print, remove=value)


def _demo_new_states(value):
    DemoPage(skill="uarm-point").start_episode(new_states=value)


OPTIONS = {
    "guidance": lambda v: _episode(guidance=v),
    "ghost": lambda v: _episode(ghost=v),
    "show_description": lambda v: _episode(show_description=v),
    "show_outcome": lambda v: _episode(show_outcome=v),
    "remove": _callbacks_remove,
    "auto_advance": lambda v: TeachingCanvas(SKILL, STATES, auto_advance=v),
    "show_velocity": lambda v: ReproductionPlayer(SKILL).view.show_state(SKILL.start, show_velocity=v),
    "exact": lambda v: GuidancePanel(_episode().theme, "cm").show([1.0, 0.0], [0.0, 1.0], exact=v),
    "legend": lambda v: GuidancePanel(_episode().theme, "cm").show([1.0, 0.0], [0.0, 1.0], legend=v),
    "guidance ": lambda v: DemoPage(skill="uarm-point", guidance=v),
    "new_states": _demo_new_states,
    "gravity_compensation": lambda v: TwoLinkArm(gravity_compensation=v),
    "elbow_up": lambda v: TwoLinkArm().inverse_kinematics([1.0, 1.0], elbow_up=v),
    "elbow_up ": lambda v: ArmPlant().state_at([1.0, 1.0], elbow_up=v),
    "enabled": lambda v: AudioCues(enabled=v),
    "pinned": lambda v: ScreenGeometry(pinned=v),
    "show_player": lambda v: fit_episode(_episode(), ScreenGeometry(), show_player=v),
}


@pytest.mark.parametrize("option", sorted(OPTIONS))
def test_a_boolean_option_refuses_anything_but_a_bool_and_names_itself(option):
    call = OPTIONS[option]
    for value in (True, False):
        call(value)
    for value in NOT_BOOLEANS:
        with pytest.raises(TypeError, match=rf"^{option.strip()}: expected True or False, got "):
            call(value)


def test_guidance_no_does_not_show_guidance():
    with pytest.raises(TypeError, match="guidance: expected True or False, got str 'no'"):
        EpisodeWidget("sim-point", guidance="no")
    episode = EpisodeWidget("sim-point", guidance=False)
    episode.demonstrate([0.1, 0.2])
    assert episode.guidance_panel.value == "" and episode.phase == "teaching"
