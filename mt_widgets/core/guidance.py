"""How machine-teaching guidance is shown: the optimal arrow, words about the difference, both, or nothing.

The paper's guidance "consists of the display of arrows on a screen, representing the direction
and magnitude of the correct action and the action provided by the user": ``"arrows"``. Lessons
add words (how many degrees off, how much too long): ``"arrows+words"``. A study protocol names
its modality (``mt_widgets.study.protocol``) and the teaching widget shows exactly that.
"""

from __future__ import annotations

#: The ways guidance can be shown, and what each shows: (arrows, words).
GUIDANCE_MODALITIES = {
    "arrows": (True, False),
    "arrows+words": (True, True),
    "words": (False, True),
    "none": (False, False),
}


def guidance_parts(modality: str) -> tuple[bool, bool]:
    """(shows the optimal arrow, shows words) for a modality name; ValueError naming it otherwise."""
    if not isinstance(modality, str) or modality not in GUIDANCE_MODALITIES:
        raise ValueError(f"guidance_modality: expected one of {list(GUIDANCE_MODALITIES)}, got {modality!r}")
    return GUIDANCE_MODALITIES[modality]
