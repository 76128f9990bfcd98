"""In-silico studies: the whole protocol for many synthetic teachers at once.

``run_in_silico`` runs one study (every participant through every phase, the learner fitted
for all of them at once, reproductions rolled out as one batch per skill) and returns the
same tidy episode and demonstration rows a real study's logs give (``mt_widgets.study.tidy``),
so the analysis cannot tell them apart. ``run_many_studies`` runs thousands of studies
together for power by simulation. ``run_through_sessions`` (``mt_widgets.in_silico.sessions``)
drives the session engine, one demonstration at a time, to write real logs.

Each episode is the batched form of a teaching episode: for one episode every participant of a
study answers the same query states (the paper's "pre-determined" states). Every learner of
``LEARNERS`` goes through ``mt_widgets.core.learner_batch.episode_batch``, which batches it as it
declares: a learner with a Theta on the features (``ParametricSmoother``, the paper's ridge) by one
SVD of Phi per set, giving its map and the optimal arrows for all of them, the fit and its scores
(``||Theta_hat - Theta||``) one batched product; any other linear smoother by its matrix, which
depends on the query states only; a learner with a batched fit (the network, the reward learner)
by fitting each set's teachers in one call. Without a Theta the teaching error is the policy
risk, as in a real study with that learner (``TeachingEpisode``).

**The synthetic teachers' assumption per learner.** The teacher model (``teachers``) was fitted to
the paper's ridge studies: a teacher's action blends their own idea of the skill with the arrows
shown. With another learner the arrows shown are that learner's machine teaching, and the model
assumes that novices blend them into theirs alike, with the same parameters: for kernel ridge and
the GP (exact MT; arrows close to ridge's on a linear skill), for the network and the reward
learner (approximate MT). No study with those learners has measured it.
"""

from __future__ import annotations

import json
import os
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from mt_widgets.core.episode_batch import EpisodeBatch
from mt_widgets.core.learner_batch import LearnerEpisodeBatch, episode_batch
from mt_widgets.core.learner_teaching import learnt_policy
from mt_widgets.core.validation import as_bool, as_count
from mt_widgets.study.participants import block_assignment
from mt_widgets.study.study_learners import study_learner

from .plan import (
    default_parameters,
    episode_plan,
    imagined_line_target,
    participant_id,
    query_states_for,
    resolve_protocol,
    session_delays,
    teacher_seed,
)
from .progress import Progress
from .teachers import (
    Forgetting,
    TeacherParameters,
    TeacherPopulation,
    along_line_offsets,
    position_gain,
    target_offsets,
)

# -- the batched engine ----------------------------------------------------------------------------

def _episode_batch(protocol, skill, states):
    """The batched episode of ``skill`` on states (K, N, state_dim) with the protocol's learner, made
    as the study makes it (``study_learner``), batched as it declares (``learner_batch.episode_batch``)."""
    return episode_batch(skill, states, study_learner(protocol, skill), protocol.reproduction_duration_s)


@dataclass
class _BatchOutcome:
    """One episode of the protocol for B simulated teachers at once, as arrays (not an
    ``EpisodeResult``: no ``TeachingEpisode`` is built per teacher; ``EpisodeBatch`` computes all B)."""

    actions: np.ndarray       # (B, N, R)
    optimal: np.ndarray       # (B, N, R)
    theta_hat: np.ndarray | None   # (B, R, S); None for a learner without a Theta
    theta_error: np.ndarray | None   # (B,) ||Theta_hat - Theta||; None for a learner without a Theta
    policy_risk: np.ndarray   # (B,)
    rho1: np.ndarray          # (B,)
    rho2: np.ndarray          # (B,)
    batch: EpisodeBatch | LearnerEpisodeBatch   # the episode's query states, learner and optimal arrows
    first_input: np.ndarray   # (B, N) s
    drawing: np.ndarray       # (B, N) s



