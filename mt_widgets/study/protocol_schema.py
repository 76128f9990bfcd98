"""Validating a protocol file: TOML or JSON text -> a ``Protocol``, or a ``ProtocolError`` naming
the file, the line and the field, the value expected and the value found.

The format is documented in ``mt_widgets.study.protocol``; the sessions' tables in
``mt_widgets.study.session_plan``, the ``[online]`` table in ``mt_widgets.study.online``, the
steps around the task in ``mt_widgets.study.steps``.

TOML needs ``tomllib`` (Python >= 3.11); on Python 3.10 the ``tomli`` package (the same parser,
in pyproject.toml's ``analysis`` extra there) is used.
"""

from __future__ import annotations

import copy
import json
import math
import re
from pathlib import Path
from typing import Any

try:  # Python >= 3.11
    import tomllib as _toml
except ModuleNotFoundError:  # pragma: no cover - exercised only on Python 3.10
    try:
        import tomli as _toml  # type: ignore[no-redef]
    except ModuleNotFoundError:
        _toml = None

from mt_widgets.core.guidance import GUIDANCE_MODALITIES
from mt_widgets.core.learner_teaching import LEARNERS
from mt_widgets.core.validation import as_bool

from .analysis_plan import ALTERNATIVES, PAPER_CHANGES, TESTS, AnalysisPlan, Change, changes_that_fit
from .online import parse_online
from .protocol_arm import check_arm_skills, resolve_protocol_arm
from .protocol_model import OPTIONAL_TEXTS, Phase, Practice, Protocol, ProtocolError, ProtocolSkills
from .protocol_source import SourceLocator, path_name
from .session_plan import ProtocolSession, bids_label, parse_window
from .skill_modules import resolve_protocol_skills
from .steps import WITHDRAWAL_POLICIES, parse_steps
from .timeline import REPRODUCTION_TIMINGS

#: The protocol file format this code reads (``format = 1`` at the top of every protocol).
FORMAT_VERSION = 1
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,63}$")
_TEXT_KEYS = ("welcome", "consent", "instructions", "reproduction", "thank_you")


class Checker:
    """Reads fields of a protocol's tables, failing with a ``ProtocolError`` that names the line."""

    def __init__(self, locator: SourceLocator, source: str):
        self.locator, self.source = locator, source

    def fail(self, path: tuple, message: str):
        raise ProtocolError(message, self.source, self.locator.line(path), path_name(path))

    def get(self, table: dict, path: tuple, kind: str, default: Any = ..., **limits):
        key = path[-1]
        if key not in table:
            if default is ...:
                self.fail(path, f"missing required field ({kind})")
            return default
        value = table[key]
        if kind == "text":
            if not isinstance(value, str):
                self.fail(path, f"expected text, got {type(value).__name__} {value!r}"[:200])
            if limits.get("nonempty") and not value.strip():
                self.fail(path, "expected non-empty text, got an empty string")
            if limits.get("name") and not _NAME.match(value):
                self.fail(path, f"expected a plain name (letters, digits, '-', '_'; at most 64 characters), "
                                f"got {value!r}")
            if "choices" in limits and value not in limits["choices"]:
                self.fail(path, f"expected one of {list(limits['choices'])}, got {value!r}")
            return value
        if kind in ("integer", "count"):
            if isinstance(value, bool) or not isinstance(value, int):
                self.fail(path, f"expected an integer, got {type(value).__name__} {value!r}")
            low = limits.get("minimum", 0)
            high = limits.get("maximum")
            if value < low or (high is not None and value > high):
                bounds = f">= {low}" + (f" and <= {high}" if high is not None else "")
                self.fail(path, f"expected an integer {bounds}, got {value}")
            return value
        if kind == "number":
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                self.fail(path, f"expected a finite number, got {type(value).__name__} {value!r}")
            if value < limits.get("minimum", -math.inf) or (limits.get("positive") and value <= 0):
                bound = "> 0" if limits.get("positive") else ">= " + str(limits["minimum"])
                self.fail(path, f"expected a number {bound}"
                                f", got {value}")
            return float(value)
        if kind == "table":
            if not isinstance(value, dict):
                self.fail(path, f"expected a table, got {type(value).__name__}")
            return value
        raise AssertionError(kind)

    def unknown(self, table: dict, path: tuple, allowed: tuple):
        for key in table:
            if key not in allowed:
                self.fail(path + (key,), f"unknown field (expected one of {sorted(allowed)}); check its spelling")


