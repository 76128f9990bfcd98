"""In-silico studies: the whole protocol for many synthetic teachers at once.

``run_in_silico`` runs one study (every participant through every phase, the learner fitted
for all of them at once, reproductions rolled out as one batch per skill) and returns the
same tidy episode and demonstration rows a real study's logs give (``mt_widgets.study.tidy``),
so the analysis cannot tell them apart. ``run_many_studies`` runs thousands of studies
together for power by simulation. ``run_through_sessions`` (in ``in_silico_sessions``) drives
the session engine, one demonstration at a time, to write real logs.

The learner is batched exactly: for one episode every participant of a study answers the same
query states (the paper's "pre-determined" states), so one SVD of Phi gives the ridge map
``A = (Phi^T Phi + lam I)^-1 Phi^T`` and the optimal arrows ``U_bar`` for all of them, and
``Theta_hat^T = A U`` is one matrix product per participant.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from mt_widgets.core import SKILLS, SeedSchedule

from .synthetic_teachers import (
    TeacherParameters,
    TeacherPopulation,
    along_line_offsets,
    naive_offsets,
    paper_fit,
    position_gain,
)


# -- the protocol, as far as the engine needs it ---------------------------------------------------

def resolve_protocol(protocol):
    """A ``Protocol`` from a protocol object, a shipped name ("paper-sim") or a file path."""
    from .protocol import Protocol, load_protocol
    if protocol is None:
        protocol = "paper-sim"
    if isinstance(protocol, Protocol):
        return protocol
    return load_protocol(protocol)


def episode_plan(protocol) -> list[dict]:
    """The protocol's episodes in order: phase, phase_index, episode (1-based), skill, states seed index."""
    plan = []
    for phase in protocol.phases:
        for e in range(phase.episodes):
            plan.append({"phase": phase.id, "phase_index": phase.index, "episode": e + 1, "skill": phase.skill,
                         "demonstrations": phase.demonstrations, "guidance": phase.guidance,
                         "states_index": phase.states_index, "episode_index": e})
    return plan


def query_states_for(protocol, step: dict, participant: int | None = None, study_seed: int | None = None) -> np.ndarray:
    """The query states of one episode, from the protocol's seed schedule.

    Args:
        protocol: the ``Protocol``.
        step: an ``episode_plan`` entry.
        participant: the enrolment number, used when the protocol draws states per participant.
        study_seed: overrides the protocol's seed (each simulated study of a power analysis
            has its own).

    Returns:
        (demonstrations, state_dim) states.
    """
    schedule = SeedSchedule(protocol.seed if study_seed is None else study_seed)
    who = participant if protocol.query_states == "per-participant" else None
    seed = schedule.seed(step["states_index"], step["episode_index"], who)
    return SKILLS[step["skill"]].query_states(seed=seed, n=step["demonstrations"])


def imagined_line_target(protocol, phase_index: int):
    """The point a novice takes for a line skill's target in phase ``phase_index`` (model item 1b).

    It is the point target they last practised or taught on the same robot before this phase
    (the practice skill counts first): in the paper's protocols skill 1's point, practised for
    two minutes and taught in P1 just before the line appears in P2.

    Args:
        protocol: the ``Protocol``.
        phase_index: the 0-based index of the phase in ``protocol.phases``.

    Returns:
        (2,) the point in the skill's units, or None (a point skill, or no point taught before).
    """
    phase = protocol.phases[phase_index]
    skill = SKILLS[phase.skill]
    if not hasattr(skill.target, "direction"):
        return None
    before = [protocol.practice.skill] if protocol.practice.duration_s > 0 else []
    before += [p.skill for p in protocol.phases[:phase_index]]
    anchor = None
    for key in before:
        other = SKILLS[key]
        if type(other.plant) is type(skill.plant) and other.target is not None \
                and not hasattr(other.target, "direction"):
            anchor = np.asarray(other.target.point, dtype=float)
    return anchor


def default_parameters(protocol) -> TeacherParameters:
    """The fitted teacher parameters for a protocol: ``PAPER_FIT_UARM`` for a uArm protocol, else ``PAPER_FIT``."""
    return paper_fit(resolve_protocol(protocol))


