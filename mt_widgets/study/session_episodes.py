"""The task's episodes in a session: their ``TeachingEpisode``s, demonstrations and results.

Each study episode has one ``TeachingEpisode``, built when its first demonstration step is
entered (``episode_started`` logs its query states) or, on resume, from the log (each logged
demonstration recorded as it was given). It is the one place the episode's demonstrations
live: the step's view shows it and demonstrates into it, ``submit_demonstration`` logs each
demonstration and then records it in it (a view's ``Demonstration``: that very object),
``Step.actions`` and the ``EpisodeResult`` read it, and ``finish_episode`` logs what it learnt.
A mixin of ``mt_widgets.study.session.Session``.
"""

from __future__ import annotations

import datetime as _dt
import time
from collections.abc import Mapping

import numpy as np

from mt_widgets.core import Demonstration, TeachingEpisode
from mt_widgets.core.validation import as_positive

from .log import to_jsonable
from .session_types import EpisodeResult, Feedback, SessionStateError
from .study_learners import learner_parameters, learnt_actions, study_learner
from .timeline import Slot, episode_query_states

#: Timing keys ``submit_demonstration`` reads (seconds, None when unknown).
TIMING_KEYS = ("time_to_first_input_s", "drawing_duration_s")


def _parse_time(stamp: str) -> float:
    return _dt.datetime.fromisoformat(stamp.replace("Z", "+00:00")).timestamp()


def _check_seconds(name: str, value):
    """A duration in seconds (>= 0), or None for "not measured"."""
    return None if value is None else as_positive(name, value, allow_zero=True)