def parse_protocol(text: str, source: str = "<string>", kind: str | None = None, check_files: bool = True) -> Protocol:
    """Parses and validates protocol text.

    Args:
        text: TOML or JSON.
        source: a file name for error messages (and the folder a relative video file is in).
        kind: "toml" or "json" (default: from ``source``'s suffix, else TOML).
        check_files: refuse a video file that does not exist (False when a stored protocol is
            rebuilt for analysis, where the study's media need not be present).

    Raises:
        ProtocolError: naming the line and field of the first problem.
    """
    check_files = as_bool("check_files", check_files)
    if not isinstance(text, str):
        raise ValueError(f"text: expected the protocol as a str, got {type(text).__name__}")
    kind = kind or ("json" if str(source).lower().endswith(".json") else "toml")
    if kind not in ("toml", "json"):
        raise ValueError(f"kind: expected 'toml' or 'json', got {kind!r}")
    if kind == "toml":
        if _toml is None:  # pragma: no cover - Python 3.10 with a broken install (tomli is a dependency)
            raise ProtocolError("TOML protocols need Python >= 3.11 (tomllib) or the 'tomli' package, which "
                                "mt-widgets depends on for Python 3.10; reinstall mt-widgets, or write the protocol "
                                "as JSON", source)
        try:
            raw = _toml.loads(text)
        except _toml.TOMLDecodeError as error:
            match = re.search(r"line (\d+)", str(error))
            raise ProtocolError(f"not valid TOML ({error})", source, int(match.group(1)) if match else None) from None
    else:
        try:
            raw = json.loads(text)
        except json.JSONDecodeError as error:
            raise ProtocolError(f"not valid JSON ({error.msg})", source, error.lineno) from None
        if not isinstance(raw, dict):
            raise ProtocolError(f"expected a JSON object at the top, got {type(raw).__name__}", source, 1)
    check = Checker(SourceLocator(text, kind), source)
    skills, skills_table = resolve_protocol_skills(raw, check, source)
    with_arm = dict(skills)
    arm, arm_table = resolve_protocol_arm(raw, check, source, with_arm)
    if arm_table is not None:
        skills = ProtocolSkills(with_arm)

    top_keys = ("format", "name", "title", "groups", "lambda", "seed", "query_states", "reproduction_duration_s",
                "assignment", "texts", "practice", "phases", "skills", "guidance_modality", "withdrawal", "before",
                "after", "analysis", "session", "sessions", "online", "reproduce_after",
                "matched_difficulty", "demonstration_modality", "learner", "arm")
    check.unknown(raw, (), top_keys)
    version = check.get(raw, ("format",), "integer")
    if version != FORMAT_VERSION:
        check.fail(("format",), f"expected format version {FORMAT_VERSION}, got {version}")
    name = check.get(raw, ("name",), "text", name=True)
    title = check.get(raw, ("title",), "text", default=name)
    groups = raw.get("groups", ["target", "control"])
    if not isinstance(groups, list) or not groups or not all(isinstance(g, str) and _NAME.match(g) for g in groups):
        check.fail(("groups",), f"expected a non-empty list of plain names, got {groups!r}")
    if len(set(groups)) != len(groups):
        check.fail(("groups",), f"expected distinct group names, got {groups!r}")
    lam = check.get(raw, ("lambda",), "number", minimum=0.0)
    learner = _parse_learner(check, raw)
    seed = check.get(raw, ("seed",), "integer", minimum=0)
    query_states = check.get(raw, ("query_states",), "text", default="shared", choices=("shared", "per-participant"))
    duration = raw.get("reproduction_duration_s")
    if duration is not None:
        duration = check.get(raw, ("reproduction_duration_s",), "number", positive=True)

    assignment = check.get(raw, ("assignment",), "table")
    check.unknown(assignment, ("assignment",), ("method", "block_size", "seed"))
    check.get(assignment, ("assignment", "method"), "text", default="block", choices=("block",))
    block_size = check.get(assignment, ("assignment", "block_size"), "count", minimum=1, maximum=1000)
    if block_size % len(groups):
        check.fail(("assignment", "block_size"), f"expected a multiple of the {len(groups)} groups so every block "
                                                 f"is balanced, got {block_size}")
    assignment_seed = check.get(assignment, ("assignment", "seed"), "integer", minimum=0)

    texts_raw = check.get(raw, ("texts",), "table")
    check.unknown(texts_raw, ("texts",), _TEXT_KEYS + tuple(OPTIONAL_TEXTS))
    # A protocol with its own consent step says it there; texts.consent is the default consent's.
    own_consent = any(isinstance(e, dict) and e.get("kind") == "consent" for e in raw.get("before", []) or [])
    texts = {key: check.get(texts_raw, ("texts", key), "text", nonempty=True, default="" if own_consent and
                            key == "consent" else ...) for key in _TEXT_KEYS}
    texts.update({key: check.get(texts_raw, ("texts", key), "text", nonempty=True, default=default)
                  for key, default in OPTIONAL_TEXTS.items()})

    practice_raw = check.get(raw, ("practice",), "table")
    check.unknown(practice_raw, ("practice",), ("skill", "duration_s", "text", "reproduction"))
    practice_skill = check.get(practice_raw, ("practice", "skill"), "text")
    if practice_skill not in skills:
        check.fail(("practice", "skill"), f"unknown skill {practice_skill!r}; expected one of {sorted(skills)}")
    practice_reproduction = practice_raw.get("reproduction", True)
    if not isinstance(practice_reproduction, bool):
        check.fail(("practice", "reproduction"), f"expected true or false, got {practice_reproduction!r}")
    practice = Practice(practice_skill, check.get(practice_raw, ("practice", "duration_s"), "number", minimum=0.0),
                        check.get(practice_raw, ("practice", "text"), "text", nonempty=True), practice_reproduction)

    modality = check.get(raw, ("guidance_modality",), "text", default="arrows+words",
                         choices=tuple(GUIDANCE_MODALITIES))
    demonstration_modality = check.get(raw, ("demonstration_modality",), "text", default="drawn",
                                       choices=("drawn", "hand"))
    withdrawal = check.get(raw, ("withdrawal",), "text", default="exclude", choices=WITHDRAWAL_POLICIES)
    folder = Path(source).parent if source not in ("<string>", "") else None
    step_ids: set = set()
    before = parse_steps(check, raw, "before", folder, step_ids, check_files)
    after = parse_steps(check, raw, "after", folder, step_ids, check_files)

    phases_raw = raw.get("phases")
    if not isinstance(phases_raw, list) or not phases_raw:
        check.fail(("phases",), "missing required field: expected at least one [[phases]] table")
    first_id = check.get(raw, ("session",), "text", name=True, default="main")
    phase_ids: dict[str, Phase] = {}
    phases = _parse_phases(check, phases_raw, (), groups, skills, phase_ids, first_id)
    main = ProtocolSession(first_id, 0, phases, before, after, texts, None, practice=True, default_consent=True)
    sessions = [main] + _parse_sessions(check, raw, groups, skills, phase_ids, step_ids, folder, check_files,
                                        texts, first_id)
    if arm is not None:
        check_arm_skills(check, arm, skills, practice, [(("phases", i, "skill"), p) for i, p in enumerate(phases)]
                         + [(("sessions",), p) for session in sessions[1:] for p in session.phases])
    _check_learner_represents(check, learner, sessions, skills)
    online = parse_online(check, raw)
    reproduce_after = check.get(raw, ("reproduce_after",), "text", default="episode", choices=REPRODUCTION_TIMINGS)
    matched = _parse_matched_difficulty(check, raw)
    plan = _parse_analysis(check, raw, phase_ids)
    _check_changes(check, plan, phase_ids)

    data = copy.deepcopy(raw)
    if skills_table is not None:
        data["skills"] = skills_table
    if arm_table is not None:
        data["arm"] = arm_table
    for position, steps in (("before", before), ("after", after)):
        # A video's content is part of the protocol (and so of its hash); its file name stays as
        # written, so the hash does not depend on where the study runs.
        for entry, step in zip(data.get(position, []), steps):
            if step.kind == "video" and step.video_sha256 is not None:
                entry["sha256"] = step.video_sha256
    data.setdefault("groups", list(groups))
    data.setdefault("query_states", query_states)
    data["assignment"].setdefault("method", "block")
    for phase, entry in zip(phases, data["phases"]):
        entry.setdefault("demonstrations", phase.demonstrations)
        entry.setdefault("guidance", [])
    for session, entry in zip(sessions[1:], data.get("sessions", [])):
        for phase, phase_entry in zip(session.phases, entry["phases"]):
            phase_entry.setdefault("demonstrations", phase.demonstrations)
            phase_entry.setdefault("guidance", [])
    return Protocol(name, title, tuple(groups), lam, seed, query_states, duration, block_size, assignment_seed,
                    texts, practice, tuple(phases), data, text, source, skills, guidance_modality=modality,
                    demonstration_modality=demonstration_modality, before=before, after=after,
                    withdrawal=withdrawal, analysis=plan, sessions=tuple(sessions), online=online,
                    reproduce_after=reproduce_after, matched_difficulty=matched, learner=learner)