def teacher_seed(seed: int, participant: int) -> np.random.SeedSequence:
    """The seed of synthetic participant ``participant`` of a run seeded ``seed``."""
    return np.random.SeedSequence(seed, spawn_key=(1, participant))


def assign_groups(n_participants: int, groups=("target", "control"), block_size: int = 4, seed: int = 0) -> list[str]:
    """Seeded block randomisation: every block of ``block_size`` holds each group equally often."""
    if block_size % len(groups):
        raise ValueError(f"block_size: expected a multiple of the {len(groups)} groups, got {block_size}")
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(2,)))
    assigned: list[str] = []
    while len(assigned) < n_participants:
        block = list(groups) * (block_size // len(groups))
        rng.shuffle(block)
        assigned.extend(block)
    return assigned[:n_participants]


# -- progress --------------------------------------------------------------------------------------

def _in_kernel() -> bool:
    shell = sys.modules.get("IPython")
    if shell is None:
        return False
    try:
        ip = shell.get_ipython()
    except AttributeError:
        return False
    return ip is not None and type(ip).__name__ == "ZMQInteractiveShell"


class Progress:
    """A progress bar: ipywidgets.IntProgress in a Jupyter kernel, a text line elsewhere.

    ipywidgets is imported only when a kernel runs, so ``mt_widgets.study`` imports without it.

    Args:
        total: steps in all.
        description: a short label.
        enabled: False makes every call a no-op.
    """

    def __init__(self, total: int, description: str = "", enabled: bool = True):
        self.total, self.description, self.enabled = max(int(total), 1), description, enabled
        self.done, self._bar, self._started, self._last_print = 0, None, time.perf_counter(), 0.0
        if enabled and _in_kernel():
            try:
                import ipywidgets
                from IPython.display import display
            except ImportError:   # no widgets installed: fall back to text
                pass
            else:
                self._bar = ipywidgets.IntProgress(value=0, min=0, max=self.total, description=description)
                display(self._bar)

    def update(self, steps: int = 1) -> None:
        if not self.enabled:
            return
        self.done = min(self.done + steps, self.total)
        if self._bar is not None:
            self._bar.value = self.done
            return
        now = time.perf_counter()
        # At most a few lines a second, and always the last one.
        if now - self._last_print > 0.5 or self.done == self.total:
            self._last_print = now
            elapsed = now - self._started
            print(f"\r{self.description} {self.done}/{self.total} ({elapsed:.1f} s)", end="", file=sys.stderr,
                  flush=True)
            if self.done == self.total:
                print(file=sys.stderr)


# -- the batched engine ----------------------------------------------------------------------------

@dataclass
class _EpisodeResult:
    actions: np.ndarray       # (B, N, R)
    optimal: np.ndarray       # (B, N, R)
    theta_hat: np.ndarray     # (B, R, S)
    error: np.ndarray         # (B,)
    rho1: np.ndarray          # (B,)
    rho2: np.ndarray          # (B,)
    first_input: np.ndarray   # (B, N) s
    drawing: np.ndarray       # (B, N) s


def ridge_maps(Phi: np.ndarray, theta: np.ndarray, lam: float):
    """The ridge map A, the optimal arrows U_bar and rho1 for a stack of feature matrices.

    Args:
        Phi: (K, N, S) features of K sets of query states (each of full column rank).
        theta: (R, S) the skill.
        lam: the ridge parameter.

    Returns:
        (A (K, S, N), U_bar (K, N, R), rho1 (K,)).
    """
    left, singular, right_t = np.linalg.svd(Phi, full_matrices=False)
    gains = singular / (singular**2 + lam)
    A = np.einsum("kis,ks,kjs->kij", np.swapaxes(right_t, 1, 2), gains, left)
    U_bar = np.einsum("kns,ks,ksr->knr", left, 1 / gains, right_t @ theta.T)
    return A, U_bar, gains.max(axis=1)


def _simulate(protocol, population: TeacherPopulation, groups: np.ndarray, study_of: np.ndarray,
              states_by_episode: list[np.ndarray], progress: Progress | None = None,
              keep_demonstrations: bool = True) -> list[_EpisodeResult]:
    """Runs B teachers through the protocol's episodes.

    Args:
        protocol: the ``Protocol``.
        population: B teachers.
        groups: (B,) group names.
        study_of: (B,) index of each teacher's study (into the first axis of the states).
        states_by_episode: per episode, (K, N, state_dim) query states of each of K studies.
        progress: ticked once per episode.
        keep_demonstrations: keep actions, optimal arrows and timings (off for power runs).
    """
    results = []
    for e, step in enumerate(episode_plan(protocol)):
        skill = SKILLS[step["skill"]]
        guided = np.isin(groups, list(step["guidance"]))
        states = states_by_episode[e]
        Phi = skill.features(states.reshape(-1, states.shape[-1])).reshape(states.shape[:2] + (-1,))
        A, U_bar, rho1 = ridge_maps(Phi, skill.theta, protocol.lam)
        positions, _ = skill.end_effector(states)
        offsets = naive_offsets(positions, skill.target)[study_of]                  # (B, N, 2)
        anchor = imagined_line_target(protocol, step["phase_index"])
        along = None if anchor is None else along_line_offsets(positions, skill.target, anchor)[study_of]
        optimal = U_bar[study_of]                                                    # (B, N, R)
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
        theta_hat = np.swapaxes(np.einsum("bsn,bnr->bsr", A[study_of], actions), 1, 2)
        error = np.linalg.norm((theta_hat - skill.theta).reshape(len(groups), -1), axis=1)
        rho2 = np.linalg.norm((actions - optimal).reshape(len(groups), -1), axis=1)
        population.see_reproduction()
        results.append(_EpisodeResult(actions if keep_demonstrations else None,
                                      optimal if keep_demonstrations else None, theta_hat, error,
                                      rho1[study_of], rho2, first, drawing))
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


def participant_id(index: int) -> str:
    """The code of synthetic participant ``index`` in logs ("S001")."""
    return f"S{index + 1:03d}"


def run_in_silico(n_participants: int = 32, protocol=None, parameters: TeacherParameters | None = None,
                  seed: int = 0, groups=None, reproduce: bool = True, record_every: int = 10,
                  progress: bool | None = None, study_name: str | None = None) -> InSilicoStudy:
    """Runs one study of synthetic teachers through the whole protocol.

    Args:
        n_participants: how many participants.
        protocol: a ``Protocol``, a shipped name ("paper-sim", "paper-uarm") or a file path.
        parameters: the teacher model's parameters (default: the protocol's fit, ``PAPER_FIT`` or
            ``PAPER_FIT_UARM``; see ``default_parameters``).
        seed: root seed of the teachers (and of the group assignment when ``groups`` is None).
        groups: a group name per participant (default: the protocol's block randomisation,
            seeded).
        reproduce: roll out every learnt skill (what participants watch after each episode).
        record_every: control steps between recorded samples of each reproduction.
        progress: show a progress bar (default: only for runs of more than 1000 participants).
        study_name: the ``study`` column (default: the protocol's name + "-in-silico").

    Returns:
        An ``InSilicoStudy``.
    """
    protocol = resolve_protocol(protocol)
    if isinstance(n_participants, bool) or not isinstance(n_participants, (int, np.integer)) or n_participants < 1:
        raise ValueError(f"n_participants: expected a whole number >= 1, got {n_participants!r}")
    parameters = default_parameters(protocol) if parameters is None else parameters
    if groups is None:
        groups = assign_groups(n_participants, protocol.groups, protocol.block_size, seed)
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
    results = _simulate(protocol, population, groups.astype(str), study_of, states, bar)
    teaching_s = time.perf_counter() - started

    started = time.perf_counter()
    reproductions, diverged = {}, np.zeros((n_participants, len(plan)), dtype=bool)
    if reproduce:
        for skill_key in dict.fromkeys(step["skill"] for step in plan):
            columns = [e for e, step in enumerate(plan) if step["skill"] == skill_key]
            thetas = np.concatenate([results[e].theta_hat for e in columns])
            duration = protocol.reproduction_duration_s
            batch = SKILLS[skill_key].reproduce(thetas, duration=duration, record_every=record_every)
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
            theta_hats[(pid, step["phase"], step["episode"])] = r.theta_hat[p]
            episode_rows.append({
                "study": name, "participant": pid, "group": groups[p], "phase": step["phase"],
                "phase_index": step["phase_index"], "episode": step["episode"], "skill": step["skill"],
                "guidance": int(guided), "n_demonstrations": step["demonstrations"],
                "teaching_error": float(r.error[p]), "rho1": float(r.rho1[p]), "rho2": float(r.rho2[p]),
                "theta_hat": json.dumps(np.round(r.theta_hat[p], 12).tolist()),
                "reproduction_diverged": bool(diverged[p, e]) if reproduce else None,
                "started_at": clock, "duration_s": duration})
            clock += duration
            for d in range(step["demonstrations"]):
                demonstration_rows.append({
                    "study": name, "participant": pid, "group": groups[p], "phase": step["phase"],
                    "phase_index": step["phase_index"], "episode": step["episode"], "index": d,
                    "skill": step["skill"], "state": json.dumps(states[e][study_of[p], d].tolist()),
                    "action_1": float(r.actions[p, d, 0]), "action_2": float(r.actions[p, d, 1]),
                    "optimal_1": float(r.optimal[p, d, 0]), "optimal_2": float(r.optimal[p, d, 1]),
                    "guidance_shown": int(guided), "time_to_first_input_s": float(r.first_input[p, d]),
                    "drawing_duration_s": float(r.drawing[p, d])})
    return InSilicoStudy(protocol, population.parameters, seed, pd.DataFrame(episode_rows),
                         pd.DataFrame(demonstration_rows), theta_hats, reproductions,
                         {"teaching_s": teaching_s, "rollout_s": rollout_s})


def run_many_studies(n_studies: int, n_per_group: int, seed: int = 0, parameters: TeacherParameters | None = None,
                     changes=None, progress: bool | None = None, protocol=None, share_states: bool = False,
                     workers: int | None = None) -> dict:
    """Many independent studies at once, reduced to each participant's changes.

    Every study has its own participants and its own query states (its own study seed), and
    2 * n_per_group participants split equally between the first two groups.

    Args:
        n_studies: studies to simulate.
        n_per_group: participants per group in each.
        seed: root seed.
        parameters: ``TeacherParameters`` (default: the protocol's fit, ``default_parameters``).
        changes: ``Change`` comparisons (default the paper's three).
        progress: show a progress bar (default: for more than 50 studies).
        protocol: the ``Protocol`` (default the paper's simulation protocol).
        share_states: use the protocol's own query states in every study (isolates the
            teachers' variability; used when fitting).
        workers: processes drawing the studies' query states, the slow part (default: up to
            2 for 100 studies or more, else 1). The result does not depend on it.

    Returns:
        {change name: {group: (n_studies, n_per_group) array of after - before}}.
    """
    protocol = resolve_protocol(protocol)
    parameters = default_parameters(protocol) if parameters is None else parameters
    for name, value in (("n_studies", n_studies), ("n_per_group", n_per_group)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"{name}: expected a whole number >= 1, got {value!r}")
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
                            shared=share_states)


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
    import os
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
            from concurrent.futures import ProcessPoolExecutor
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
                     shared: bool | None = None) -> dict:
    """Runs a drawn population as ``n_studies`` studies and returns each participant's changes.

    Args:
        protocol: the ``Protocol``.
        population: n_studies * 2 * n_per_group teachers; in each study the first n_per_group
            are in the first group, the next in the second.
        n_studies: how many studies.
        n_per_group: participants per group.
        states: per episode, (n_studies, N, state_dim) query states, or (1, N, state_dim)
            shared by all studies.
        changes: ``Change`` comparisons (default the paper's three).
        progress: ticked once per episode.
        shared: whether all studies share one set of states (default: from ``states``).

    Returns:
        {change name: {group: (n_studies, n_per_group) after - before,
        "before": (n_studies, 2 n_per_group) the earlier episode's errors}}.
    """
    from .statistics import PAPER_CHANGES
    changes = PAPER_CHANGES if changes is None else tuple(changes)
    plan = episode_plan(protocol)
    per_study = 2 * n_per_group
    if len(population) != n_studies * per_study:
        raise ValueError(f"population: expected {n_studies * per_study} teachers, got {len(population)}")
    shared = states[0].shape[0] == 1 if shared is None else shared
    groups = np.tile(np.repeat(np.asarray(protocol.groups[:2]), n_per_group), n_studies)
    study_of = np.zeros(n_studies * per_study, dtype=int) if shared else np.repeat(np.arange(n_studies), per_study)
    results = _simulate(protocol, population, groups, study_of, states, progress, keep_demonstrations=False)
    errors = np.stack([r.error for r in results], axis=1)       # (B, episodes)
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


