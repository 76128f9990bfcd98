"""A study protocol as data: practice, phases, guidance by group, seeds and texts.

Like a jsPsych timeline, a protocol is plain data run by a generic engine
(``mt_widgets.study.session``); changing the study means editing a file, not code. The
paper's protocol ships as ``protocols/paper_sim.toml`` and ``protocols/paper_uarm.toml``.

File format (TOML, or the same structure in JSON; ``format = 1``)::

    format = 1
    name = "paper-sim"                  # plain text, names the study in logs and CSVs
    title = "..."                       # for the experimenter
    groups = ["target", "control"]      # between-subjects groups
    lambda = 0.01                       # the learner's ridge parameter
    seed = 20240501                     # study seed of the query-state schedule
    query_states = "shared"             # "shared": the same states for every participant;
                                        # "per-participant": drawn per enrolment number
    reproduction_duration_s = 10.0      # optional: rollout length (default: the plant's)

    [assignment]
    method = "block"                    # seeded block randomisation
    block_size = 4                      # a multiple of the number of groups
    seed = 7

    [texts]                             # shown to every participant, whatever the group
    welcome = "..."
    consent = "..."
    instructions = "..."
    reproduction = "..."
    thank_you = "..."

    [practice]
    skill = "sim-point"
    duration_s = 120                    # 0 skips practice
    text = "..."

    [skills]                            # optional: a user's own skills
    module = "my_skills.py"             # a Python file (relative to this file); its Skills by key

    [[phases]]                          # in order; one table per phase
    id = "P1"
    skill = "sim-point"                 # a key of mt_widgets.SKILLS, of [skills], or "module:name"
    episodes = 1
    demonstrations = 5                  # optional, default: the skill's number of features
    guidance = []                       # groups that see guidance after each demonstration
    instructions = "..."
    states_from = "P1"                  # optional: reuse another phase's query states

Validation errors (``ProtocolError``) name the file, the line and the field, the value
expected and the value found. Line numbers come from the TOML source (``tomllib`` keeps
none, so fields are located by scanning the text table by table); JSON files get the line
of the field's first occurrence inside its phase.

TOML needs ``tomllib`` (Python >= 3.11). On Python 3.10 ``tomli`` is used when installed;
otherwise TOML files are refused with a message saying so and JSON works everywhere. The
project did not add ``tomli`` as a dependency for one old Python version.
"""

from __future__ import annotations

import copy
import hashlib
import importlib
import importlib.util
import json
import math
import re
import sys
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mt_widgets.core import SKILLS, Skill, SkillRegistry

try:  # Python >= 3.11
    import tomllib as _toml
except ModuleNotFoundError:  # pragma: no cover - exercised only on Python 3.10
    try:
        import tomli as _toml  # type: ignore[no-redef]
    except ModuleNotFoundError:
        _toml = None

from mt_widgets.core.guidance import GUIDANCE_MODALITIES
from mt_widgets.core.validation import as_bool

from .analysis_plan import ALTERNATIVES, PAPER_CHANGES, TESTS, AnalysisPlan, Change
from .practice import PRACTICE_SKILLS
from .steps import WITHDRAWAL_POLICIES, StudyStep, parse_steps

FORMAT_VERSION = 1
PROTOCOL_FOLDER = Path(__file__).parent / "protocols"
#: The protocols shipped with the package, by short name.
BUILTIN_PROTOCOLS = {"paper-sim": "paper_sim.toml", "paper-uarm": "paper_uarm.toml"}

_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,63}$")
_TEXT_KEYS = ("welcome", "consent", "instructions", "reproduction", "thank_you")
#: Texts a protocol may set for a session that ends early; these say it when it does not.
OPTIONAL_TEXTS = {
    "declined": "You chose not to take part. Thank you for your time; please let the experimenter know.",
    "ineligible": "Thank you for your interest. This study is looking for participants with a different "
                  "background, so it ends here. Please let the experimenter know.",
    "withdrawn": "You have withdrawn from the study. Nothing more is recorded. Thank you for your time; please "
                 "let the experimenter know.",
}


class ProtocolError(ValueError):
    """A protocol file that cannot be run, with where and why.

    Attributes:
        source: the file (or "<string>").
        line: 1-based line of the offending field or table, or None when unknown.
        field: the field's path, e.g. ``phases[2].episodes``.
    """

    def __init__(self, message: str, source: str = "<string>", line: int | None = None, field: str | None = None):
        self.source, self.line, self.field, self.reason = source, line, field, message
        where = source + (f", line {line}" if line else "")
        super().__init__(f"{where}: {field + ': ' if field else ''}{message}")


