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
    reproduce_after = "episode"         # optional: "episode" (the robot plays back after every
                                        # episode, the paper's simulator section) or "phase"
                                        # (after each phase's last episode, its protocol section)
    session = "main"                    # optional: the id of the first session (see [[sessions]])

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

    [arm]                               # optional: the arm taught, a shipped one (robot = "panda")
    urdf = "my_arm.urdf"                # or a URDF beside this file, with tool, name, home,
    tool = "flange"                     # teaching_box, part, fixture: its skills "<name>-reach",
    ...                                 # "<name>-place" (mt_widgets/study/protocol_arm.py)

    [[phases]]                          # in order; one table per phase
    id = "P1"
    skill = "sim-point"                 # a key of mt_widgets.SKILLS, of [skills], or "module:name"
    episodes = 1
    demonstrations = 5                  # optional, default: the skill's number of features
    guidance = []                       # groups that see guidance after each demonstration
    instructions = "..."
    states_from = "P1"                  # optional: reuse another phase's query states

    [matched_difficulty]                # optional (off in the shipped paper protocols, which
    sensitivity = [1.5, 2.5]            # draw plain seeded states as the paper did): every
                                        # episode's states are drawn so that the learner's
                                        # sensitivity ||A||_F lies in this band, so a slip costs
                                        # the same in every phase (mt_widgets/study/timeline.py)

    [[before]] / [[after]]              # steps around the task: video (a file the researcher
                                        # provides, its sha256 in the protocol's hash, or a url),
                                        # information, consent, eligibility, demographics,
                                        # questionnaire (mt_widgets/study/steps.py)
    [[sessions]]                        # later sessions with their own phases, steps, texts and
                                        # window (mt_widgets/study/session_plan.py)
    [online]                            # completion URLs and codes, the URL's participant
                                        # parameters (mt_widgets/study/online.py)
    [analysis]                          # the pre-registered plan (mt_widgets/study/analysis_plan.py)

Validation errors (``ProtocolError``) name the file, the line and the field, the value
expected and the value found. Line numbers come from the TOML source (``tomllib`` keeps
none, so fields are located by scanning the text table by table); JSON files get the line
of the field's first occurrence inside its phase.

TOML needs ``tomllib`` (Python >= 3.11); on Python 3.10 the same parser comes as the ``tomli``
package, in the ``analysis`` extra there (``tomli; python_version < '3.11'`` in pyproject.toml), so the
shipped TOML protocols load on every Python the package claims. JSON works everywhere.

The module tree of a protocol: ``protocol_model`` (the frozen model), ``protocol_schema``
(validation), ``protocol_source`` (line numbers in the source), ``skill_modules`` (a user's
skills), ``protocol_arm`` (the ``[arm]`` table), ``session_plan`` (sessions and windows),
``online``, ``steps``, ``analysis_plan``.
"""


from __future__ import annotations

import json
from pathlib import Path

from .protocol_model import OPTIONAL_TEXTS, Phase, Practice, Protocol, ProtocolError, ProtocolSkills, protocol_hash
from .protocol_schema import FORMAT_VERSION, parse_protocol

PROTOCOL_FOLDER = Path(__file__).parent / "protocols"
#: The protocols shipped with the package, by short name.
BUILTIN_PROTOCOLS = {"paper-sim": "paper_sim.toml", "paper-uarm": "paper_uarm.toml",
                     "paper-sim-followup": "paper_sim_followup.toml",
                     "industrial-sim": "industrial_sim.toml", "paper-so101": "paper_so101.toml"}

# The reward-learning follow-up's study (arXiv 2505.10151; docs/guide/learners.md).
BUILTIN_PROTOCOLS["reward-sim"] = "reward_sim.toml"

__all__ = ["BUILTIN_PROTOCOLS", "FORMAT_VERSION", "OPTIONAL_TEXTS", "PROTOCOL_FOLDER", "Phase", "Practice", "Protocol",
           "ProtocolError", "ProtocolSkills", "load_protocol", "parse_protocol", "protocol_from_data",
           "protocol_hash"]


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
