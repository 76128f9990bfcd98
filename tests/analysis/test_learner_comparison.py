"""Per learner: the same synthetic teachers through the same protocol, each learner's guidance and errors."""

import numpy as np
import pytest

from mt_widgets.analysis import guidance_by_learner, protocol_with_learner
from mt_widgets.core.validation import UnknownKeyError
from mt_widgets.study import load_protocol
from mt_widgets.study.log import read_log


def test_a_protocol_with_another_learner_differs_in_its_learner_and_name_only():
    base = load_protocol("paper-uarm")
    variant = protocol_with_learner(base, "kernel-ridge")
    assert variant.learner == "kernel-ridge" and variant.name == "paper-uarm-kernel-ridge"
    assert [(p.id, p.skill, p.episodes, p.demonstrations, p.guidance) for p in variant.phases] == [
        (p.id, p.skill, p.episodes, p.demonstrations, p.guidance) for p in base.phases]
    with pytest.raises(UnknownKeyError, match="learner: expected one of the available learners .* got 'svm'"):
        protocol_with_learner(base, "svm")


def test_guidance_helps_the_teachers_of_each_learner_and_each_study_runs_its_learner(tmp_path):
    table = guidance_by_learner(tmp_path, ["ridge", "reward"], n_participants=4, seed=0)
    assert list(table["learner"]) == ["ridge"] * 3 + ["reward"] * 3
    # The guided teachers (blending in the learner's MT arrows) improve more than the unguided ones.
    assert (table["difference"] < 0).all() and (table["target_percent_change"] < 0).all()
    ridge = read_log(tmp_path / "ridge" / "S001.jsonl", "main")
    reward = read_log(tmp_path / "reward" / "S001.jsonl", "main")
    ridge_done = [e for e in ridge if e["type"] == "episode_finished"]
    reward_done = [e for e in reward if e["type"] == "episode_finished"]
    assert all("learner" not in e and np.shape(e["theta_hat"]) == (2, 3) for e in ridge_done)
    assert all(e["learner"] == "reward" and e["theta_hat"] is None for e in reward_done)
    # The same teachers on the same query states: a novice's first arrows (before any guidance,
    # understanding w = 0) do not depend on the robot; only the guidance they later see does.
    def baseline(events):
        return [(e["state"], e["action"]) for e in events if e["type"] == "demonstration" and e["phase"] == "P1"]
    assert baseline(ridge) == baseline(reward) and len(baseline(ridge)) == 3


@pytest.mark.parametrize("protocol, learner", [("reward-sim", None), ("paper-uarm", "kernel-ridge"),
                                               ("paper-uarm", "gaussian-process"),
                                               # Approximate MT per set and a batched fit: about 5 s.
                                               pytest.param("paper-uarm", "neural-network", marks=pytest.mark.slow)])
def test_the_batched_engine_scores_every_learner_as_its_teaching_episode_does(protocol, learner):
    import json

    from mt_widgets.core import TeachingEpisode
    from mt_widgets.in_silico import run_in_silico, run_many_studies
    from mt_widgets.study.study_learners import study_learner

    protocol = load_protocol(protocol)
    protocol = protocol if learner is None else protocol_with_learner(protocol, learner)
    study = run_in_silico(3, protocol=protocol, reproduce=False, progress=False)
    assert study.episodes["theta_hat"].isna().all() and not study.theta_hats
    # Each row's error, rho1 and rho2 are those of a TeachingEpisode with the study's learner, one
    # teacher at a time (the batched smoother's S U or the batched fit against the single path).
    rows = study.demonstrations.groupby(["participant", "phase", "episode"], sort=False)
    checked = 0
    for (participant, phase, episode), demos in list(rows)[::5]:
        skill = protocol.skill(demos["skill"].iloc[0])
        states = np.array([json.loads(s) for s in demos["state"]])
        actions = demos[["action_1", "action_2"]].to_numpy()
        single = TeachingEpisode.from_actions(skill, states, actions, learner=study_learner(protocol, skill))
        episodes = study.episodes
        row = episodes[(episodes["participant"] == participant) & (episodes["phase"] == phase)
                       & (episodes["episode"] == episode)].iloc[0]
        np.testing.assert_allclose(row["policy_risk"], single.policy_risk, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(row["rho1"], single.rho1, rtol=1e-9)
        np.testing.assert_allclose(demos[["optimal_1", "optimal_2"]].to_numpy(), single.optimal_actions, atol=1e-9)
        checked += 1
    assert checked >= 5
    # Power by simulation takes the same learner: 2 studies of 2 x 2, each change per group.
    changes = run_many_studies(2, 2, protocol=protocol, share_states=True, progress=False)
    assert all(change[group].shape == (2, 2) for change in changes.values() for group in protocol.groups[:2])


def test_the_batched_engine_refuses_a_learner_it_cannot_batch_by_name():
    from mt_widgets.core import SKILLS
    from mt_widgets.core.learner import Learner
    from mt_widgets.core.learner_batch import LearnerEpisodeBatch

    class OneAtATime(Learner):
        def fit(self, X, U):
            return U

        def predict(self, fitted, X_star):
            return np.zeros((len(X_star), 2))

    skill = SKILLS["uarm-point"]
    with pytest.raises(TypeError, match="learner: expected a linear smoother or a learner with a batched fit .* "
                                        "got OneAtATime\\(\\)"):
        LearnerEpisodeBatch.of(skill, skill.query_states(seed=0)[None], OneAtATime())