#: The learners a study can run: every one (its episodes fit and guide with any learner, and the log
#: records what each gives: ``mt_widgets.study.study_learners``).
STUDY_LEARNERS = tuple(LEARNERS)


def _parse_learner(check, raw: dict) -> str:
    """``learner = "..."``: one of ``mt_widgets.core.LEARNERS`` (every one a study can teach:
    ``STUDY_LEARNERS``); "ridge" (the paper's, with ``lambda``) when absent."""
    learner = check.get(raw, ("learner",), "text", default="ridge")
    if learner not in LEARNERS:
        check.fail(("learner",), f"unknown learner {learner!r}; expected one of the available learners "
                                 f"({', '.join(LEARNERS)})")
    return learner


def _check_learner_represents(check, learner: str, sessions, skills) -> None:
    """Refuses a protocol whose learner cannot represent a skill its phases teach (``Learner.
    cannot_represent``): its machine teaching could not teach that skill, and its guidance would
    show arrows toward a policy the learner never reaches."""
    taught = dict.fromkeys(phase.skill for session in sessions for phase in session.phases)
    for key in taught:
        reason = LEARNERS[learner].cannot_represent(skills[key])
        if reason is not None:
            check.fail(("learner",), f"learner {learner!r} cannot represent skill {key!r}: {reason}; choose a "
                                     f"learner that can (one of {', '.join(LEARNERS)}) or another skill")


