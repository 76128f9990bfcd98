"""EpisodeWidget's lam and episode_index: a lam that contradicts the shown TeachingEpisode's own
is refused (even the default's value), and the index is a whole number >= 0."""

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.core import DEFAULT_LAMBDA, TeachingEpisode
from mt_widgets.widgets import EpisodeWidget

SKILL = SKILLS["sim-point"]


def test_a_shown_episode_keeps_its_own_lam_and_refuses_any_other():
    episode = TeachingEpisode(SKILL, seed=1, lam=0.5)
    assert EpisodeWidget(episode).lam == 0.5
    assert EpisodeWidget(episode, lam=0.5).episode is episode
    # DEFAULT_LAMBDA said explicitly contradicts this episode's 0.5: refused, not ignored.
    for lam in (DEFAULT_LAMBDA, 0.1):
        with pytest.raises(ValueError, match=r"^lam: expected None or the shown TeachingEpisode's own \(0.5\)"):
            EpisodeWidget(episode, lam=lam)


def test_without_an_episode_lam_defaults_to_the_learners_default():
    assert EpisodeWidget(SKILL).lam == DEFAULT_LAMBDA
    assert EpisodeWidget(SKILL, lam=0.2).lam == 0.2


@pytest.mark.parametrize("value", [-1, 1.5, "2", None, True, np.float64(2.0)])
def test_the_episode_index_is_a_whole_number_from_zero(value):
    wrong_type = not isinstance(value, int) or isinstance(value, bool)   # -1 is a whole number, but negative
    with pytest.raises(TypeError if wrong_type else ValueError, match=r"^episode_index: expected a whole number"):
        EpisodeWidget(SKILL, episode_index=value)
    assert EpisodeWidget(SKILL, episode_index=np.int64(2)).episode_index == 2