def _simulate(protocol, population: TeacherPopulation, groups: np.ndarray, study_of: np.ndarray,
              states_by_episode: list[np.ndarray], progress: Progress | None = None,
              keep_demonstrations: bool = True, forgetting: Forgetting | None = None,
              delays: dict | None = None) -> list[_BatchOutcome]:
    """Runs B teachers through the protocol's episodes.

    Args:
        protocol: the ``Protocol``.
        population: B teachers.
        groups: (B,) group names.
        study_of: (B,) index of each teacher's study (into the first axis of the states).
        states_by_episode: per episode, (K, N, state_dim) query states of each of K studies.
        progress: ticked once per episode.
        keep_demonstrations: keep actions, optimal arrows and timings (off for power runs).
        forgetting: how teachers forget between sessions (None: they do not).
        delays: seconds before each later session (``session_delays``).
    """
    results = []
    delays = session_delays(protocol, delays)
    session = protocol.sessions[0].id
    for e, step in enumerate(episode_plan(protocol)):
        if step["session"] != session:
            session = step["session"]
            population.forget(forgetting, delays[session])
        skill = protocol.skill(step["skill"])
        guided = np.isin(groups, list(step["guidance"]))
        states = states_by_episode[e]
        batch = _episode_batch(protocol, skill, states)
        positions, _ = skill.end_effector(states)
        offsets = target_offsets(skill, states)[study_of]                          # (B, N, R)
        anchor = imagined_line_target(protocol, step["phase_index"], step["session"])
        along = None if anchor is None else along_line_offsets(positions, skill.target, anchor)[study_of]
        optimal = batch.optimal_for(study_of, len(groups))                            # (B, N, R)
        gain = position_gain(skill.theta)
        n = states.shape[1]
        actions = np.empty_like(optimal)
        first = np.empty(optimal.shape[:2]) if keep_demonstrations else None
        drawing = np.empty(optimal.shape[:2]) if keep_demonstrations else None
        for d in range(n):
            actions[:, d] = population.act(e, d, offsets[:, d], optimal[:, d], gain, skill.key, guided,
                                           None if along is None else along[:, d])
            if keep_demonstrations:
                first[:, d], drawing[:, d] = population.timings(e, d, guided)
            population.see_guidance(skill.key, guided)
        outcome = batch.complete(actions, study_of)
        if step["reproduced"]:
            population.see_reproduction()
        results.append(_BatchOutcome(actions if keep_demonstrations else None,
                                      optimal if keep_demonstrations else None, outcome.theta_hat, outcome.theta_error,
                                      outcome.policy_risk, outcome.rho1, outcome.rho2, batch, first, drawing))
        if progress is not None:
            progress.update()
    return results


@dataclass
class InSilicoStudy:
    """One in-silico study, in the tidy form of a real one.

    Attributes:
        protocol: the ``Protocol`` run.
        parameters: the teachers' ``TeacherParameters``.
        seed: the run's seed.
        episodes: tidy episode rows (the columns of ``episodes.csv``).
        demonstrations: tidy demonstration rows (the columns of ``demonstrations.csv``).
        theta_hats: {(participant, phase, episode): (R, S) learnt parameters}.
        reproductions: {(participant, phase, episode): Trajectory}, empty when not reproduced.
        timings: seconds spent teaching and rolling out.
    """

    protocol: object
    parameters: TeacherParameters
    seed: int
    episodes: pd.DataFrame
    demonstrations: pd.DataFrame
    theta_hats: dict = field(repr=False)
    reproductions: dict = field(repr=False)
    timings: dict = field(default_factory=dict)