# -- how near the paper ---------------------------------------------------------------------------

#: The paper's rows whose names differ from ``PAPER_CHANGES``' and whose sign is flipped: the
#: physical experiment prints its P1 -> P4 row as an improvement (positive = better).
_PRINTED_AS_IMPROVEMENT = {"P1_to_P4_improvement": "P1_to_P4"}


def paper_changes(reference: dict | None = None, experiment: str = "simulation") -> dict:
    """The paper's changes of one experiment, every row as later minus earlier (negative = better).

    Args:
        reference: the paper's results (default: ``paper_results()``).
        experiment: "simulation" or "physical".

    Returns:
        {change name (as in ``PAPER_CHANGES``): {group: {"mean", "sd"}}}; a row printed as an
        improvement has its mean negated and keeps its SD.
    """
    reference = paper_results() if reference is None else reference
    if experiment not in reference:
        raise ValueError(f"experiment: expected one of {sorted(k for k in reference if 'changes' in reference[k])}, "
                         f"got {experiment!r}")
    out = {}
    for name, groups in reference[experiment]["changes"].items():
        flip = name in _PRINTED_AS_IMPROVEMENT
        out[_PRINTED_AS_IMPROVEMENT.get(name, name)] = {
            group: {"mean": -values["mean"] if flip else values["mean"], "sd": values["sd"]}
            for group, values in groups.items() if isinstance(values, dict)}
    return out