class SessionEpisodes:
    """The episode steps of a ``Session`` (demonstrations, episode ends, results); mixed into ``Session``."""

    def _start_episode(self, slot: Slot) -> None:
        phase = self._phase(slot)
        skill = self.protocol.skills[phase.skill]
        states, seed = episode_query_states(self.protocol, phase.states_index, slot.episode, phase.demonstrations,
                                            phase.skill, participant=self.enrolment["index"])
        teaching = self._new_teaching_episode(skill, states)
        event = self.log.append(
            "episode_started", phase=phase.id, phase_index=phase.index, episode=slot.episode, skill=phase.skill,
            guidance=phase.guidance_for(self.group), guidance_modality=self.protocol.guidance_modality,
            n_demonstrations=phase.demonstrations, query_states=states,
            features=teaching.features, theta=skill.theta, lam=self.protocol.lam, optimal=teaching.optimal_actions,
            exact=teaching.exact, seed={"study_seed": self.protocol.seed, "spawn_key": list(seed.spawn_key)},
            **self._learner_fields(teaching))
        self._episodes[(phase.index, slot.episode)] = event
        # Kept: the step's view shows this episode and the log records it (one per episode). The
        # episodes before it are over (every step reads its own episode only) and each holds its
        # reproduction (about 0.8 MB for the simulated arm's 1 kHz rollout): kept, a session's
        # memory grew by that much per episode (tests/study/test_long_session.py).
        self._teaching_episodes.clear()
        self._teaching_episodes[(phase.index, slot.episode)] = teaching

    def _new_teaching_episode(self, skill, states) -> TeachingEpisode:
        """The episode of ``skill`` on ``states`` with this protocol's learner (``study_learner``:
        ridge's lambda is the protocol's) and reproduction length."""
        return TeachingEpisode(skill, states, duration=self.protocol.reproduction_duration_s,
                               learner=study_learner(self.protocol, skill))

    def _learner_fields(self, teaching: TeachingEpisode) -> dict:
        """What ``episode_started`` logs of a learner without a Theta on the features: its name and
        parameters (a learner with one logs Theta_hat and the analysis: the paper protocols' log
        stays as it was)."""
        if teaching.has_theta:
            return {}
        return {"learner": self.protocol.learner, "learner_parameters": learner_parameters(teaching.learner)}

    def _episode_from_log(self, key, events) -> TeachingEpisode:
        """The episode a log describes: on its logged states, each logged demonstration recorded
        as it was given (action, method, timings), so a resumed view shows what the log holds."""
        started = self._episodes[key]
        episode = self._new_teaching_episode(self.protocol.skills[started["skill"]],
                                             np.asarray(started["query_states"], dtype=float))
        for event in events:
            given = event.get("input") or {}
            redraws = given.get("redraws", 0)
            episode.demonstrate(event["action"], method=str(given.get("method", "code")),
                                time_to_first_input_s=event.get("time_to_first_input_s"),
                                drawing_duration_s=event.get("drawing_duration_s"),
                                redraws=redraws if isinstance(redraws, int) and not isinstance(redraws, bool) else 0,
                                confirmed_at=_parse_time(event["time"]), guidance_shown=bool(event["guidance_shown"]),
                                episode_index=key[1] - 1)
        return episode

    def _result(self, key) -> EpisodeResult:
        started = self._episodes[key]
        return EpisodeResult(self._teaching_episodes[key], phase=started["phase"], phase_index=key[0],
                             episode_number=key[1])

    def submit_demonstration(self, action, timings: Mapping | None = None, index: int | None = None) -> Feedback:
        """Records the action for the current query state; returns once it is on disk.

        Args:
            action: (R,) the demonstrated action, in the skill's action units; or the
                ``Demonstration`` a view built from the step's ``teaching_episode`` (its method,
                timings and redraws are logged, and that very object is what the episode keeps).
            timings: ``time_to_first_input_s`` and ``drawing_duration_s`` in seconds (None
                when unknown), plus any other input details to log (method, redraws, ...); None
                with a ``Demonstration``, which carries its own.
            index: the 0-based demonstration the caller means; if given and not the current
                one the call is refused (a double click cannot record an action twice).

        Returns:
            ``Feedback``: the optimal action if this episode shows guidance, else None.
        """
        slot = self._expect("submit_demonstration", "demonstration")
        if index is not None and index != slot.index:
            raise SessionStateError(f"index: expected the current demonstration {slot.index}, got {index}; "
                                    f"it was already recorded or is not reached yet")
        key = (slot.phase_index, slot.episode)
        started = self._episodes[key]
        teaching = self._teaching_episodes[key]
        if isinstance(action, Demonstration):
            demonstration = action
            if timings is not None:
                raise ValueError(f"timings: expected None with a Demonstration (it carries its own), got "
                                 f"{type(timings).__name__}")
            if demonstration.index != slot.index or not np.array_equal(demonstration.state,
                                                                        teaching.query_states[slot.index]):
                raise SessionStateError(f"action: expected a Demonstration at the current state {slot.index} of "
                                        f"{self._describe(slot)}, got one at state {demonstration.index} of "
                                        f"another episode or state")
            timings = {"time_to_first_input_s": demonstration.time_to_first_input_s,
                       "drawing_duration_s": demonstration.drawing_duration_s, "method": demonstration.method,
                       "redraws": demonstration.redraws}
        else:
            try:
                teaching.check_action(action)
            except ValueError as error:  # the episode's own check, said for this step
                raise ValueError(f"action: expected {teaching.action_dim} finite numbers, got {action!r}: "
                                 f"{error}"[:300]) from None
            demonstration = None
        if timings is None:
            timings = {}
        if not isinstance(timings, Mapping):
            raise ValueError(f"timings: expected a mapping (e.g. {{'time_to_first_input_s': 1.2, "
                             f"'drawing_duration_s': 0.8}}) or None, got {type(timings).__name__} {timings!r}")
        timings = dict(timings)
        measured = {key_: _check_seconds(f"timings[{key_!r}]", timings.pop(key_, None)) for key_ in TIMING_KEYS}
        for name, value in timings.items():  # refused here, by name, rather than inside the log write
            try:
                to_jsonable(value)
            except TypeError:
                raise ValueError(f"timings[{name!r}]: expected JSON-like data (numbers, text, lists, dicts), "
                                 f"got {type(value).__name__}") from None
        if demonstration is None:
            redraws = timings.get("redraws", 0)
            demonstration = teaching.analyse(
                action, method=str(timings.get("method", "code")), **measured,
                redraws=redraws if isinstance(redraws, int) and not isinstance(redraws, bool) else 0,
                confirmed_at=time.time(), guidance_shown=started["guidance"], episode_index=slot.episode - 1)
        optimal = np.asarray(started["optimal"])[slot.index]
        self.log.append("demonstration", phase=started["phase"], phase_index=slot.phase_index, episode=slot.episode,
                        index=slot.index, state=np.asarray(started["query_states"])[slot.index],
                        action=demonstration.action, optimal=optimal, guidance_shown=started["guidance"], **measured,
                        response_time_s=time.monotonic() - self._entered_at, input=timings,
                        modality="hand" if timings.get("method") == "hand" else "drawn")
        teaching.record(demonstration)  # on disk: now the episode keeps it (a view's record: that object)
        self._complete()
        return Feedback(slot.index, started["guidance"], optimal.copy() if started["guidance"] else None,
                        demonstration.action, started["guidance_modality"])

    def finish_episode(self, episode: TeachingEpisode | None = None) -> EpisodeResult:
        """Records the finished episode (what was learnt, its error and its reproduction) in the log.

        Args:
            episode: the ``TeachingEpisode`` a view ran on this step's query states with the
                logged actions, when it is not the step's own ``teaching_episode`` (which a view
                normally demonstrates into); it is checked against the log and kept as it is, so
                its one reproduction serves both the view and the log. None: the step's own.

        Returns:
            The ``EpisodeResult`` (the next step is the reproduction).
        """
        slot = self._expect("finish_episode", "episode_end")
        key = (slot.phase_index, slot.episode)
        started = self._episodes[key]
        if episode is not None and episode is not self._teaching_episodes[key]:
            self._check_recorded(episode, started, self._teaching_episodes[key])
            self._teaching_episodes[key] = episode
        teaching = self._teaching_episodes[key]
        trajectory = teaching.reproduction
        if teaching.has_theta:
            theta_hat, bound, residual, learnt = teaching.theta_hat, teaching.bound, teaching.residual_norm, {}
        else:
            # No Theta: what every learner gives, its fitted policy at the query states (the
            # policy itself comes back from the logged states and actions: study_learners).
            theta_hat = bound = residual = None
            learnt = {"learner": self.protocol.learner, "learnt_actions": learnt_actions(teaching)}
        self.log.append(
            "episode_finished", phase=started["phase"], phase_index=slot.phase_index, episode=slot.episode,
            skill=started["skill"], guidance=started["guidance"], actions=teaching.actions,
            optimal=teaching.optimal_actions, theta_hat=theta_hat, theta_error=teaching.theta_error,
            policy_risk=teaching.policy_risk,
            rho1=teaching.rho1, rho2=teaching.rho2, bound=bound, residual=residual,
            contributions=teaching.contribution_norms, exact=teaching.exact, **learnt,
            reproduction={"diverged": trajectory.diverged, "diverged_at": trajectory.diverged_at,
                          "final_position": trajectory.final_position, "duration_s": float(trajectory.times[-1])},
            started_at=started["time"], duration_s=max(0.0, time.time() - _parse_time(started["time"])))
        result = self._result(key)  # before moving on: the next episode may start (and drop this one) there
        self._finished.add(key)
        self._complete()
        return result

    def _check_recorded(self, episode, started: dict, logged: TeachingEpisode) -> None:
        """Refuses an episode that is not the one this step logged (other states, actions, lambda...)."""
        if not isinstance(episode, TeachingEpisode):
            raise ValueError(f"episode: expected a TeachingEpisode or None, got {type(episode).__name__}")
        duration = self.protocol.reproduction_duration_s
        duration = self.protocol.skills[started["skill"]].default_duration if duration is None else duration
        checks = (
            ("skill", episode.skill.key == started["skill"]
             and np.array_equal(episode.skill.theta, np.asarray(started["theta"], dtype=float)),
             f"the skill {started['skill']!r} and its theta", repr(episode.skill.key)),
            ("lam", episode.lam == logged.lam, f"the protocol's lam {logged.lam}", episode.lam),
            ("learner", repr(episode.learner) == repr(logged.learner), f"the protocol's learner {logged.learner!r}",
             repr(episode.learner)),
            ("duration", episode.duration == duration, f"the protocol's reproduction of {duration} s",
             episode.duration),
            ("query_states", np.array_equal(episode.query_states, np.asarray(started["query_states"], dtype=float)),
             "this step's logged query states", "other states"),
            ("actions", episode.complete and np.array_equal(episode.actions, logged.actions),
             f"the {len(logged.demonstrations)} logged actions, all given",
             f"{len(episode.demonstrations)} other or fewer"),
        )
        for name, ok, wanted, got in checks:
            if not ok:
                raise ValueError(f"episode: expected a TeachingEpisode with {wanted} (episode.{name}), got {got}")