def run_in_silico(n_participants: int = 32, protocol=None, parameters: TeacherParameters | None = None,
                  seed: int = 0, groups=None, reproduce: bool = True, record_every: int = 10,
                  progress: bool | None = None, study_name: str | None = None, forgetting: Forgetting | None = None,
                  delays: dict | None = None) -> InSilicoStudy:
    """Runs one study of synthetic teachers through the whole protocol.

    Args:
        n_participants: how many participants.
        protocol: a ``Protocol``, a shipped name ("paper-sim", "paper-uarm") or a file path.
        parameters: the teacher model's parameters (default: the protocol's fit, ``PAPER_FIT`` or
            ``PAPER_FIT_UARM``; see ``default_parameters``).
        seed: root seed of the teachers (and of the group assignment when ``groups`` is None).
        groups: a group name per participant (default: the protocol's block randomisation,
            ``mt_widgets.study.participants.block_assignment``, as a real study enrols them).
        reproduce: roll out every learnt skill (what participants watch after each episode).
        record_every: control steps between recorded samples of each reproduction.
        progress: show a progress bar (default: only for runs of more than 1000 participants).
        study_name: the ``study`` column (default: the protocol's name + "-in-silico").
        forgetting: how teachers forget between the protocol's sessions (``Forgetting``; None:
            they do not).
        delays: {session id: seconds} before later sessions (default: each window's earliest).

    Returns:
        An ``InSilicoStudy``.
    """
    reproduce = as_bool("reproduce", reproduce)
    progress = as_bool("progress", progress, allow_none=True)
    protocol = resolve_protocol(protocol)
    n_participants = as_count("n_participants", n_participants)
    parameters = default_parameters(protocol) if parameters is None else parameters
    if groups is None:
        groups = [block_assignment(p, protocol.groups, protocol.block_size, protocol.assignment_seed)
                  for p in range(n_participants)]
    groups = np.asarray(list(groups), dtype=object)
    if groups.shape != (n_participants,) or not set(groups) <= set(protocol.groups):
        raise ValueError(f"groups: expected {n_participants} names from {protocol.groups}, got {list(groups)[:8]}...")
    plan = episode_plan(protocol)
    started = time.perf_counter()
    shared = protocol.query_states == "shared"
    if shared:
        states = [query_states_for(protocol, step)[None] for step in plan]
        study_of = np.zeros(n_participants, dtype=int)
    else:
        states = [np.stack([query_states_for(protocol, step, p) for p in range(n_participants)]) for step in plan]
        study_of = np.arange(n_participants)
    population = TeacherPopulation.draw(parameters, [teacher_seed(seed, p) for p in range(n_participants)],
                                        len(plan), max(step["demonstrations"] for step in plan))
    show = progress if progress is not None else n_participants > 1000
    bar = Progress(len(plan), "teaching", show)
    results = _simulate(protocol, population, groups.astype(str), study_of, states, bar, forgetting=forgetting,
                        delays=delays)
    teaching_s = time.perf_counter() - started

    started = time.perf_counter()
    reproductions, diverged = {}, np.zeros((n_participants, len(plan)), dtype=bool)
    if reproduce and not all(isinstance(r.batch, EpisodeBatch) for r in results):
        # A learner without a Theta: its policy is rolled out one participant at a time (the plant's
        # generic integrator, as a TeachingEpisode's reproduction with that learner).
        for e, step in enumerate(plan):
            batch = results[e].batch
            for p in range(n_participants):
                policy = learnt_policy(batch.learner, batch.skill, batch.query_states[study_of[p]],
                                       results[e].actions[p])
                trajectory = batch.skill.reproduce_policy(policy, batch.duration, record_every)
                diverged[p, e] = bool(trajectory.diverged)
                reproductions[(participant_id(p), step["phase"], step["episode"])] = trajectory
    elif reproduce:
        for skill_key in dict.fromkeys(step["skill"] for step in plan):
            columns = [e for e, step in enumerate(plan) if step["skill"] == skill_key]
            thetas = np.concatenate([results[e].theta_hat for e in columns])
            # A Theta for every episode: one rollout batch per skill (its episodes share plant and start).
            batch = results[columns[0]].batch.reproduce(thetas, record_every=record_every)
            for k, e in enumerate(columns):
                for p in range(n_participants):
                    index = k * n_participants + p
                    diverged[p, e] = bool(batch.diverged[index])
                    reproductions[(participant_id(p), plan[e]["phase"], plan[e]["episode"])] = batch[index]
    rollout_s = time.perf_counter() - started

    name = study_name or f"{protocol.name}-in-silico"
    episode_rows, demonstration_rows, theta_hats = [], [], {}
    for p in range(n_participants):
        clock = 0.0
        for e, step in enumerate(plan):
            r = results[e]
            pid = participant_id(p)
            guided = groups[p] in step["guidance"]
            duration = float(np.sum(r.first_input[p] + r.drawing[p]))
            if r.theta_hat is not None:
                theta_hats[(pid, step["phase"], step["episode"])] = r.theta_hat[p]
            episode_rows.append({
                "study": name, "participant": pid, "group": groups[p], "session": step["session"],
                "phase": step["phase"], "phase_index": step["phase_index"], "episode": step["episode"],
                "skill": step["skill"],
                "guidance": int(guided), "n_demonstrations": step["demonstrations"],
                "theta_error": None if r.theta_error is None else float(r.theta_error[p]),
                "policy_risk": float(r.policy_risk[p]), "rho1": float(r.rho1[p]), "rho2": float(r.rho2[p]),
                # Only ridge has a Theta_hat (another learner's is empty, as in a real study's tidy file).
                "theta_hat": None if r.theta_hat is None else json.dumps(np.round(r.theta_hat[p], 12).tolist()),
                "reproduction_diverged": bool(diverged[p, e]) if reproduce else None,
                "started_at": clock, "duration_s": duration})
            clock += duration
            for d in range(step["demonstrations"]):
                demonstration_rows.append({
                    "study": name, "participant": pid, "group": groups[p], "session": step["session"],
                    "phase": step["phase"], "phase_index": step["phase_index"], "episode": step["episode"],
                    "index": d,
                    "skill": step["skill"], "state": json.dumps(states[e][study_of[p], d].tolist()),
                    **{f"{kind}_{c + 1}": float(values[p, d, c]) for kind, values in
                       (("action", r.actions), ("optimal", r.optimal)) for c in range(values.shape[-1])},
                    "guidance_shown": int(guided), "time_to_first_input_s": float(r.first_input[p, d]),
                    "drawing_duration_s": float(r.drawing[p, d])})
    return InSilicoStudy(protocol, population.parameters, seed, pd.DataFrame(episode_rows),
                         pd.DataFrame(demonstration_rows), theta_hats, reproductions,
                         {"teaching_s": teaching_s, "rollout_s": rollout_s})


