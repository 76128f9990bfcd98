"""What a participant's page could show: every text a widget tree holds (a test helper for blinding)."""


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
        # ``text``: a teaching canvas's words for screen readers (widgets/canvas_access.py).
        for name in ("value", "description", "placeholder", "tooltip", "button_text", "text"):
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

