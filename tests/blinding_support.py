"""What a participant's page could show: every text a widget tree holds (a test helper for blinding)."""

import re

# A page script's code is never shown (the canvas's touch and keyboard script, widgets/canvas_access.py,
# rides in an ``onerror`` attribute and reads the DOM's ``event.target``); every text it shows is
# markup of the page. Blinding checks read the words, not the code: ``without_scripts``.
_SCRIPT = re.compile(r"<script\b.*?</script>|\son[a-z]+=\"[^\"]*\"", re.IGNORECASE | re.DOTALL)


def participant_texts(widget) -> list[str]:
    """Every piece of text a widget tree can show (values, descriptions, labels, options, tooltips).

    Used to check blinding: walk what the participant view holds and read what it would render.
    """
    texts: list[str] = []
    seen = set()

    def walk(node):
        if id(node) in seen:
            return
        seen.add(id(node))
        for name in ("value", "description", "placeholder", "tooltip", "button_text"):
            value = getattr(node, name, None)
            if isinstance(value, str):
                texts.append(value)
        for name in ("options", "_options_labels", "tooltips"):
            value = getattr(node, name, None)
            if isinstance(value, (list, tuple)):
                texts.extend(str(v) for v in value)
        for child in getattr(node, "children", ()) or ():
            walk(child)

    walk(widget)
    return texts


def without_scripts(text: str) -> str:
    """``text`` without the code of its page scripts (``<script>`` elements and ``on...=`` attributes)."""
    return _SCRIPT.sub(" ", text)
