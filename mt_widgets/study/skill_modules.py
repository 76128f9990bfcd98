"""The skills a protocol can name: the paper's, the practice skills, a user's Python file of skills,
or an importable "package.module:name".

A user's file is executed (``importlib``), once per process, so its skills keep their identity
across protocols that name it; what it raises is reported with the file's name.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import re
import sys
from collections.abc import Mapping
from pathlib import Path

from mt_widgets.core import SKILLS, Skill, SkillRegistry

from .practice import PRACTICE_SKILLS
from .protocol_model import ProtocolSkills

_SKILL_REFERENCE = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_]\w*$")


def resolve_protocol_skills(raw: dict, check, source: str) -> tuple[Mapping[str, Skill], dict | None]:
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