def _parse_matched_difficulty(check, raw: dict):
    """``[matched_difficulty] sensitivity = [low, high]``: the band of ||A||_F, or None."""
    if "matched_difficulty" not in raw:
        return None
    table = check.get(raw, ("matched_difficulty",), "table")
    check.unknown(table, ("matched_difficulty",), ("sensitivity",))
    band = table.get("sensitivity")
    path = ("matched_difficulty", "sensitivity")
    if not (isinstance(band, list) and len(band) == 2 and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                               and math.isfinite(v) for v in band)):
        check.fail(path, f"expected [low, high], two numbers (the band of ||A||_F), got {band!r}")
    if not 0 < band[0] < band[1]:
        check.fail(path, f"expected 0 < low < high, got {band!r}")
    return float(band[0]), float(band[1])


_PHASE_KEYS = ("id", "skill", "episodes", "demonstrations", "guidance", "instructions", "states_from")


def _parse_phases(check, entries, prefix: tuple, groups, skills, ids: dict, session_id: str) -> tuple[Phase, ...]:
    """The phases of one session; ``ids`` (phase id -> Phase, every session's so far) is updated.

    A phase's ``states_index`` (the seed position of its query states) counts the phases of
    every session before it, so a later session never reuses a seed unless ``states_from`` says so.
    """
    phases = []
    offset = len(ids)
    for i, entry in enumerate(entries):
        path = prefix + ("phases", i)
        if not isinstance(entry, dict):
            check.fail(path, f"expected a table, got {type(entry).__name__}")
        check.unknown(entry, path, _PHASE_KEYS)
        phase_id = check.get(entry, path + ("id",), "text", name=True)
        if phase_id in ids:
            check.fail(path + ("id",), f"expected a unique phase id, got {phase_id!r} again")
        skill = check.get(entry, path + ("skill",), "text")
        if skill not in skills:
            check.fail(path + ("skill",), f"unknown skill {skill!r}; expected one of {sorted(skills)}")
        episodes = check.get(entry, path + ("episodes",), "count", minimum=1, maximum=1000)
        demonstrations = check.get(entry, path + ("demonstrations",), "count",
                                   default=skills[skill].n_features, minimum=1, maximum=1000)
        guidance = entry.get("guidance", [])
        if not isinstance(guidance, list) or any(g not in groups for g in guidance):
            check.fail(path + ("guidance",), f"expected a list of groups from {groups}, got {guidance!r}")
        instructions = check.get(entry, path + ("instructions",), "text", nonempty=True)
        states_index = offset + i
        if "states_from" in entry:
            source_id = check.get(entry, path + ("states_from",), "text")
            if source_id not in ids:
                check.fail(path + ("states_from",), f"expected the id of an earlier phase ({list(ids)}), "
                                                    f"got {source_id!r}")
            earlier = ids[source_id]
            if (earlier.skill, earlier.demonstrations) != (skill, demonstrations) or earlier.episodes < episodes:
                check.fail(path + ("states_from",), f"phase {source_id!r} must have the same skill, the same number "
                                                    f"of demonstrations and at least as many episodes to lend its "
                                                    f"query states, got skill {earlier.skill!r}, "
                                                    f"{earlier.demonstrations} demonstrations, {earlier.episodes} "
                                                    f"episodes")
            states_index = earlier.states_index
        phase = Phase(phase_id, i, skill, episodes, demonstrations, tuple(guidance), instructions, states_index,
                      session_id)
        ids[phase_id] = phase
        phases.append(phase)
    return tuple(phases)