def experiment_of(protocol) -> str:
    """The paper's experiment a protocol replicates: "physical" on the uArm, else "simulation"."""
    from .synthetic_teachers import runs_on_uarm
    return "physical" if runs_on_uarm(resolve_protocol(protocol)) else "simulation"


def compare_with_paper(result, reference: dict | None = None, experiment: str | None = None) -> pd.DataFrame:
    """Row-by-row comparison of an in-silico study's changes with the paper's.

    Args:
        result: an ``InSilicoStudy``, or episode rows.
        reference: the paper's results (default: ``paper_results()``).
        experiment: "simulation" or "physical" (default: the study's protocol's, else
            "simulation"). The physical experiment's P1 -> P4 row, printed as an improvement,
            is compared as later minus earlier like the others (``paper_changes``).

    Returns:
        One row per (change, group): the paper's mean and SD, the in-silico mean and SD, and
        how near: ``mean_gap`` (in-silico minus paper) and ``mean_gap_in_sd`` (the gap in units
        of the paper's SD), ``sd_ratio`` (in-silico / paper).
    """
    from .statistics import change_summary, participant_changes
    if experiment is None:
        experiment = experiment_of(result.protocol) if isinstance(result, InSilicoStudy) else "simulation"
    episodes = result.episodes if isinstance(result, InSilicoStudy) else result
    summary = change_summary(participant_changes(episodes)).set_index(["change", "group"])
    rows = []
    for name, groups in paper_changes(reference, experiment).items():
        for group, values in groups.items():
            if (name, group) not in summary.index:
                continue
            s = summary.loc[(name, group)]
            rows.append({"change": name, "group": group, "paper_mean": values["mean"], "paper_sd": values["sd"],
                         "in_silico_mean": float(s["mean"]), "in_silico_sd": float(s["sd"]),
                         "mean_gap": float(s["mean"]) - values["mean"],
                         "mean_gap_in_sd": (float(s["mean"]) - values["mean"]) / values["sd"],
                         "sd_ratio": float(s["sd"]) / values["sd"], "n": int(s["n"])})
    return pd.DataFrame(rows)