@dataclass(frozen=True)
class Phase:
    """One phase: ``episodes`` episodes of ``demonstrations`` demonstrations of one skill.

    Attributes:
        id: short name shown in logs and CSVs ("P3").
        index: 0-based position in the protocol.
        skill: the skill's name in the protocol (``Protocol.skills[skill]`` is the ``Skill``).
        episodes: number of episodes (>= 1).
        demonstrations: demonstrations per episode (>= 1).
        guidance: groups that see guidance after each demonstration.
        instructions: text shown before the phase, the same for every group.
        states_index: index of the phase whose query-state seeds this phase uses (itself
            unless ``states_from`` names another).
    """

    id: str
    index: int
    skill: str
    episodes: int
    demonstrations: int
    guidance: tuple[str, ...]
    instructions: str
    states_index: int

    def guidance_for(self, group: str) -> bool:
        return group in self.guidance


@dataclass(frozen=True)
class Practice:
    """Free drawing before the study: ``duration_s`` seconds on ``skill`` (0: no practice).

    Attributes:
        skill: the practice skill's key; the shipped protocols use a neutral one that no phase
            uses (``mt_widgets.study.practice``).
        duration_s: seconds of practice.
        text: shown above the practice.
        reproduction: whether each practice round ends with the robot reproducing what it
            learnt (False: arrows are drawn and confirmed, nothing is learnt or played back).
    """

    skill: str
    duration_s: float
    text: str
    reproduction: bool = True


class ProtocolSkills(Mapping):
    """The skills a protocol names, by name: read-only, and picklable (unlike a ``MappingProxyType``),
    since in-silico studies send the protocol to worker processes."""

    def __init__(self, skills: Mapping[str, Skill]):
        self._skills = dict(skills)

    def __getitem__(self, name: str) -> Skill:
        return self._skills[name]

    def __iter__(self):
        return iter(self._skills)

    def __len__(self) -> int:
        return len(self._skills)

    def __repr__(self) -> str:
        return f"ProtocolSkills({sorted(self._skills)})"


@dataclass(frozen=True)
class Protocol:
    """A validated protocol. Build it with ``load_protocol`` or ``parse_protocol``.

    ``data`` is the normalised plain-data form (what ``study.json`` stores and what the hash
    covers); ``source_text`` the file as written.
    """

    name: str
    title: str
    groups: tuple[str, ...]
    lam: float
    seed: int
    query_states: str
    reproduction_duration_s: float | None
    block_size: int
    assignment_seed: int
    texts: dict[str, str]
    practice: Practice
    phases: tuple[Phase, ...]
    data: dict = field(repr=False, compare=False)
    source_text: str = field(default="", repr=False, compare=False)
    source: str = field(default="<string>", compare=False)
    #: The skills its phases name, by name (see ``resolve_protocol_skills``).
    skills: Mapping[str, Skill] = field(default_factory=lambda: ProtocolSkills({**SKILLS, **PRACTICE_SKILLS}),
                                        repr=False, compare=False)
    guidance_modality: str = "arrows+words"
    #: How demonstrations are given: "drawn" on the screen, or "hand" (moving the uArm by hand).
    demonstration_modality: str = "drawn"
    before: tuple[StudyStep, ...] = ()
    after: tuple[StudyStep, ...] = ()
    withdrawal: str = "exclude"
    analysis: AnalysisPlan = AnalysisPlan()

    @property
    def steps(self) -> tuple[StudyStep, ...]:
        """Every step around the task, those before it first."""
        return self.before + self.after

    def step(self, step_id: str) -> StudyStep:
        for step in self.steps:
            if step.id == step_id:
                return step
        raise KeyError(f"step_id: expected one of {[s.id for s in self.steps]}, got {step_id!r}")

    def skill(self, key: str) -> Skill:
        """The ``Skill`` a phase or the practice names (``skills``: the paper's, the neutral
        practice skills and any the protocol brings)."""
        if key not in self.skills:
            raise KeyError(f"key: expected one of {sorted(self.skills)}, got {key!r}")
        return self.skills[key]

    @property
    def hash(self) -> str:
        """sha256 of the canonical JSON of ``data``: equal for protocols that run the same."""
        return protocol_hash(self.data)

    @property
    def n_episodes(self) -> int:
        return sum(phase.episodes for phase in self.phases)

    def phase(self, phase_id: str) -> Phase:
        for phase in self.phases:
            if phase.id == phase_id:
                return phase
        raise KeyError(f"phase_id: expected one of {[p.id for p in self.phases]}, got {phase_id!r}")


