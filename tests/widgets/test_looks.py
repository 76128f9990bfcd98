"""mt_widgets/widgets/looks.py: shared layouts and styles, frozen, one per kernel, never closed with a view."""

from __future__ import annotations

import multiprocessing

import pytest
from ipywidgets import HTML, Button, ButtonStyle, Layout
from ipywidgets.widgets import widget as widget_module

from mt_widgets.widgets import EpisodeWidget, retire
from mt_widgets.widgets.looks import is_shared, layered_canvas, plain, shared_layout, shared_style
from mt_widgets.widgets.tree import widget_tree


def test_the_same_css_is_one_layout_and_other_css_another():
    assert shared_layout(width="170px") is shared_layout(width="170px")
    assert shared_layout(width="170px") is not shared_layout(width="171px")
    assert shared_layout(flex="1", width="2px") is shared_layout(width="2px", flex="1")
    assert shared_layout(width="170px").width == "170px"
    assert shared_style(ButtonStyle) is shared_style(ButtonStyle)


def test_a_shared_layout_refuses_a_change_and_a_widget_given_its_own_can_change():
    button = plain(Button, description="x")
    assert button.layout is shared_layout() and button.style is shared_style(ButtonStyle)
    with pytest.raises(TypeError, match=r"display: this Layout is shared .*widget\.layout = Layout"):
        button.layout.display = "none"
    assert shared_layout().display is None   # nothing changed, for anyone
    with pytest.raises(TypeError, match="button_color: this ButtonStyle is shared"):
        button.style.button_color = "red"
    button.layout = Layout()
    button.layout.display = "none"
    assert button.layout.display == "none" and shared_layout().display is None


def test_plain_keeps_what_it_is_given_and_names_bad_arguments():
    own = Layout(width="3px")
    text = plain(HTML, "hi", layout=own)
    assert text.layout is own and is_shared(text.style) and text.value == "hi"
    with pytest.raises(TypeError, match="widget_class: expected an ipywidgets widget class, got 'HTML'"):
        plain("HTML")
    with pytest.raises(TypeError, match="width: expected a CSS value as a str, got int"):
        shared_layout(width=170)
    with pytest.raises(TypeError, match="style_class: expected an ipywidgets style class"):
        shared_style(dict)


def test_a_closed_shared_layout_is_made_again():
    layout = shared_layout(margin="1px 2px 3px 4px")
    layout.close()
    again = shared_layout(margin="1px 2px 3px 4px")
    assert again is not layout and again.comm is not None


def _model_id_in_child(queue):
    queue.put(shared_layout(width="99px").model_id)


def test_a_forked_process_makes_its_own():
    # A kernel forked from a template (mt_widgets/kernels/template.py) must not use a model the
    # template opened: the page never heard of it.
    parent = shared_layout(width="99px").model_id
    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=_model_id_in_child, args=(queue,))
    child.start()
    child_id = queue.get(timeout=60)
    child.join(60)
    assert child_id != parent


def test_layers_are_born_at_the_canvas_size_with_the_shared_layout():
    canvas = layered_canvas(3, 320, 240, layout=Layout(width="50%"))
    assert len(canvas._canvases) == 3 and canvas.width == 320 and canvas.height == 240
    assert all((layer.width, layer.height) == (320, 240) for layer in canvas._canvases)
    assert all(layer.layout is shared_layout() for layer in canvas._canvases)
    assert canvas.layout.width == "50%" and not is_shared(canvas.layout)
    canvas.width = 400   # MultiCanvas still resizes its layers
    assert all(layer.width == 400 for layer in canvas._canvases)
    for bad in (0, True, 2.0):
        with pytest.raises(ValueError, match="layers: expected a positive int"):
            layered_canvas(bad, 10, 10)


def _open_models() -> set:
    return set(widget_module._instances)


def test_an_episode_opens_fewer_models_and_retiring_it_leaves_the_shared_ones_open():
    EpisodeWidget("sim-point", seed=1, guidance=True)   # the shared ones made once
    before = _open_models()
    episode = EpisodeWidget("sim-point", seed=2, guidance=True)
    opened = _open_models() - before
    # ipywidgets' own layouts and styles would make it 120 (48 layouts, 23 styles).
    assert len(opened) <= 66, len(opened)
    tree = list(widget_tree(episode))
    assert not any(is_shared(node) for node in tree)
    shared = [node for node in (episode.header.layout, episode.header.style, episode.stage.layout,
                                episode.teaching.confirm_button.style)]
    assert all(is_shared(node) for node in shared)
    retire(episode)   # no kernel here: closed at once
    assert all(node.comm is None for node in tree)
    assert all(node.comm is not None for node in shared)
    again = EpisodeWidget("sim-point", seed=3, guidance=True)
    assert again.header.layout is shared[0]