def baseline_comparison(result, reference: dict | None = None, experiment: str | None = None) -> pd.DataFrame:
    """The baselines (P1 and P2 teaching errors) of an in-silico study against the paper's.

    The paper prints no baseline means; they follow from each target-group change and its
    percentage reduction (baseline = -change / percent), e.g. P2 in simulation 1.47 / 50.03 %
    = 2.94. Groups are pooled in silico (the randomisation makes them alike at baseline).

    Args:
        result: an ``InSilicoStudy``, or episode rows.
        reference: the paper's results (default: ``paper_results()``).
        experiment: "simulation" or "physical" (default: as ``compare_with_paper``).

    Returns:
        One row per baseline phase: ``phase``, ``paper_mean`` (implied), ``in_silico_mean``,
        ``in_silico_sd``, ``n``.
    """
    from .synthetic_teachers import implied_baselines
    if experiment is None:
        experiment = experiment_of(result.protocol) if isinstance(result, InSilicoStudy) else "simulation"
    episodes = result.episodes if isinstance(result, InSilicoStudy) else result
    frame = pd.DataFrame(episodes)
    rows = []
    for phase, paper in implied_baselines(reference, experiment).items():
        errors = frame[(frame.phase == phase) & (frame.episode == 1)].teaching_error.to_numpy(dtype=float)
        rows.append({"phase": phase, "paper_mean": paper, "in_silico_mean": float(errors.mean()),
                     "in_silico_sd": float(errors.std(ddof=1)) if errors.size > 1 else float("nan"),
                     "n": int(errors.size)})
    return pd.DataFrame(rows)