def protocol_hash(data: dict) -> str:
    canonical = json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return "sha256:" + hashlib.sha256(canonical.encode()).hexdigest()


# -- locating fields in the source text -------------------------------------------------------------

class _Locator:
    """Finds the line of a table or a key in TOML/JSON text (1-based), or None."""

    def __init__(self, text: str, kind: str):
        self.lines = text.splitlines()
        self.kind = kind

    def _table_spans(self, table: str, array: bool):
        """(start, end) line indices of each ``[table]`` / ``[[table]]`` section."""
        header = re.compile(r"^\s*\[\[\s*" + re.escape(table) + r"\s*\]\]" if array
                            else r"^\s*\[\s*" + re.escape(table) + r"\s*\]")
        any_header = re.compile(r"^\s*\[")
        spans, start = [], None
        for i, line in enumerate(self.lines):
            if any_header.match(line):
                if start is not None:
                    spans.append((start, i))
                    start = None
                if header.match(line):
                    start = i
        if start is not None:
            spans.append((start, len(self.lines)))
        return spans

    def _top_span(self):
        for i, line in enumerate(self.lines):
            if re.match(r"^\s*\[", line):
                return 0, i
        return 0, len(self.lines)

    def _json_phase_spans(self):
        # The n-th "{" after the '"phases"' key opens phase n when phases are written one per
        # object, as the shipped files and any hand-written JSON protocol are.
        spans, inside = [], False
        depth, start = 0, None
        for i, line in enumerate(self.lines):
            if not inside and re.search(r'"phases"\s*:', line):
                inside = True
            if inside:
                for ch in line:
                    if ch == "{":
                        if depth == 0:
                            start = i
                        depth += 1
                    elif ch == "}":
                        depth -= 1
                        if depth == 0 and start is not None:
                            spans.append((start, i + 1))
                    elif ch == "]" and depth == 0 and spans:
                        return spans
        return spans

    def _step_line(self, path: tuple) -> int | None:
        """Line of a field of a ``[[before]]`` / ``[[after]]`` step or of one of its ``items``."""
        table, index = path[0], path[1]
        header = re.compile(r"^\s*\[")
        own = re.compile(r"^\s*\[\[\s*" + table + r"\s*\]\]")
        nested = re.compile(r"^\s*\[\[\s*" + table + r"\.items\s*\]\]")
        starts = [i for i, line in enumerate(self.lines) if own.match(line)]
        if index >= len(starts):
            return None
        start = starts[index]
        end = next((i for i in range(start + 1, len(self.lines))
                    if header.match(self.lines[i]) and not nested.match(self.lines[i])), len(self.lines))
        key = path[2] if len(path) > 2 else None
        if key == "items" and len(path) > 3 and isinstance(path[3], int):
            items = [i for i in range(start, end) if nested.match(self.lines[i])]
            if path[3] < len(items):
                item_end = next((i for i in range(items[path[3]] + 1, end) if header.match(self.lines[i])), end)
                start, end = items[path[3]], item_end
                key = path[4] if len(path) > 4 else None
        if isinstance(key, str):
            pattern = re.compile(r'^\s*"?' + re.escape(key) + r'"?\s*=')
            for i in range(start, end):
                if pattern.match(self.lines[i]):
                    return i + 1
        return start + 1

    def line(self, path: tuple) -> int | None:
        """Line of ``path`` (e.g. ("phases", 2, "episodes")); falls back to its table."""
        if self.kind == "toml" and len(path) > 1 and path[0] in ("before", "after") and isinstance(path[1], int):
            return self._step_line(path)
        if self.kind == "json":
            span = (0, len(self.lines))
            if path and path[0] == "phases" and len(path) > 1 and isinstance(path[1], int):
                spans = self._json_phase_spans()
                if path[1] < len(spans):
                    span = spans[path[1]]
            key = path[-1] if path and isinstance(path[-1], str) else None
            if key:
                for i in range(*span):
                    if re.search(r'"' + re.escape(key) + r'"\s*:', self.lines[i]):
                        return i + 1
            return span[0] + 1 if span[0] or len(path) > 1 else None
        if not path:
            return None
        if path[0] == "phases" and len(path) > 1 and isinstance(path[1], int):
            spans = self._table_spans("phases", array=True)
            if path[1] >= len(spans):
                return None
            span, key = spans[path[1]], (path[2] if len(path) > 2 else None)
        elif len(path) > 1 and isinstance(path[1], str):
            spans = self._table_spans(path[0], array=False)
            if not spans:
                return None
            span, key = spans[0], path[1]
        else:
            span, key = self._top_span(), path[0]
            spans = self._table_spans(path[0], array=False) or self._table_spans(path[0], array=True)
            if spans and len(path) == 1:
                return spans[0][0] + 1
        if key is not None:
            pattern = re.compile(r'^\s*"?' + re.escape(str(key)) + r'"?\s*=')
            for i in range(*span):
                if pattern.match(self.lines[i]):
                    return i + 1
        return span[0] + 1 if span[0] or path[0] == "phases" else None


