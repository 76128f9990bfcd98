"""The widgets shape (``pip install "mt-widgets[widgets]"``): a teaching widget built and displayed
headlessly. Displaying gives the front-end its model; the canvases then draw the robot and the query
state, which this records as the commands ipycanvas would send to the browser."""

import ipycanvas
from ipycanvas.canvas import COMMANDS

from mt_widgets import SKILLS
from mt_widgets.widgets import EpisodeWidget, TeachingCanvas

NAMES = {index: name for name, index in COMMANDS.items()}
sent = []


def record(command, buffers=()):
    batch = command if command and isinstance(command[0], list) else [command]
    sent.extend(NAMES[c[0]] for c in batch)


ipycanvas.canvas._CANVAS_MANAGER._send_custom = record

skill = SKILLS["sim-point"]
teach = TeachingCanvas(skill)
bundle = teach._repr_mimebundle_()
view = bundle["application/vnd.jupyter.widget-view+json"]
assert view["model_id"] == teach.model_id, view
assert teach.state_index == 0 and teach.n_states == skill.n_features
assert "fillCircle" in sent and "fillText" in sent, f"the canvas drew nothing recognisable: {sorted(set(sent))}"
state = teach.get_state()
assert state["children"], "the widget has its canvas and readouts"

episode = EpisodeWidget("sim-point")
assert episode._repr_mimebundle_()["application/vnd.jupyter.widget-view+json"]["model_id"] == episode.model_id
print(f"widgets: {len(sent)} canvas commands, {len(state['children'])} children")