#: The paper's printed summary figures (docs/design.md, "Reported results"): per
#: experiment the changes (mean and SD per group) and the target group's percentage reductions.
PAPER_RESULTS = {
    "simulation": {
        "p1_vs_p2_posthoc_p": [0.0989, 0.1148],
        "changes": {
            "P1_to_P3E8": {"target": {"mean": -2.03, "sd": 0.82}, "control": {"mean": 0.025, "sd": 0.53}},
            "P1_to_P4": {"target": {"mean": -1.51, "sd": 0.84}, "control": {"mean": -0.22, "sd": 0.56}},
            "P2_to_P5": {"target": {"mean": -1.47, "sd": 0.80}, "control": {"mean": -0.06, "sd": 0.64}},
        },
        "percent_reduction_target": {"during_P3": 69.40, "P4_vs_P1": 51.47, "P5_vs_P2": 50.03},
    },
    "physical": {
        "changes": {
            "P1_to_P3E8": {"target": {"mean": -5.30, "sd": 1.79}, "control": {"mean": -1.54, "sd": 3.44}},
            # Printed as an improvement (positive = better), unlike the other rows.
            "P1_to_P4_improvement": {"target": {"mean": 4.55, "sd": 1.80}, "control": {"mean": -0.35, "sd": 2.46}},
            "P2_to_P5": {"target": {"mean": -6.32, "sd": 2.92}, "control": {"mean": 2.21, "sd": 5.54}},
        },
        "percent_reduction_target": {"P3E8_vs_P1": 88.26, "P5_vs_P2": 77.34},
    },
}

#: The simulation experiment alone (kept for code that read it before the physical rows came).
PAPER_SIMULATION_RESULTS = {"simulation": PAPER_RESULTS["simulation"]}


def paper_results() -> dict:
    """The paper's reported results of both experiments (a fresh copy: changes, % reductions)."""
    return json.loads(json.dumps(PAPER_RESULTS))


# -- through the session engine: real logs ---------------------------------------------------------