def _path_name(path: tuple) -> str:
    name = ""
    for part in path:
        name += f"[{part}]" if isinstance(part, int) else ("." if name else "") + part
    return name


# -- validation --------------------------------------------------------------------------------------

class _Checker:
    def __init__(self, locator: _Locator, source: str):
        self.locator, self.source = locator, source

    def fail(self, path: tuple, message: str):
        raise ProtocolError(message, self.source, self.locator.line(path), _path_name(path))

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


_SKILL_REFERENCE = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_]\w*$")


def resolve_protocol_skills(raw: dict, check: _Checker, source: str) -> tuple[Mapping[str, Skill], dict | None]:
    """The skills a protocol can name, by the names it uses.

    - the paper's four (``SKILLS``: "sim-point", ...) and the neutral practice skills
      (``mt_widgets.study.practice``: "sim-practice", "uarm-practice");
    - every ``Skill`` (and every skill of a ``SkillRegistry``) defined at the top of the Python
      file named by ``[skills] module = "path/to/skills.py"``, by its key; the path is relative
      to the protocol file;
    - a reference "package.module:name" to an importable module's ``Skill``, by that text.

    Returns:
        (name -> Skill, the ``[skills]`` table with the module's absolute path, or None). The
        stored protocol (``study.json``) keeps the absolute path, so a study folder reopened
        from anywhere finds the same file.
    """
    skills: dict[str, Skill] = {**SKILLS, **PRACTICE_SKILLS}
    table = raw.get("skills")
    if table is not None:
        table = check.get(raw, ("skills",), "table")
        check.unknown(table, ("skills",), ("module",))
        given = check.get(table, ("skills", "module"), "text", nonempty=True)
        base = Path(source).parent if source not in ("<string>", "") else Path.cwd()
        path = (base / given).resolve()
        if not path.is_file():
            check.fail(("skills", "module"), f"expected a Python file of skills (relative to {base}), got {given!r}: "
                                             f"no file at {path}")
        name = "mt_widgets_protocol_skills_" + hashlib.sha256(str(path).encode()).hexdigest()[:16]
        module = sys.modules.get(name)  # loaded once per process: its skills keep their identity
        if module is None:
            spec = importlib.util.spec_from_file_location(name, path)
            module = importlib.util.module_from_spec(spec)
            try:
                spec.loader.exec_module(module)
            except Exception as error:  # the user's code: whatever it raises is reported with its file
                check.fail(("skills", "module"), f"{path} failed to load: {type(error).__name__}: {error}")
            sys.modules[name] = module
        found = [value for value in vars(module).values() if isinstance(value, Skill)]
        for registry in (value for value in vars(module).values() if isinstance(value, SkillRegistry)):
            found.extend(registry.values())
        for skill in found:
            if skills.get(skill.key, skill) is not skill:
                check.fail(("skills", "module"), f"expected skills with keys of their own, got a second skill "
                                                 f"{skill.key!r} in {path}")
            skills[skill.key] = skill
        table = {"module": str(path)}
    names = [raw.get("practice", {}).get("skill")] + [entry.get("skill") for entry in raw.get("phases", [])
                                                      if isinstance(entry, dict)]
    for i, reference in enumerate(names):
        if not isinstance(reference, str) or reference in skills or not _SKILL_REFERENCE.match(reference):
            continue
        path = ("practice", "skill") if i == 0 else ("phases", i - 1, "skill")
        module_name, attribute = reference.split(":")
        try:
            value = getattr(importlib.import_module(module_name), attribute)
        except (ImportError, AttributeError) as error:
            check.fail(path, f"expected a Skill at {reference!r} (module:name), got {type(error).__name__}: {error}")
        if not isinstance(value, Skill):
            check.fail(path, f"expected a Skill at {reference!r}, got {type(value).__name__}")
        skills[reference] = value
    return ProtocolSkills(skills), table


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
        if _toml is None:  # pragma: no cover - Python 3.10 without tomli
            raise ProtocolError("TOML protocols need Python >= 3.11 (tomllib) or the 'tomli' package; "
                                "install tomli or write the protocol as JSON", source)
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
    check = _Checker(_Locator(text, kind), source)
    skills, skills_table = resolve_protocol_skills(raw, check, source)

    top_keys = ("format", "name", "title", "groups", "lambda", "seed", "query_states", "reproduction_duration_s",
                "assignment", "texts", "practice", "phases", "skills", "guidance_modality", "withdrawal", "before",
                "after", "analysis", "demonstration_modality")
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
    plan = _parse_analysis(check, raw)

    phases_raw = raw.get("phases")
    if not isinstance(phases_raw, list) or not phases_raw:
        check.fail(("phases",), "missing required field: expected at least one [[phases]] table")
    phases, ids = [], {}
    for i, entry in enumerate(phases_raw):
        path = ("phases", i)
        if not isinstance(entry, dict):
            check.fail(path, f"expected a table, got {type(entry).__name__}")
        check.unknown(entry, path, ("id", "skill", "episodes", "demonstrations", "guidance", "instructions",
                                    "states_from"))
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
        states_index = i
        if "states_from" in entry:
            source_id = check.get(entry, path + ("states_from",), "text")
            if source_id not in ids:
                check.fail(path + ("states_from",), f"expected the id of an earlier phase ({list(ids)}), "
                                                    f"got {source_id!r}")
            earlier = phases[ids[source_id]]
            if (earlier.skill, earlier.demonstrations) != (skill, demonstrations) or earlier.episodes < episodes:
                check.fail(path + ("states_from",), f"phase {source_id!r} must have the same skill, the same number "
                                                    f"of demonstrations and at least as many episodes to lend its "
                                                    f"query states, got skill {earlier.skill!r}, "
                                                    f"{earlier.demonstrations} demonstrations, {earlier.episodes} "
                                                    f"episodes")
            states_index = earlier.states_index
        ids[phase_id] = i
        phases.append(Phase(phase_id, i, skill, episodes, demonstrations, tuple(guidance), instructions, states_index))

    data = copy.deepcopy(raw)
    if skills_table is not None:
        data["skills"] = skills_table
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
    return Protocol(name, title, tuple(groups), lam, seed, query_states, duration, block_size, assignment_seed,
                    texts, practice, tuple(phases), data, text, source, skills, guidance_modality=modality,
                    demonstration_modality=demonstration_modality, before=before, after=after,
                    withdrawal=withdrawal, analysis=plan)


