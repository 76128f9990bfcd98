"""The reward-learning follow-up's study (protocol reward-sim) end to end: run, log, tidy, BIDS, analysis.

Every number the runner logs for the reward learner is checked against a computation made here
from the logged states and actions with ``RewardLearner`` itself, so a runner that logged ridge's
numbers, another learner's, or stale ones would fail.
"""

import csv
import json

import numpy as np
import pytest
from bids_validator import BIDSValidator

from mt_widgets import SKILLS
from mt_widgets.analysis import analyse_study
from mt_widgets.core.learner_teaching import evaluation_states, risk_of_actions, teach
from mt_widgets.core.reward_learner import RewardLearner
from mt_widgets.study import Session, StudyFolder, export_bids, load_protocol
from mt_widgets.study.log import read_log
from mt_widgets.study.pseudonyms import code_of
from mt_widgets.study.tidy import export_study

from .scripted import run_to_end_one, short_protocol

ANSWERS = {"eligibility": {"robotics_background": "no"}, "demographics": {"age": 30, "sex": "female"},
           "questionnaire": {"difficulty": "easy", "comments": ""}}
PARTICIPANTS = {"P01": "target", "P02": "control", "P03": "target", "P04": "control"}


def _teach(session, seed: int) -> None:
    """A scripted novice: the skill's own actions plus noise; once a guided participant has seen
    the guidance (after their first P3 episode) they demonstrate near the guidance's arrows."""
    rng = np.random.default_rng(seed)
    seen_guidance = False
    while not session.finished:
        step = session.current_step()
        if step.kind == "demonstration":
            skill = SKILLS[step.skill]
            target = skill.target_actions(step.state[None])[0]
            if seen_guidance:
                action = step.teaching_episode.optimal_actions[step.index] + rng.normal(0, 0.1, 2)
            else:
                action = target + rng.normal(0, 0.3 * (1 + np.abs(target)), 2)
            feedback = session.submit_demonstration(action, index=step.index)
            seen_guidance = seen_guidance or feedback.guidance
        elif step.kind in ("eligibility", "demographics", "questionnaire"):
            session.submit_answers(ANSWERS[step.study_step.id])
        else:
            run_to_end_one(session)


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    root = tmp_path_factory.mktemp("reward")
    folder = StudyFolder.create(root / "study", load_protocol("reward-sim"))
    for k, (pid, group) in enumerate(PARTICIPANTS.items()):
        session = Session.start(folder, pid, group=group)
        if pid == "P03":  # interrupted in the middle of a training episode, then resumed
            while not (session.current_step().kind == "demonstration" and session.current_step().phase == "P3"
                       and session.current_step().index == 3):
                run_to_end_one(session, ANSWERS)
            session.close()
            session = Session.resume(folder, pid)
        _teach(session, k)
        session.close()
    return folder, root


def _events(folder, pid):
    return read_log(folder.folder / f"{pid}.jsonl", "main")


def test_the_protocol_teaches_the_reward_learner_with_8_demonstrations():
    protocol = load_protocol("reward-sim")
    assert protocol.learner == "reward"
    assert [(p.id, p.skill, p.demonstrations) for p in protocol.phases] == [
        ("P1", "uarm-point", 8), ("P2", "uarm-line", 8), ("P3", "uarm-point", 8), ("P4", "uarm-point", 8),
        ("P5", "uarm-line", 8)]
    assert [p.id for p in protocol.phases if p.guidance] == ["P3"]


def test_each_episode_logs_the_reward_learners_guidance_fit_and_risk(study):
    folder, _ = study
    learner = RewardLearner()
    checked = 0
    for pid in PARTICIPANTS:
        events = _events(folder, pid)
        started = {(e["phase_index"], e["episode"]): e for e in events if e["type"] == "episode_started"}
        finished = [e for e in events if e["type"] == "episode_finished"]
        assert len(finished) == 12
        for done in finished:
            begun = started[(done["phase_index"], done["episode"])]
            skill = SKILLS[done["skill"]]
            states, actions = np.array(begun["query_states"]), np.array(done["actions"])
            assert begun["learner"] == done["learner"] == "reward"
            assert begun["learner_parameters"] == {"lam": 1e-3, "inputs": "state"}
            assert len(states) == 8
            # The guidance is the reward learner's machine teaching on these states.
            np.testing.assert_allclose(begun["optimal"], teach(learner, skill, states).optimal, atol=1e-9)
            # What it learnt: its optimal policy for the reward fitted to the logged actions (uArm:
            # the inputs are the positions, the states themselves).
            np.testing.assert_allclose(done["learnt_actions"], learner.predict(learner.fit(states, actions), states),
                                       atol=1e-9)
            assert done["theta_error"] is None and done["policy_risk"] == pytest.approx(
                risk_of_actions(learner, skill, states, actions, evaluation_states(skill)), rel=1e-9)
            assert done["theta_hat"] is None and done["bound"] is None and done["residual"] is None
            checked += 1
    assert checked == 48


def test_the_paper_protocols_log_stays_as_it_was(tmp_path):
    folder = StudyFolder.create(tmp_path / "study", short_protocol())
    session = Session.start(folder, "P01", group="target")
    while not session.finished:
        run_to_end_one(session)
    session.close()
    events = read_log(folder.folder / "P01.jsonl", "main")
    done = next(e for e in events if e["type"] == "episode_finished")
    begun = next(e for e in events if e["type"] == "episode_started")
    assert "learner" not in done and "learnt_actions" not in done and "learner" not in begun
    assert np.array(done["theta_hat"]).shape == (2, 3) and done["bound"] >= done["theta_error"]