def run_many_studies(n_studies: int, n_per_group: int, seed: int = 0, parameters: TeacherParameters | None = None,
                     changes=None, progress: bool | None = None, protocol=None, share_states: bool = False,
                     workers: int | None = None, forgetting: Forgetting | None = None,
                     delays: dict | None = None) -> dict:
    """Many independent studies at once, reduced to each participant's changes.

    Every study has its own participants and its own query states (its own study seed), and
    2 * n_per_group participants split equally between the first two groups.

    Args:
        n_studies: studies to simulate.
        n_per_group: participants per group in each.
        seed: root seed.
        parameters: ``TeacherParameters`` (default: the protocol's fit, ``default_parameters``).
        changes: ``Change`` comparisons (default: the protocol's analysis plan's).
        progress: show a progress bar (default: for more than 50 studies).
        protocol: the ``Protocol`` (default the paper's simulation protocol).
        share_states: use the protocol's own query states in every study (isolates the
            teachers' variability; used when fitting).
        workers: processes drawing the studies' query states, the slow part (default: up to
            2 for 100 studies or more, else 1). The result does not depend on it.
        forgetting: how teachers forget between the protocol's sessions (None: they do not).
        delays: {session id: seconds} before later sessions (default: each window's earliest).

    Returns:
        {change name: {group: (n_studies, n_per_group) array of after - before}}.
    """
    share_states = as_bool("share_states", share_states)
    progress = as_bool("progress", progress, allow_none=True)
    protocol = resolve_protocol(protocol)
    parameters = default_parameters(protocol) if parameters is None else parameters
    n_studies, n_per_group = as_count("n_studies", n_studies), as_count("n_per_group", n_per_group)
    plan = episode_plan(protocol)
    show = progress if progress is not None else n_studies > 50
    bar = Progress(n_studies + len(plan), "studies", show)
    per_study = 2 * n_per_group
    if share_states:
        states = [query_states_for(protocol, step)[None] for step in plan]
        bar.update(n_studies)
    else:
        by_study = _states_of_studies(protocol, n_studies, seed, workers, bar)
        states = [np.stack([by_study[k][e] for k in range(n_studies)]) for e in range(len(plan))]
    seeds = [teacher_seed(seed, p) for p in range(n_studies * per_study)]
    population = TeacherPopulation.draw(parameters, seeds, len(plan), max(step["demonstrations"] for step in plan))
    return simulate_changes(protocol, population, n_studies, n_per_group, states, changes, bar,
                            shared=share_states, forgetting=forgetting, delays=delays)


def _study_query_states(arguments):
    """The query states of every episode of one simulated study, or None if the sampler fails."""
    protocol, study_seed = arguments
    try:
        return [query_states_for(protocol, step, study_seed=study_seed) for step in episode_plan(protocol)]
    except ValueError:
        # The greedy sampler can paint itself into a corner (S - 1 states that no candidate
        # completes under the threshold); a real study would redraw its seed, and so does this.
        return None


