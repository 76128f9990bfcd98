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


def test_the_batched_engine_refuses_a_learner_it_does_not_fit():
    from mt_widgets.in_silico import run_in_silico, run_many_studies

    reward = load_protocol("reward-sim")
    for run in (lambda: run_in_silico(2, protocol=reward), lambda: run_many_studies(2, 2, protocol=reward)):
        with pytest.raises(ValueError, match="protocol: expected a protocol whose learner is ridge .* "
                                             "'reward-sim' with learner 'reward'"):
            run()