def test_the_tidy_export_has_the_policy_risk_and_no_theta(study):
    folder, root = study
    episodes_csv, _ = export_study(folder.folder, root / "tidy")
    with open(episodes_csv, encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 48 and {r["theta_hat"] for r in rows} == {""}
    logged = [e["policy_risk"] for e in _events(folder, "P01") if e["type"] == "episode_finished"]
    assert [float(r["policy_risk"]) for r in rows if r["participant"] == "P01"] == logged


def test_the_bids_sidecar_names_the_reward_learner_and_its_parameters(study):
    folder, root = study
    out = export_bids(folder.folder, root / "bids")
    files = sorted("/" + str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    assert [f for f in files if not BIDSValidator().is_bids(f)] == []
    code = code_of(folder.folder, "P01")
    sidecar = json.loads((out / f"sub-{code}" / "beh" / f"sub-{code}_task-rewardsim_beh.json").read_text())
    assert sidecar["Learner"] == "reward" and "LearnerRidgeLambda" not in sidecar
    expected = {"lam": 1e-3, "inputs": "state"}
    assert sidecar["LearnerParameters"] == {"uarm-line": expected, "uarm-point": expected}
    assert "policy risk" in sidecar["policy_risk"]["Description"]
    assert "no Theta" in sidecar["theta_error"]["Description"]


def test_the_analysis_reports_the_reward_learner_and_rolls_out_what_was_taught(study):
    folder, _ = study
    analysis = analyse_study(folder.folder)
    statistics = analysis.statistics
    assert statistics.learner == "reward" and "reward learner" in statistics.summary()
    means = statistics.change_summary.set_index(["change", "group"])["mean"]
    # The scripted guided novices demonstrate near the guidance after P3E1: their error falls more.
    assert means[("P1_to_P4", "target")] < means[("P1_to_P4", "control")]
    # The trajectory figure draws the policy refitted from the log, rolled out from the skill's start.
    events = _events(folder, "P01")
    begun = next(e for e in events if e["type"] == "episode_started" and e["phase"] == "P4")
    done = next(e for e in events if e["type"] == "episode_finished" and e["phase"] == "P4")
    skill, learner = SKILLS["uarm-point"], RewardLearner()
    fitted = learner.fit(np.array(begun["query_states"]), np.array(done["actions"]))
    expected = skill.reproduce_policy(lambda r: learner.predict(fitted, r)).final_position
    lines = [line for ax in analysis.figures["trajectories"].axes for line in ax.get_lines()
             if line.get_gid() == "P01/P4E1"]
    assert lines and all(np.allclose(line.get_xydata()[-1], expected) for line in lines)
    np.testing.assert_allclose(done["reproduction"]["final_position"], expected)


def test_the_study_app_runs_the_reward_protocol_and_guides_with_its_mt(tmp_path):
    from mt_widgets.apps import StudyApp
    from mt_widgets.study.protocol import PROTOCOL_FOLDER

    from .scripted import act

    # The protocol's task as the participant page runs it (the steps around it are the paper's).
    text = (PROTOCOL_FOLDER / "reward_sim.toml").read_text()
    path = tmp_path / "reward.toml"
    task = text[:text.index("# -- steps around the task")]
    path.write_text(task.replace("[texts]\n", '[texts]\nconsent = "Consent."\n'))
    app = StudyApp(protocol=str(path), log_folder=tmp_path / "logs")
    app.start_participant("P01", group="target")
    guided = 0
    while not app.session.finished:
        step = app.session.current_step()
        if step.kind in ("demonstration", "episode_end") and app.episode.phase == "guidance":
            states = app.episode.query_states
            assert len(states) == 8 and step.phase == "P3"
            np.testing.assert_allclose(app.episode.optimal,
                                       teach(RewardLearner(), SKILLS[step.skill], states).optimal, atol=1e-9)
            guided += 1
        act(app)
    assert guided == 8 * 8
    finished = [e for e in read_log(tmp_path / "logs" / "P01.jsonl", "main") if e["type"] == "episode_finished"]
    assert len(finished) == 12 and {e["learner"] for e in finished} == {"reward"}


def test_the_reward_protocol_runs_online_with_an_online_table(tmp_path):
    from mt_widgets.study import parse_protocol
    from mt_widgets.study.online import outcome_of
    from mt_widgets.study.protocol import PROTOCOL_FOLDER

    from .scripted import ONLINE

    protocol = parse_protocol((PROTOCOL_FOLDER / "reward_sim.toml").read_text() + ONLINE,
                              str(PROTOCOL_FOLDER / "reward_online.toml"))
    arrival = protocol.online.participant_from_url({"PROLIFIC_PID": ["5f3a9c2e8b1d4a0012345678"]})
    study = StudyFolder.create(tmp_path / "study", protocol)
    with Session.arrive(study, arrival.participant_id, parameters=arrival.parameters) as session:
        _teach(session, 0)
        assert outcome_of(session) == "completed"
        assert protocol.online.completion_url("completed").endswith("cc=C1MPL3T3")
    finished = [e for e in read_log(study.folder / f"{arrival.participant_id}.jsonl", "main")
                if e["type"] == "episode_finished"]
    assert len(finished) == 12 and {e["learner"] for e in finished} == {"reward"}
