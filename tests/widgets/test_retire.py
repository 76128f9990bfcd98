"""A view leaving the page for good closes every widget it owns, and nothing it does not own:
a study of twelve episodes kept about 1,760 widgets open in the kernel and the browser."""

import pytest
from ipycanvas import Canvas
from ipywidgets import HTML, Button, VBox, Widget

from mt_widgets import SKILLS
from mt_widgets.widgets import EpisodeWidget, retire
from mt_widgets.widgets.tree import widget_tree


def is_open(widget: Widget) -> bool:
    return widget.comm is not None


def test_the_tree_holds_layouts_styles_and_parts_kept_off_the_page_but_not_the_canvas_manager():
    episode = EpisodeWidget(SKILLS["uarm-point"], seed=1)
    owned = {id(w) for w in widget_tree(episode)}
    shown = {id(w) for w in widget_tree(episode, shown_only=True)}
    # The TeachingCanvas box whose pieces moved to the stage: owned, not shown.
    assert id(episode.teaching) in owned and id(episode.teaching) not in shown
    assert id(episode.layout) in shown and id(episode.next_button.style) in shown
    canvas = episode.teaching.view.canvas
    layers = getattr(canvas, "_canvases", [canvas])
    assert all(id(layer) in shown for layer in layers)
    # ipycanvas' one canvas manager stands behind every canvas of the page: nobody's to close.
    manager = Canvas()._canvas_manager
    assert id(manager) not in owned


def test_retire_closes_what_the_view_owns_and_keeps_what_the_page_shows_and_the_canvas_manager():
    episode = EpisodeWidget(SKILLS["uarm-point"], seed=1)
    moved = HTML("the page's own")
    episode.next_actions.children = [moved]
    page = VBox([moved])          # the page moved this widget out before the close
    retire(episode, keep=page)    # no kernel here: closes at once
    assert not is_open(episode) and not is_open(episode.teaching) and not is_open(episode.layout)
    assert not is_open(episode.teaching.view.canvas) and not is_open(episode.next_button.style)
    assert is_open(moved) and is_open(page)
    assert is_open(Canvas()._canvas_manager)
    Canvas()   # a new canvas still opens (its manager is open)


def test_retiring_only_what_a_screen_shows_leaves_what_its_attributes_reach_open():
    held = Button(description="held by an attribute, shown elsewhere")
    text = HTML("a screen's text")
    screen = VBox([text])
    screen.page_part = held       # an attribute of the screen: not the screen's to close
    retire(screen, shown_only=True)
    assert not is_open(screen) and not is_open(text) and not is_open(text.style) and not is_open(screen.layout)
    assert is_open(held) and is_open(held.layout)
    with pytest.raises(TypeError, match="shown_only: expected a bool"):
        retire(VBox(), shown_only=1)





def test_the_collection_after_closes_comes_once_a_turn_and_takes_at_most_its_share_of_the_kernel(monkeypatch):
    """A closed view is freed by a full collection (animation.py, ``_collect_soon``): one for all the views
    closed in a turn of the kernel's loop, and, when a collection is long (a notebook holding millions of
    objects), the next one only once the kernel has had ``1 / COLLECTION_SHARE`` times as long for itself."""
    import asyncio
    import time

    from mt_widgets.widgets import animation

    started = []

    def collect(*args):
        started.append(time.monotonic())
        time.sleep(0.01)  # a long collection: the next one no sooner than 0.5 s after it

    monkeypatch.setattr(animation.gc, "collect", collect)
    monkeypatch.setattr(animation, "_malloc_trim", lambda: None)
    monkeypatch.setattr(animation, "_COLLECTION", {})
    monkeypatch.setattr(animation, "_LAST_COLLECTION", [0.0, 0.0])
    stale = asyncio.new_event_loop()
    animation._collect_soon(stale)  # a timer left on a loop that closes before it runs
    stale.close()
    loop = asyncio.new_event_loop()
    try:
        animation._collect_soon(loop)
        animation._collect_soon(loop)  # a second view closed in the same turn
        assert started == [], "collected before the loop's next turn"
        loop.run_until_complete(asyncio.sleep(0.05))
        assert len(started) == 1, started
        ended, took = animation._LAST_COLLECTION
        due = ended + took / animation.COLLECTION_SHARE  # what this collection measured, load and all
        animation._collect_soon(loop)  # the next close: its collection waits its turn
        loop.run_until_complete(asyncio.sleep(max(0.0, due - time.monotonic()) / 2))
        assert len(started) == 1, f"a {took * 1000:.0f} ms collection came again before {due - ended:.2f} s"
        deadline = due + 5
        while len(started) < 2 and time.monotonic() < deadline:
            loop.run_until_complete(asyncio.sleep(0.05))
        assert len(started) == 2 and started[1] >= due - 0.005, (started, due)
    finally:
        loop.close()