def _states_of_studies(protocol, n_studies: int, seed: int, workers: int | None, bar: Progress) -> list:
    """Query states for n_studies studies, each with its own study seed, drawn in parallel.

    Candidate study seeds are spawned in order from ``seed``; the first n_studies whose
    schedules can be drawn are used, so the result is the same for any number of workers.
    """
    root = np.random.SeedSequence(seed)
    if workers is None:
        workers = min(2, os.cpu_count() or 1) if n_studies >= 100 else 1
    chosen: list = []
    while len(chosen) < n_studies:
        wanted = n_studies - len(chosen)
        # A few spares per batch: about 1 schedule in 200 cannot be completed.
        candidates = [int(s.generate_state(1)[0]) for s in root.spawn(wanted + wanted // 50 + 2)]
        jobs = [(protocol, study_seed) for study_seed in candidates]
        if workers > 1:
            with ProcessPoolExecutor(max_workers=workers) as pool:
                drawn = list(pool.map(_study_query_states, jobs, chunksize=max(1, len(jobs) // (8 * workers))))
        else:
            drawn = [_study_query_states(job) for job in jobs]
        for states in drawn:
            if states is not None and len(chosen) < n_studies:
                chosen.append(states)
                bar.update()
    return chosen


def simulate_changes(protocol, population: TeacherPopulation, n_studies: int, n_per_group: int,
                     states: list[np.ndarray], changes=None, progress: Progress | None = None,
                     shared: bool | None = None, forgetting: Forgetting | None = None,
                     delays: dict | None = None) -> dict:
    """Runs a drawn population as ``n_studies`` studies and returns each participant's changes.

    Args:
        protocol: the ``Protocol``.
        population: n_studies * 2 * n_per_group teachers; in each study the first n_per_group
            are in the first group, the next in the second.
        n_studies: how many studies.
        n_per_group: participants per group.
        states: per episode, (n_studies, N, state_dim) query states, or (1, N, state_dim)
            shared by all studies.
        changes: ``Change`` comparisons (default: the protocol's analysis plan's).
        progress: ticked once per episode.
        shared: whether all studies share one set of states (default: from ``states``).
        forgetting, delays: as for ``run_many_studies``.

    Returns:
        {change name: {group: (n_studies, n_per_group) after - before,
        "before": (n_studies, 2 n_per_group) the earlier episode's errors}}.
    """
    shared = as_bool("shared", shared, allow_none=True)
    changes = protocol.analysis.compared(protocol.name) if changes is None else tuple(changes)
    plan = episode_plan(protocol)
    per_study = 2 * n_per_group
    if len(population) != n_studies * per_study:
        raise ValueError(f"population: expected {n_studies * per_study} teachers, got {len(population)}")
    shared = states[0].shape[0] == 1 if shared is None else shared
    groups = np.tile(np.repeat(np.asarray(protocol.groups[:2]), n_per_group), n_studies)
    study_of = np.zeros(n_studies * per_study, dtype=int) if shared else np.repeat(np.arange(n_studies), per_study)
    results = _simulate(protocol, population, groups, study_of, states, progress, keep_demonstrations=False,
                        forgetting=forgetting, delays=delays)
    # The error the analysis compares (``analysis.tables.error_measure``'s rule): Theta's error where
    # every episode has one, else the policy risk.
    measure = "theta_error" if all(r.theta_error is not None for r in results) else "policy_risk"
    errors = np.stack([getattr(r, measure) for r in results], axis=1)       # (B, episodes)
    index = {(step["phase"], step["episode"]): e for e, step in enumerate(plan)}
    last = {step["phase"]: e for e, step in enumerate(plan)}
    out = {}
    for change in changes:
        before = index[change.before] if change.before[1] is not None else last[change.before[0]]
        after = index[change.after] if change.after[1] is not None else last[change.after[0]]
        delta = (errors[:, after] - errors[:, before]).reshape(n_studies, per_study)
        out[change.name] = {protocol.groups[0]: delta[:, :n_per_group], protocol.groups[1]: delta[:, n_per_group:],
                            "before": errors[:, before].reshape(n_studies, per_study)}
    return out
