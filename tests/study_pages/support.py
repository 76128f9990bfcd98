"""Helpers of the study page tests: the online pilot protocol, a Prolific link, a participant's actions."""

from __future__ import annotations

import re
from pathlib import Path
from urllib.parse import urlencode

from ipywidgets import Button

from mt_widgets import SKILLS

PILOT = str(Path(__file__).resolve().parents[2] / "notebooks" / "study_online_pilot.toml")


#: The pool's completion link, as docs/user/study.md says to give each ending for the real study.
PROLIFIC_COMPLETION = "https://app.prolific.com/submissions/complete?cc={code}"


def pilot_with_completion_urls(folder: Path) -> str:
    """The online pilot with every ending given the pool's completion link (the shipped pilot has none:
    it ends on its page); the protocol's path, written into ``folder``."""
    text = Path(PILOT).read_text(encoding="utf-8")
    text = re.sub(r"(\[online\.completion\.\w+\]\n)", lambda m: m.group(1) + f'url = "{PROLIFIC_COMPLETION}"\n', text)
    protocol = Path(folder) / "study.toml"
    protocol.write_text(text, encoding="utf-8")
    return str(protocol)


def prolific(pid, study="S1", session="X1"):
    return urlencode({"PROLIFIC_PID": pid, "STUDY_ID": study, "SESSION_ID": session})


def buttons_in(widget):
    found, pending = [], [widget]
    while pending:
        node = pending.pop(0)
        if isinstance(node, Button) and node.layout.display != "none" and not node.disabled:
            found.append(node)
        pending += list(getattr(node, "children", ()))
    return found


def act(view, answers=None):
    """One participant action on a ``ParticipantView``, as the buttons and the canvas would do it."""
    step = view.session.current_step()
    if step.kind == "eligibility":
        view.form.fields["robotics_background"].value = (answers or {}).get("robotics_background", "no")
        view.form.continue_button.click()
    elif step.kind == "demographics":
        view.form.fields["age"].value = "30"
        view.form.fields["sex"].value = "female"
        view.form.continue_button.click()
    elif step.kind == "practice":
        view.practice.done_button.disabled = False
        view.practice.done_button.click()
    elif step.kind in ("demonstration", "episode_end"):
        if view.episode.phase == "guidance":
            view.episode.next()
        else:
            view.episode.demonstrate(SKILLS[step.skill].target_actions(step.state[None])[0] + 0.3)
    else:
        [b for b in buttons_in(view.body) if b.button_style == "primary"][0].click()