_SESSION_KEYS = ("id", "welcome", "instructions", "reproduction", "thank_you", "window", "phases", "before", "after")


def _parse_sessions(check, raw, groups, skills, phase_ids, step_ids, folder, check_files, texts,
                    first_id) -> list[ProtocolSession]:
    """The ``[[sessions]]`` after the first (see ``mt_widgets.study.session_plan``)."""
    entries = raw.get("sessions", [])
    if not isinstance(entries, list) or any(not isinstance(e, dict) for e in entries):
        check.fail(("sessions",), f"expected a list of [[sessions]] tables, got {type(entries).__name__}")
    sessions, labels = [], {bids_label(first_id): first_id}
    for i, entry in enumerate(entries):
        path = ("sessions", i)
        check.unknown(entry, path, _SESSION_KEYS)
        session_id = check.get(entry, path + ("id",), "text", name=True)
        label = bids_label(session_id)
        if not label or label in labels:
            check.fail(path + ("id",), f"expected a session id of its own (ids compare without '-' and '_', as "
                                       f"BIDS writes them), got {session_id!r}"
                                       + (f", like {labels[label]!r}" if label in labels else ""))
        labels[label] = session_id
        own = {key: check.get(entry, path + (key,), "text", nonempty=True) for key in
               ("welcome", "instructions", "thank_you")}
        own["reproduction"] = check.get(entry, path + ("reproduction",), "text", nonempty=True,
                                        default=texts["reproduction"])
        session_texts = {**texts, **own}
        window_table = check.get(entry, path + ("window",), "table")
        window = parse_window(check, window_table, path + ("window",))
        phases_raw = entry.get("phases")
        if not isinstance(phases_raw, list) or not phases_raw:
            check.fail(path + ("phases",), "missing required field: expected at least one [[sessions.phases]] table")
        phases = _parse_phases(check, phases_raw, path, groups, skills, phase_ids, session_id)
        before = parse_steps(check, entry, "before", folder, step_ids, check_files, prefix=path)
        after = parse_steps(check, entry, "after", folder, step_ids, check_files, prefix=path)
        sessions.append(ProtocolSession(session_id, i + 1, phases, before, after, session_texts, window,
                                        practice=False, default_consent=False))
    return sessions