class SessionTeacher:
    """One synthetic teacher driving a ``Session`` exactly as the study app drives it for a person.

    The teacher sees what a participant sees: the episode's query states as they appear, and
    after each demonstration the optimal arrow only when the session shows guidance. Its arrows
    are those the batched engine computes for the same seed (the same model, the same draws).

    Args:
        protocol: the ``Protocol``.
        parameters: ``TeacherParameters`` (default: the protocol's fit, ``default_parameters``).
        seed: the teacher's seed (``teacher_seed(run_seed, participant)``).
    """

    def __init__(self, protocol, parameters: TeacherParameters | None, seed):
        self.protocol = protocol
        self.plan = episode_plan(protocol)
        self._episode_of = {(step["phase_index"], step["episode"]): e for e, step in enumerate(self.plan)}
        parameters = default_parameters(protocol) if parameters is None else parameters
        self.population = TeacherPopulation.draw(parameters, [seed], len(self.plan),
                                                 max(step["demonstrations"] for step in self.plan))
        self._episode = None

    def run(self, session) -> list:
        """Takes the session from its current step to the end; returns the ``EpisodeResult``s."""
        results = []
        while not session.finished:
            step = session.current_step()
            if step.kind == "demonstration":
                self.demonstrate(session, step)
            elif step.kind == "episode_end":
                results.append(session.finish_episode())
                self.population.see_reproduction()
            elif step.kind == "practice":
                session.finish_practice(duration_s=float(step.duration_s or 0.0))
            else:
                session.advance()
        return results

    def demonstrate(self, session, step) -> None:
        """Draws one arrow for the current query state and submits it with its timings."""
        from mt_widgets.core import optimal_actions
        skill = SKILLS[step.skill]
        e = self._episode_of[(step.phase_index, step.episode)]
        if self._episode is None or self._episode[0] != e:
            # What the teacher works from for this episode: where the target is from each tip
            # position, and the optimal arrows its understanding blends in.
            positions, _ = skill.end_effector(step.query_states)
            optimal = optimal_actions(skill.features(step.query_states), skill.theta, self.protocol.lam)
            anchor = imagined_line_target(self.protocol, step.phase_index)
            along = None if anchor is None else along_line_offsets(positions, skill.target, anchor)
            self._episode = (e, naive_offsets(positions, skill.target), optimal, along)
        _, offsets, optimal, along = self._episode
        d = step.index
        guided = np.array([bool(step.guidance)])
        action = self.population.act(e, d, offsets[d][None], optimal[d][None], position_gain(skill.theta),
                                     skill.key, guided, None if along is None else along[d][None])[0]
        first, drawing = self.population.timings(e, d, guided)
        session.submit_demonstration(action, {"time_to_first_input_s": float(first[0]),
                                              "drawing_duration_s": float(drawing[0]), "method": "synthetic"},
                                     index=d)
        self.population.see_guidance(skill.key, guided)


def run_through_sessions(folder, n_participants: int = 8, protocol=None, parameters: TeacherParameters | None = None,
                         seed: int = 0, groups=None, progress: bool | None = None):
    """Runs synthetic teachers through the session engine into a real study folder.

    Every participant is enrolled, assigned to a group (by the protocol's randomisation unless
    ``groups`` says otherwise) and driven step by step through ``Session``, so the folder holds
    the same logs a real study writes and ``read_study`` / the analysis read it unchanged.
    Participant i is seeded ``teacher_seed(seed, i)``: ``run_in_silico`` with the same seed and
    groups gives the same arrows and teaching errors.

    Args:
        folder: the study folder (created; must not hold another protocol's study).
        n_participants: participants to run, coded "S001", "S002", ...
        protocol: a ``Protocol``, a shipped name or a path (default "paper-sim").
        parameters: ``TeacherParameters`` (default: the protocol's fit, ``default_parameters``).
        seed: root seed of the teachers.
        groups: a group per participant, or None for the protocol's randomisation.
        progress: show a progress bar (default: for more than 16 participants).

    Returns:
        The ``StudyFolder``.
    """
    from .log import StudyFolder
    from .session import Session
    protocol = resolve_protocol(protocol)
    if isinstance(n_participants, bool) or not isinstance(n_participants, (int, np.integer)) or n_participants < 1:
        raise ValueError(f"n_participants: expected a whole number >= 1, got {n_participants!r}")
    if groups is not None and len(list(groups)) != n_participants:
        raise ValueError(f"groups: expected {n_participants} group names, got {len(list(groups))}")
    study = StudyFolder.create(folder, protocol)
    bar = Progress(n_participants, "participants", progress if progress is not None else n_participants > 16)
    for p in range(n_participants):
        session = Session.start(study, participant_id(p), group=None if groups is None else list(groups)[p])
        try:
            SessionTeacher(protocol, parameters, teacher_seed(seed, p)).run(session)
        finally:
            session.close()
        bar.update()
    return study
