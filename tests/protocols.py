"""A factory of study protocols for the tests: the boilerplate (format, texts, assignment, practice)
written once, the parts a test is about (name, seed, phases, skills, texts it checks) as arguments.

``protocol_toml(...)`` returns the TOML text a protocol file holds (what ``parse_protocol`` and
``load_protocol`` read), so a test can still write it to a file, point a page at it or edit it.
"""

from __future__ import annotations

import json

#: The texts every step needs, short: a test that checks a text passes its own.
TEXTS = {"welcome": "Welcome.", "consent": "Consent.", "instructions": "Instructions.",
         "reproduction": "Reproduction.", "thank_you": "Thank you."}
#: The texts of the study page's browser tests (tests/browser_study/), as a participant reads them.
BROWSER_TEXTS = {"welcome": "Welcome to the test study.", "consent": "Consent text.", "instructions": "How to teach.",
                 "reproduction": "This is what the robot learnt.", "thank_you": "Thank you, all done."}


def phase(id: str, skill: str, episodes: int = 1, instructions: str | None = None, **fields) -> dict:
    """One ``[[phases]]`` table: ``guidance=["target"]``, ``demonstrations=3``, ... as keywords."""
    return {"id": id, "skill": skill, "episodes": episodes, **fields,
            "instructions": instructions if instructions is not None else f"Phase {id}."}


def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, str):
        return json.dumps(value)   # a TOML basic string is a JSON string
    return repr(value)


def _table(header: str, fields: dict) -> list[str]:
    return [header, *(f"{key} = {_value(value)}" for key, value in fields.items())]


def protocol_toml(name: str, phases: list[dict], *, seed: int = 5, lam: float = 0.01, assignment_seed: int = 1,
                  practice_skill: str | None = None, practice_s: float = 0, practice_text: str = "Practice.",
                  texts: dict | None = None, skills_module: str | None = None, top: dict | None = None) -> str:
    """A protocol's TOML text.

    Args:
        name: the protocol's name.
        phases: its phases (``phase(...)``), in order.
        seed: the protocol's seed (query states, assignment); ``assignment_seed`` the block assignment's.
        lam: the learner's lambda.
        practice_skill, practice_s, practice_text: the practice (default skill: the first phase's).
        texts: texts replacing the short defaults of ``TEXTS``.
        skills_module: a user's skill module (``[skills] module = ...``).
        top: further top-level keys (``reproduction_duration_s``, ``withdrawal``, ...).
    """
    lines = ["format = 1", f"name = {_value(name)}", f"lambda = {lam!r}", f"seed = {seed}"]
    lines += [f"{key} = {_value(value)}" for key, value in (top or {}).items()]
    if skills_module is not None:
        lines += _table("[skills]", {"module": skills_module})
    lines += _table("[assignment]", {"block_size": 2, "seed": assignment_seed})
    lines += _table("[texts]", {**TEXTS, **(texts or {})})
    lines += _table("[practice]", {"skill": practice_skill or phases[0]["skill"], "duration_s": practice_s,
                                   "text": practice_text})
    for table in phases:
        lines += _table("[[phases]]", table)
    return "\n".join(lines) + "\n"


def industrial_online_toml(practice_s: int | None = None) -> str:
    """The shipped industrial-sim protocol (the paper's phases on the UR5) with the online pilot's
    ``[online]`` tables (notebooks/study_online_pilot.toml), for the online page; ``practice_s``
    shortens the practice."""
    from pathlib import Path

    from mt_widgets.study.protocol import PROTOCOL_FOLDER
    text = (PROTOCOL_FOLDER / "industrial_sim.toml").read_text(encoding="utf-8")
    pilot = (Path(__file__).resolve().parents[1] / "notebooks" / "study_online_pilot.toml").read_text(encoding="utf-8")
    online = pilot[pilot.index("\n[online]\n"):]
    online = online[:online.index("\n[", online.index("[online.completion.withdrawn]") + 1)]
    if practice_s is not None:
        text = text.replace("duration_s = 120", f"duration_s = {int(practice_s)}", 1)
    return text.rstrip() + "\n" + online + "\n"