def _parse_analysis(check, raw: dict) -> AnalysisPlan:
    """The ``[analysis]`` table: the pre-registered test, sidedness, alpha and planned power."""
    table = raw.get("analysis")
    if table is None:
        return AnalysisPlan()
    table = check.get(raw, ("analysis",), "table")
    check.unknown(table, ("analysis",), ("test", "alternative", "alpha", "effect_size", "power", "changes"))
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
        values["changes"] = PAPER_CHANGES
    return AnalysisPlan(**values)


def load_protocol(path_or_name) -> Protocol:
    """Loads a protocol file, or a shipped one by name ("paper-sim", "paper-uarm").

    Raises:
        ProtocolError: when the file does not validate (names the line and field).
        FileNotFoundError: when the file does not exist.
    """
    if isinstance(path_or_name, str) and path_or_name in BUILTIN_PROTOCOLS:
        path = PROTOCOL_FOLDER / BUILTIN_PROTOCOLS[path_or_name]
    else:
        if not isinstance(path_or_name, (str, Path)):
            raise ValueError(f"path_or_name: expected a file path or one of {sorted(BUILTIN_PROTOCOLS)}, "
                             f"got {type(path_or_name).__name__}")
        path = Path(path_or_name)
    if not path.is_file():
        raise FileNotFoundError(f"path_or_name: no protocol file at {path} (shipped protocols: "
                                f"{sorted(BUILTIN_PROTOCOLS)})")
    return parse_protocol(path.read_text(encoding="utf-8"), str(path))


def protocol_from_data(data: dict, source: str = "study.json") -> Protocol:
    """Rebuilds a protocol from its stored plain-data form (as ``study.json`` keeps it)."""
    return parse_protocol(json.dumps(data, indent=1), source, kind="json", check_files=False)