def _check_changes(check, plan: AnalysisPlan, phase_ids: dict) -> None:
    """The analysis plan compares episodes that exist (phases of any session, episodes in range)."""
    for i, change in enumerate(plan.changes):
        for phase_id, episode in (change.before, change.after):
            if phase_id not in phase_ids:
                check.fail(("analysis", "changes"), f"expected changes[{i}] to name phases of the protocol "
                                                    f"({list(phase_ids)}), got {phase_id!r}")
            if episode is not None and not 1 <= episode <= phase_ids[phase_id].episodes:
                check.fail(("analysis", "changes"), f"expected changes[{i}]'s episode of {phase_id!r} between 1 and "
                                                    f"{phase_ids[phase_id].episodes}, got {episode}")


def _parse_analysis(check, raw: dict, phase_ids: dict) -> AnalysisPlan:
    """The ``[analysis]`` table: the pre-registered test, sidedness, alpha and planned power.

    Without ``changes`` (or without the table), the paper's comparisons that fit the protocol's
    phases (``changes_that_fit``): the paper's P3E8 or P5 is never asked of a protocol without them.
    """
    episodes = {phase_id: phase.episodes for phase_id, phase in phase_ids.items()}
    default_changes = changes_that_fit(PAPER_CHANGES, episodes)
    table = raw.get("analysis")
    if table is None:
        return AnalysisPlan(changes=default_changes)
    table = check.get(raw, ("analysis",), "table")
    check.unknown(table, ("analysis",), ("test", "alternative", "alpha", "effect_size", "power", "changes",
                                         "baseline"))
    values = {"test": check.get(table, ("analysis", "test"), "text", default="student", choices=TESTS),
              "alternative": check.get(table, ("analysis", "alternative"), "text", default="less",
                                       choices=ALTERNATIVES)}
    for key, default in (("alpha", 0.05), ("power", 0.8)):
        value = check.get(table, ("analysis", key), "number", default=default, positive=True)
        if not value < 1:
            check.fail(("analysis", key), f"expected a number strictly between 0 and 1, got {value}")
        values[key] = value
    values["effect_size"] = check.get(table, ("analysis", "effect_size"), "number", default=0.9, minimum=-math.inf)
    if values["effect_size"] == 0:
        check.fail(("analysis", "effect_size"), "expected a non-zero Cohen's d, got 0")
    changes = table.get("changes")
    if changes is not None:
        if not isinstance(changes, list) or not changes:
            check.fail(("analysis", "changes"), f"expected a list of changes, got {changes!r}")
        parsed = []
        for i, change in enumerate(changes):
            try:
                parsed.append(Change(change["name"], (change["before"][0], change["before"][1]),
                                     (change["after"][0], change["after"][1]), change.get("label", change["name"]),
                                     change.get("meaning", "")))
            except (KeyError, IndexError, TypeError):
                check.fail(("analysis", "changes"), f"expected changes[{i}] as {{name, before = [phase, episode], "
                                                    f"after = [phase, episode]}}, got {change!r}")
        values["changes"] = tuple(parsed)
    else:
        values["changes"] = default_changes
    if "baseline" in table:
        baseline = table["baseline"]
        ok = (isinstance(baseline, list) and len(baseline) == 2 and all(
            isinstance(b, list) and len(b) == 2 and isinstance(b[0], str) and isinstance(b[1], int)
            and not isinstance(b[1], bool) for b in baseline))
        if baseline is not False and not ok:
            check.fail(("analysis", "baseline"), f"expected [[phase, episode], [phase, episode]] (or false for no "
                                                 f"baseline check), got {baseline!r}")
        values["baseline"] = None if baseline is False else tuple((b[0], b[1]) for b in baseline)
    return AnalysisPlan(**values)
