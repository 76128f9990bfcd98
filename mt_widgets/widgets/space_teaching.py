"""Teaching a plant drawn in space: an arm in a perspective view and two linked orthographic views.

The canvas holds three panels, each a ``ViewProjection`` of the plant's ``SpaceDrawing``:

- **top** (looking down): a drag from the tool sets the action's horizontal components (x, y);
- **side** (looking along +y): a drag from the tool sets x and the height z (x is shared with the
  top view: the two are linked, an arrow drawn in one shows in both, and a drag changes x by the
  pointer's sideways travel, so a drag straight up in the side view keeps the x the top view set);
- **perspective**: a drag anywhere orbits the camera (or keys ``a``/``d``, ``w``/``s``).

The query state (the arm's chain and its tool) and the tool's arrows are drawn in every panel.
An action is also given by keyboard (``x``/``y``/``z`` or Space pick the active component, the
arrow keys nudge it, Shift finer, Enter confirms, Escape clears; Tab leaves the canvas, as on the
planar canvas, so a keyboard user is never trapped) and by typed numbers (three fields, checked:
three finite numbers). After each confirmation with guidance on, the optimal arrow (dashed) is
drawn beside the user's (solid) in every panel. Once the episode is complete the learnt skill's
reproduction plays in all three panels: every frame is sent with ``canvas.sleep`` in chunks
(``animation.play_frames``), as the planar views do.

Like every view here it holds no science: what it draws comes from the ``TeachingEpisode`` and the
plant's ``drawing()`` / ``sketch()``; it never asks which robot it draws. Nor does it hold the
episode's state machine: that is the ``EpisodeController`` (``canvas.controller``,
episode_controller.py) the planar ``TeachingCanvas`` renders too; this canvas takes input, hands
it to the controller and draws what the controller says (``EpisodeWidget`` shows it for a plant
drawn in space).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from ipycanvas import MultiCanvas
from ipywidgets import HTML, Button, FloatText, HBox, Layout, VBox

from ..core.drawing import SPACE_VIEWS, SpaceDrawing
from ..core.episode import Demonstration, TeachingEpisode
from ..core.skills import SKILLS, Skill
from ..core.validation import as_bool
from ..core.workspace import Box
from .animation import frame_times, play_frames, sample_at, stop_animation
from .arrows import draw_arrow_pair, visible_tip
from .canvas_access import FINGER_RADIUS_CSS_PX, CanvasDescription
from .episode_controller import EpisodeController
from .legend import _arrow_svg, _dot_svg, _entry, _line_svg
from .pointer_drag import ARROW_KEY_SIGNS, PointerDrag, confirm_or_clear
from .redraw import drawing_batch, repaint_on_new_view
from .theme import fill_words, get_theme

#: The panels in the canvas's 2 x 2 grid (column, row); the fourth cell holds the view's labels.
PANEL_CELLS = {"top": (0, 0), "side": (1, 0), "perspective": (0, 1)}
#: What each panel is called on the canvas and in words.
PANEL_TITLES = {"top": "Top (drag: x, y)", "side": "Side (drag: x, height)", "perspective": "3-D (drag: turn)"}
#: Action components a keyboard nudges, in the order Space moves through them.
COMPONENTS = ("x", "y", "z")
#: The radius of the hand's dot, in pixels.
HAND_RADIUS_PX = 6.0
#: The optimal arrow is drawn at least this long (pixels): its shaft clears the hand's dot and its
#: head shows the direction. The UR5's first optimal action at seed 0 is 3-5 px to scale.
SHORTEST_OPTIMAL_PX = 24.0
#: Degrees one orbit key turns the perspective camera, and per pixel of a drag.
ORBIT_KEY_DEG, ORBIT_DRAG_DEG_PER_PX = 10.0, 0.5
#: The camera's elevation stays in this range (degrees): never under the table nor upside down.
ELEVATION_RANGE = (-10.0, 89.0)
#: Frames per second the reproduction is sent at. Above issue 31's 50 fps target because the browser
#: shows a frame only after ipycanvas's ``sleep`` between frames and the frame's drawing: sent at 50 fps
#: (20 ms sleeps), Chromium showed about 47 new pictures a second (benchmarks/bench_ur5.py, part 6).
REPRODUCTION_FPS = 60.0


def check_space_action(action) -> np.ndarray:
    """An action in space as (3,) floats, or a ValueError/TypeError naming ``action``.

    Accepts any sequence of three finite real numbers (a bool is not a number here).
    """
    try:
        values = list(action)
    except TypeError:
        raise TypeError(f"action: expected 3 finite numbers (x, y, z), got {type(action).__name__}") from None
    if len(values) != 3 or any(isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating))
                                for v in values):
        raise ValueError(f"action: expected 3 finite numbers (x, y, z), got {action!r}")
    result = np.array(values, dtype=float)
    if not np.all(np.isfinite(result)):
        raise ValueError(f"action: expected 3 finite numbers (x, y, z), got {action!r}")
    return result


def _as_episode(skill, query_states, seed) -> TeachingEpisode:
    if isinstance(skill, TeachingEpisode):
        if query_states is not None or seed is not None:
            raise ValueError("query_states, seed: expected None when a TeachingEpisode is given (it has its own "
                             "states)")
        return skill
    if isinstance(skill, str):
        if skill not in SKILLS:
            raise ValueError(f"skill: expected one of {sorted(SKILLS)}, got {skill!r}")
        skill = SKILLS[skill]
    if not isinstance(skill, Skill):
        raise TypeError(f"skill: expected a Skill, a skill key or a TeachingEpisode, got {type(skill).__name__}")
    return TeachingEpisode(skill, query_states, seed=seed)


class _Panel:
    """One view's square in the canvas: world-to-view projection and view-to-pixel mapping."""

    def __init__(self, name: str, projection, extent, left: float, top: float, size: float, margin: float):
        self.name, self.projection = name, projection
        self.left, self.top, self.size = left, top, size
        (x0, x1), (y0, y1) = extent.xlim, extent.ylim
        inner = size - 2 * margin
        self.scale = inner / max(x1 - x0, y1 - y0)
        # Centred: the shorter side of the extent gets the spare room on both sides.
        self.origin = np.array([left + size / 2 - self.scale * (x0 + x1) / 2,
                                top + size / 2 + self.scale * (y0 + y1) / 2])

    def pixels(self, points) -> np.ndarray:
        """World points (..., 3) -> canvas pixels (..., 2)."""
        flat = self.projection.project(points)
        return np.stack([self.origin[0] + self.scale * flat[..., 0], self.origin[1] - self.scale * flat[..., 1]],
                        axis=-1)

    def contains(self, pointer) -> bool:
        return self.left <= pointer[0] < self.left + self.size and self.top <= pointer[1] < self.top + self.size


class SpaceTeachingCanvas(VBox):
    """Draw one 3-D action at each query state of a plant drawn in space (its ``drawing()`` a ``SpaceDrawing``).

    Args:
        skill: a ``Skill``, a skill key (``"ur5-reach"``) or the ``TeachingEpisode`` to demonstrate into.
        query_states: (N, state_dim) the states to demonstrate at (default: the skill's, from ``seed``).
        seed: seed of the default query states.
        theme: a ``Theme`` or theme name (arrow colours and dashes as the planar views).
        guidance: show the optimal arrow after each confirmation (then "Next state" or Enter goes on).
        panel_size: pixels of each view's square (the canvas is two squares wide and high).
        grab_radius: pixels around the tool (and an arrow's tip) where a mouse press starts a drag; a
            finger gets at least a 48 CSS px target.
        play: play the reproduction when the last demonstration is confirmed.
        controller: the ``EpisodeController`` to render (an episode widget's): ``skill`` is then its
            episode, ``guidance`` and ``play`` are the controller's (its ``guidance`` and
            ``reproduce``). None: the canvas makes its own.

    Attributes:
        episode: the ``TeachingEpisode`` the demonstrations go to (the one place they live).
        pending_action: the action drawn but not confirmed, (3,) floats, or None.
        active_component: the component the arrow keys nudge (one of ``COMPONENTS``).
        azimuth_deg, elevation_deg: the perspective camera's direction.
    """

    def __init__(self, skill, query_states=None, *, seed=None, theme=None, guidance: bool = True,
                 panel_size: int = 260, grab_radius: float = 22.0, play: bool = True,
                 controller: EpisodeController | None = None):
        if controller is not None:
            if not isinstance(controller, EpisodeController):
                raise TypeError(f"controller: expected an EpisodeController, got {type(controller).__name__}")
            if skill is not controller.episode:
                raise ValueError("skill: expected the controller's episode with a controller")
        self.episode = _as_episode(skill, query_states, seed)
        self.skill = self.episode.skill
        drawing = self.skill.plant.drawing()
        if not isinstance(drawing, SpaceDrawing):
            raise TypeError(f"skill: expected a plant drawn in space (its drawing() a SpaceDrawing), got "
                            f"{type(drawing).__name__} for {self.skill.key!r}; use TeachingCanvas for a planar plant")
        if self.skill.plant.action_dim != 3:
            raise ValueError(f"skill: expected a plant with 3 action components, got {self.skill.plant.action_dim}")
        self.drawing = drawing
        self.theme = get_theme(theme)
        made_here = controller is None
        if made_here:
            controller = EpisodeController(self.episode, guidance=as_bool("guidance", guidance),
                                           reproduce=as_bool("play", play))
        #: The episode's state machine (episode_controller.py); this canvas draws it.
        self.controller = controller
        self.guidance = controller.guidance
        self.play_on_complete = controller.reproduce
        if isinstance(panel_size, bool) or not isinstance(panel_size, int) or panel_size < 120:
            raise ValueError(f"panel_size: expected an int of at least 120 pixels, got {panel_size!r}")
        self.panel_size = panel_size
        self.grab_radius = float(grab_radius)
        perspective = drawing.projection("perspective")
        self.azimuth_deg, self.elevation_deg = perspective.azimuth_deg, perspective.elevation_deg
        self.action_length = drawing.action_length or 0.1 * float(np.max(drawing.bounds.high - drawing.bounds.low))
        self.active_component = "x"
        self.animation = None
        # What the pointer's drag moves: ("arrow", panel name, pixel pressed, action then) or ("orbit", last pointer).
        self._drag = None
        # An orbit goes on while guidance is shown; an arrow's drag ends when input stops being accepted.
        self._pointer = PointerDrag(self._press, lambda pointer: self._drag_to(pointer, final=False),
                                    lambda pointer: self._drag_to(pointer, final=True),
                                    lambda: self._drag is not None and (self._drag[0] == "orbit" or self._accepting()))

        size = 2 * panel_size
        self.canvas = MultiCanvas(2, width=size, height=size, layout=Layout(width="100%", max_width=f"{size}px",
                                                                         height="auto"))
        self.scene, self.plant_layer = self.canvas[0], self.canvas[1]
        self._layers = {"scene": self.scene, "robot": self.plant_layer}
        self._paints = {}
        self._panels = self._make_panels()
        # Events come from the top layer.
        self._pointer.connect(self.canvas._canvases[-1], lambda: self.grab_radius, lambda: self.finger_radius,
                              self._on_key_down)
        self.description = CanvasDescription(self.canvas)

        units = self.drawing.action_units
        self.entries = tuple(FloatText(description=f"{c} ({units})", step=0.01, layout=Layout(width="160px"))
                             for c in COMPONENTS)
        self.set_button = Button(description="Set arrow", tooltip="Draw the arrow from the three numbers")
        self.confirm_button = Button(description="Confirm", button_style="success", icon="check", disabled=True,
                                     tooltip="Record this arrow as your demonstration (Enter on the canvas)")
        self.clear_button = Button(description="Clear", icon="eraser", disabled=True,
                                   tooltip="Remove the arrow and draw again (Escape on the canvas)")
        self.next_button = Button(description="Next state", icon="arrow-right", layout=Layout(display="none"))
        self.play_button = Button(description="Play again", icon="play", layout=Layout(display="none"))
        self.readout, self.hint = HTML(""), HTML("")
        self.set_button.on_click(lambda _: self._set_from_entries())
        self.confirm_button.on_click(lambda _: self.confirm())
        self.clear_button.on_click(lambda _: self.clear_action())
        self.next_button.on_click(lambda _: self.advance())
        self.play_button.on_click(lambda _: self.play())
        self.legend = HTML(self._legend_html())
        controls = VBox([
            self.readout, HBox([self.confirm_button, self.clear_button, self.next_button, self.play_button]),
            HTML("<small>Or type the arrow:</small>"), VBox(list(self.entries)), self.set_button, self.hint,
            HTML("<small>Keyboard: Tab to the canvas (or click it); x, y, z (or Space) choose a component, the "
                 "arrow keys change it (Shift: finer), a/d and w/s turn the 3-D view, Enter confirms, Escape "
                 "clears, Tab moves on.</small>"),
            self.legend, self.description,
        ], layout=Layout(min_width="260px", max_width="380px"))
        super().__init__([HBox([self.canvas, controls], layout=Layout(flex_flow="row wrap",
                                                                       align_items="flex-start"))])
        self.add_class("mt-focus")
        for name, layer in self._layers.items():
            repaint_on_new_view(layer, lambda name=name: self._repaint(name))
        controller.observe(self._on_event)
        self._redraw_scene()
        if made_here:
            controller.resume()   # the episode as it stands (a resumed one: its demonstrations given)
        else:
            self._redraw_robot()
            self._update_words()

    # -- public API ------------------------------------------------------------------------------------
    @property
    def current_state(self) -> np.ndarray | None:
        """The query state shown (awaiting a demonstration, or its guidance shown), or None when all are done."""
        return self.controller.current_state

    @property
    def pending_action(self) -> np.ndarray | None:
        """The action drawn but not confirmed, (3,) floats (the confirmed one while guidance is shown), or None."""
        return self.controller.pending_action

    @property
    def showing_guidance(self) -> bool:
        """Whether the optimal arrow of the last confirmed demonstration is shown (the controller's pause)."""
        return self.controller.phase == "guidance"

    def _shown_index(self) -> int | None:
        return None if self.current_state is None else self.controller.state_index

    def panel(self, name: str) -> _Panel:
        """The panel called ``name`` (one of ``SPACE_VIEWS``): its ``pixels(points)`` maps world points."""
        if name not in self._panels:
            raise ValueError(f"name: expected one of {SPACE_VIEWS}, got {name!r}")
        return self._panels[name]

    def tool_pixel(self, name: str) -> np.ndarray:
        """(2,) the canvas pixel of the current state's tool in panel ``name``."""
        return self.panel(name).pixels(self._tool())

    def on_confirm(self, callback, remove: bool = False) -> None:
        """``callback(demonstration)`` at each confirmation, before it is recorded (the controller's
        ``on_demonstration``: an error keeps the arrow pending and unrecorded)."""
        self.controller.on_demonstration(callback, remove)

    def set_action(self, action, method: str = "code") -> None:
        """Draw ``action`` (3 finite numbers) as the pending arrow (not yet confirmed)."""
        action = check_space_action(action)
        if self.current_state is None or self.showing_guidance:
            raise RuntimeError("set_action: no query state awaits a demonstration")
        self.controller.hold(action, method)
        self._after_change(final=True)

    def clear_action(self) -> None:
        if self.showing_guidance:
            return
        self._end_arrow_drag()   # Escape mid-drag: the pointer still moving must not redraw it
        self.controller.clear()
        self._after_change(final=True)

    def confirm(self) -> Demonstration:
        """Record the pending arrow as the demonstration at the current state; show guidance or go on."""
        if self.pending_action is None or self.showing_guidance or self.episode.complete:
            raise RuntimeError("confirm: expected an arrow drawn at a state awaiting a demonstration")
        # Enter mid-drag: the drag ends with the confirmation, so the still pressed pointer cannot
        # change the confirmed arrow or draw one at the next state.
        self._end_arrow_drag()
        return self.controller.confirm()

    def advance(self) -> None:
        """Leave the guidance: the next query state (or the reproduction when complete)."""
        self.controller.next()

    def _on_event(self, event: str) -> None:
        """What the controller says (episode_controller.EVENTS), drawn."""
        if event == "recorded":
            return
        if event == "state":
            for entry in self.entries:  # empty fields: "Set arrow" never re-applies the previous state's numbers
                entry.value = 0.0
        if event == "reproduce" and self.play_on_complete:
            self.play()
        elif event != "finished":
            self._redraw_robot()
        self._update_words()

    def orbit(self, azimuth_deg: float = 0.0, elevation_deg: float = 0.0) -> None:
        """Turn the perspective camera by the given degrees (elevation kept in ``ELEVATION_RANGE``)."""
        if not (math.isfinite(azimuth_deg) and math.isfinite(elevation_deg)):
            raise ValueError(f"azimuth_deg, elevation_deg: expected finite degrees, got {azimuth_deg}, {elevation_deg}")
        self.azimuth_deg = (self.azimuth_deg + azimuth_deg) % 360.0
        self.elevation_deg = float(np.clip(self.elevation_deg + elevation_deg, *ELEVATION_RANGE))
        self._panels = self._make_panels()
        self._redraw_scene()
        if self.animation is None or self.animation.done or self.animation.cancelled:
            self._redraw_robot()

    def play(self):
        """Play the learnt skill's reproduction in all three panels (frames and ``canvas.sleep`` in chunks)."""
        trajectory = self.episode.reproduction
        at = frame_times(float(trajectory.times[0]), float(trajectory.times[-1]), REPRODUCTION_FPS)
        chains = self.skill.plant.sketch(sample_at(trajectory.times, trajectory.states, at)).chain  # (F, P, 3)
        # (F, panels, P, 2) pixels, computed once, not per frame; float32 halves the message (a pixel
        # needs no more).
        pixels = np.stack([panel.pixels(chains) for panel in self._panels.values()], axis=1).astype(np.float32)
        tips = np.ascontiguousarray(pixels[:, :, -1])   # (F, panels, 2)
        theme = self.theme

        # A frame is two drawing commands: every panel's arm in one stroke_line_segments and every
        # hand in one fill_circles. The styles are set once per chunk (setup), not per frame: each
        # style set is a traitlet change in the kernel and a command in the browser.
        def setup(canvas):
            canvas.line_width = 5.0
            canvas.line_cap = canvas.line_join = "round"
            canvas.stroke_style = theme.arm
            canvas.fill_style = theme.end_effector

        def draw_frame(canvas, index):
            canvas.stroke_line_segments(pixels[index])
            canvas.fill_circles(tips[index, :, 0], tips[index, :, 1], 6.0)

        def final(canvas):
            canvas.line_cap = canvas.line_join = "round"
            canvas.stroke_style = theme.trail
            canvas.line_width = 2.0
            canvas.stroke_line_segments(np.ascontiguousarray(tips.transpose(1, 0, 2)))
            setup(canvas)
            draw_frame(canvas, len(at) - 1)

        self.play_button.layout.display = None
        self.animation = play_frames(self, "robot", len(at), setup, draw_frame, final, fps=REPRODUCTION_FPS)
        self._update_words()
        return self.animation

    @property
    def finger_radius(self) -> float:
        """Canvas pixels around the hand where a finger starts a drag (larger than the mouse's)."""
        return 1.5 * max(self.grab_radius, FINGER_RADIUS_CSS_PX)

    # -- the ``view`` play_frames draws on ------------------------------------------------------------
    def layer(self, name: str):
        return self._layers[name]

    def remember(self, paint, name: str) -> None:
        self._paints[name] = paint

    def _repaint(self, name: str) -> None:
        paint = self._paints.get(name)
        if paint is not None:
            layer = self._layers[name]
            layer.clear()
            paint(layer)

    # -- geometry -------------------------------------------------------------------------------------
    def _make_panels(self) -> dict:
        size, margin = self.panel_size, 18.0
        panels = {}
        for name in SPACE_VIEWS:
            projection = self.drawing.projection(name)
            if name == "perspective":
                projection = replace(projection, azimuth_deg=self.azimuth_deg, elevation_deg=self.elevation_deg)
            extent = self._extent(projection)
            column, row = PANEL_CELLS[name]
            panels[name] = _Panel(name, projection, extent, column * size, row * size + 16.0, size - 16.0, margin)
        return panels

    def _extent(self, projection):
        bounds = self.drawing.bounds
        corners = np.array([[x, y, z] for x in bounds.xlim for y in bounds.ylim for z in bounds.zlim])
        flat = projection.project(corners)
        low, high = flat.min(axis=0), flat.max(axis=0)
        return Box((float(low[0]), float(high[0])), (float(low[1]), float(high[1])))

    def _tool(self) -> np.ndarray:
        state = self.current_state
        if state is None:
            state = self.episode.query_states[-1]
        return self.skill.plant.sketch(state[None]).chain[0, -1]

    # -- drawing --------------------------------------------------------------------------------------
    def _redraw_scene(self) -> None:
        self._paints["scene"] = self._paint_scene
        self._repaint_now("scene")

    def _redraw_robot(self) -> None:
        if self.animation is not None:
            stop_animation(self.plant_layer)
            self.animation = None
        self._paints["robot"] = self._paint_robot
        self._repaint_now("robot")

    def _repaint_now(self, name: str) -> None:
        with drawing_batch():
            self._repaint(name)

    def _paint_scene(self, canvas) -> None:
        theme, drawing = self.theme, self.drawing
        canvas.fill_style = theme.background
        canvas.fill_rect(0, 0, canvas.width, canvas.height)
        canvas.font = "13px sans-serif"
        canvas.text_align, canvas.text_baseline = "left", "top"
        bounds = drawing.bounds
        low, high = bounds.low, bounds.high
        box_edges = [(a, b) for a in range(8) for b in range(a + 1, 8) if bin(a ^ b).count("1") == 1]
        corners = np.array([[(high if i & 1 else low)[0], (high if i & 2 else low)[1], (high if i & 4 else low)[2]]
                            for i in range(8)])
        target = self.skill.target.shape() if self.skill.target is not None else None
        for name, panel in self._panels.items():
            canvas.stroke_style = theme.axes
            canvas.line_width = 1.0
            canvas.stroke_rect(panel.left + 1, panel.top, panel.size - 2, panel.size - 2)
            canvas.fill_style = theme.text
            canvas.fill_text(PANEL_TITLES[name], panel.left + 4, panel.top - 15)
            canvas.stroke_style = theme.grid
            corner_pixels = panel.pixels(corners)  # projected once: an orbit repaints this often
            for a, b in box_edges:  # the frame of the scene's bounds: depth cues in the 3-D panel
                canvas.stroke_lines(corner_pixels[[a, b]])
            canvas.fill_style = theme.grid
            canvas.global_alpha = 0.6
            for surface in drawing.surfaces:
                canvas.fill_polygon(panel.pixels(surface))
            canvas.global_alpha = 1.0
            canvas.stroke_style = theme.axes
            for surface in drawing.surfaces:
                canvas.stroke_lines(panel.pixels(surface))
            base = panel.pixels(np.array(drawing.base))
            canvas.fill_style = theme.arm
            canvas.fill_rect(float(base[0]) - 7, float(base[1]) - 4, 14, 8)
            if target is not None:
                points = panel.pixels(target.points)
                canvas.fill_style = canvas.stroke_style = theme.target
                if target.is_point:
                    canvas.fill_circle(float(points[0, 0]), float(points[0, 1]), 6.0)
                else:
                    canvas.line_width = 3.0
                    canvas.stroke_lines(points)
                label = panel.pixels(np.asarray(target.label_at))
                canvas.fill_text("goal", float(label[0]) + 8, float(label[1]) + 2)
        cell = self.panel_size
        canvas.fill_style = theme.text
        canvas.fill_text(f"Units: {drawing.units}; arrows {self.action_length:g} {drawing.units} "
                         f"per {drawing.action_units}", cell + 6, cell + 24)

    def _paint_robot(self, canvas) -> None:
        state = self.current_state
        if state is None:
            state = self.episode.query_states[-1]
        theme = self.theme
        sketch = self.skill.plant.sketch(state[None])
        chain = sketch.chain[0]
        tool = chain[-1]
        index = self._shown_index()
        user = optimal = None
        if self.showing_guidance:
            user = self.episode.demonstrations[index].action
            optimal = self.episode.optimal_actions[index]
        elif self.pending_action is not None:
            user = self.pending_action
        canvas.line_cap = canvas.line_join = "round"
        for panel in self._panels.values():
            pixels = panel.pixels(chain)
            canvas.stroke_style = theme.arm
            canvas.line_width = 5.0
            canvas.global_alpha = 1.0
            canvas.stroke_lines(pixels)
            canvas.fill_style = theme.arm
            for joint in pixels[1:-1]:
                canvas.fill_circle(float(joint[0]), float(joint[1]), 3.5)
            start = pixels[-1]
            canvas.fill_style = theme.end_effector
            canvas.stroke_style = theme.end_effector_outline
            canvas.line_width = 1.5
            canvas.fill_circle(float(start[0]), float(start[1]), HAND_RADIUS_PX)
            canvas.stroke_circle(float(start[0]), float(start[1]), HAND_RADIUS_PX)
            # Arrows over the hand; the optimal one at least a visible length (its size is then stated).
            user_tip = None if user is None else panel.pixels(tool + self.action_length * np.asarray(user))
            optimal_tip = None if optimal is None else self._optimal_tip(panel, tool, optimal)[0]
            draw_arrow_pair(canvas, start, user_tip, optimal_tip, theme.user_arrow, theme.optimal_arrow)
            canvas.global_alpha = 1.0
        if index is None:
            return
        # The active component, beside the keyboard's focus: which way the arrow keys move the tip.
        canvas.fill_style = theme.text
        canvas.font = "12px sans-serif"
        canvas.text_align, canvas.text_baseline = "left", "top"
        cell = self.panel_size
        canvas.fill_text(f"State {index + 1} of {self.episode.n_states}; keys change {self.active_component}",
                         cell + 6, cell + 44)
        if user is not None:
            canvas.fill_text("Arrow: " + ", ".join(f"{c} {v:+.3f}" for c, v in zip(COMPONENTS, user)),
                             cell + 6, cell + 62)
        if optimal is not None and self._optimal_drawn_longer(tool, optimal):
            canvas.fill_text("Dashed arrow drawn longer so that it shows:", cell + 6, cell + 80)
            canvas.fill_text(f"its size is {np.linalg.norm(optimal):.3f} {self.drawing.action_units}",
                             cell + 6, cell + 96)

    def _optimal_tip(self, panel: _Panel, tool, optimal):
        """(pixel, lengthened) of the optimal arrow's tip in ``panel``: to scale, or at least
        ``SHORTEST_OPTIMAL_PX`` long, so that a small optimal action does not hide under the hand's dot."""
        to_scale = panel.pixels(tool + self.action_length * np.asarray(optimal))
        return visible_tip(panel.pixels(tool), to_scale, SHORTEST_OPTIMAL_PX)

    def _optimal_drawn_longer(self, tool, optimal) -> bool:
        return any(self._optimal_tip(panel, tool, optimal)[1] for panel in self._panels.values())

    def _legend_html(self) -> str:
        theme = self.theme
        entries = [_entry(_dot_svg(theme.end_effector, 5, theme.end_effector_outline), "the tool (robot's hand)"),
                   _entry(_line_svg(theme.arm, 4), "the arm"),
                   _entry(_dot_svg(theme.target, 5), "the goal"),
                   _entry(_arrow_svg(theme.user_arrow), theme.legend_user)]
        if self.guidance:
            entries.append(_entry(_arrow_svg(theme.optimal_arrow), theme.legend_optimal))
        return "<div style='font-size:small'>" + "".join(entries) + "</div>"

    # -- words ----------------------------------------------------------------------------------------
    def _update_words(self) -> None:
        self.confirm_button.disabled = self.pending_action is None or self.showing_guidance
        self.clear_button.disabled = self.pending_action is None or self.showing_guidance
        self.next_button.layout.display = None if self.showing_guidance else "none"
        for entry in (*self.entries, self.set_button):
            entry.disabled = self.showing_guidance or self.current_state is None
        text = self.describe()
        self.readout.value = f"<small>{text}</small>"
        zones = ()
        if self.current_state is not None and not self.showing_guidance:
            finger = self.finger_radius
            zones = tuple((float(p[0]), float(p[1]), self.grab_radius, finger)
                          for p in (self.tool_pixel("top"), self.tool_pixel("side")))
            # A drag anywhere in the 3-D panel turns it: the whole panel is a grab zone for a finger.
            panel = self._panels["perspective"]
            zones += ((panel.left + panel.size / 2, panel.top + panel.size / 2, panel.size / 2, panel.size / 2),)
        self.description.update(text, zones)

    def describe(self) -> str:
        """The canvas in plain words (its text alternative; a screen reader reads it on each change)."""
        units, action_units = self.drawing.units, self.drawing.action_units
        goal = ""
        if self.skill.target is not None:
            goal = " " + fill_words("The goal is {target}.", target=self.theme.target_words(self.skill.target))
        head = (f"Three views of the robot: from the top, from the side and in 3-D (turned "
                f"{self.azimuth_deg:.0f} degrees round, {self.elevation_deg:.0f} up).{goal}")
        if self.current_state is None:
            played = " The robot replays what it learnt in all three views." if self.animation is not None else ""
            return f"{head} All {self.episode.n_states} demonstrations given.{played}"
        index = self._shown_index()
        x, y, z = self._tool()
        words = (f"{head} State {index + 1} of {self.episode.n_states}: the robot's hand is at x {x:.2f}, "
                 f"y {y:.2f}, height {z:.2f} {units}.")
        if self.showing_guidance:
            user = self.episode.demonstrations[index].action
            optimal = self.episode.optimal_actions[index]
            longer = ""
            if self._optimal_drawn_longer(self._tool(), optimal):
                longer = (f"; drawn longer than to scale so that it shows; its size is "
                          f"{np.linalg.norm(optimal):.3f} {action_units}")
            words += (f" Your arrow: {_vector_words(user, action_units)}. The optimal arrow (dashed): "
                      f"{_vector_words(optimal, action_units)}{longer}. Press Next state or Enter to go on.")
        elif self.pending_action is not None:
            words += f" Your arrow: {_vector_words(self.pending_action, action_units)}. Enter confirms it."
        else:
            words += " No arrow yet: drag from the hand in the top or side view, or type three numbers."
        return words

    # -- input ----------------------------------------------------------------------------------------
    def _accepting(self) -> bool:
        return self.current_state is not None and not self.showing_guidance

    def _after_change(self, final: bool) -> None:
        self._redraw_robot()
        if final:
            self._update_words()
            if self.pending_action is not None:
                for entry, value in zip(self.entries, self.pending_action):
                    entry.value = round(float(value), 4)

    def _panel_at(self, pointer):
        for name, panel in self._panels.items():
            if panel.contains(pointer):
                return name
        return None

    def _end_arrow_drag(self) -> None:
        if self._drag is not None and self._drag[0] == "arrow":
            self._pointer.cancel()

    def _press(self, x, y, radius: float) -> bool:
        """A button or finger down at canvas pixel (x, y): True when it starts a drag (an orbit, or an arrow)."""
        pointer = np.array([x, y], dtype=float)
        name = self._panel_at(pointer)
        if name == "perspective":
            self._drag = ("orbit", pointer)
            return True
        if name is None or not self._accepting():
            return False
        start = self.tool_pixel(name)
        near = np.hypot(*(pointer - start)) <= radius
        if self.pending_action is not None:
            tip = self.panel(name).pixels(self._tool() + self.action_length * self.pending_action)
            near = near or np.hypot(*(pointer - tip)) <= radius
        if not near:
            color = self.theme.color_name("end_effector")
            self.hint.value = (f"<small>Press on the robot's hand (the {color + ' ' if color else ''}dot) in the top "
                               f"or side view.</small>")
            return False
        self.hint.value = ""
        self.controller.note_input("pointer")
        # x is in both views: a drag changes it by the pointer's sideways travel from the press, so a
        # drag straight up in the side view keeps the x the top view set. A first arrow starts at the hand.
        if self.pending_action is None:
            self._drag = ("arrow", name, start, np.zeros(3))
        else:
            self._drag = ("arrow", name, pointer, self.pending_action.copy())
        self._drag_to(pointer, final=False)
        return True

    def _drag_to(self, pointer, final: bool) -> None:
        kind, value = self._drag[:2]
        if kind == "orbit":
            delta = np.asarray(pointer, dtype=float) - value
            self._drag = ("orbit", np.asarray(pointer, dtype=float))
            self.orbit(-ORBIT_DRAG_DEG_PER_PX * delta[0], ORBIT_DRAG_DEG_PER_PX * delta[1])
            if final:
                self._update_words()
            return
        _, _, pressed, at_press = self._drag
        panel = self.panel(value)
        start = self.tool_pixel(value)
        # Pixels back to world units: both orthographic views keep world lengths (scale px per unit).
        # x moves with the pointer from where it was pressed; the view's own component (y from the
        # top, the height from the side) is where the pointer is, measured from the hand.
        action = np.zeros(3) if self.pending_action is None else self.pending_action.copy()
        action[0] = at_press[0] + (float(pointer[0]) - pressed[0]) / panel.scale / self.action_length
        action[1 if value == "top" else 2] = -(float(pointer[1]) - start[1]) / panel.scale / self.action_length
        self.controller.hold(action, None)
        self._after_change(final)

    def _on_key_down(self, key, shift_key, ctrl_key, meta_key) -> None:
        orbits = {"a": (-ORBIT_KEY_DEG, 0.0), "d": (ORBIT_KEY_DEG, 0.0), "w": (0.0, ORBIT_KEY_DEG),
                  "s": (0.0, -ORBIT_KEY_DEG)}
        if key.lower() in orbits:
            self.orbit(*orbits[key.lower()])
            self._update_words()
            return
        if key == "Enter" and self.showing_guidance:
            self.advance()
            return
        if not self._accepting():
            return
        if key.lower() in COMPONENTS:
            self.active_component = key.lower()
            self._redraw_robot()
        elif key == " ":
            self.active_component = COMPONENTS[(COMPONENTS.index(self.active_component) + 1) % 3]
            self._redraw_robot()
        elif key in ARROW_KEY_SIGNS:
            # A step moves the arrow's tip by 2 % of the scene's size (Shift: 0.4 %), whatever the units.
            span = float(np.max(self.drawing.bounds.high - self.drawing.bounds.low))
            step = ARROW_KEY_SIGNS[key] * (0.004 if shift_key else 0.02) * span / self.action_length
            action = np.zeros(3) if self.pending_action is None else self.pending_action.copy()
            action[COMPONENTS.index(self.active_component)] += step
            self.set_action(action, method="keyboard")
        else:
            confirm_or_clear(key, self.pending_action is not None, self.confirm, self.clear_action)

    def _set_from_entries(self) -> None:
        values = [entry.value for entry in self.entries]
        try:
            action = check_space_action(values)
        except ValueError:
            self.hint.value = "<small>Type three finite numbers (x, y, z).</small>"
            return
        self.hint.value = ""
        self.set_action(action, method="numeric")


def _vector_words(vector, units: str) -> str:
    x, y, z = (float(v) for v in vector)
    return f"x {x:+.3f}, y {y:+.3f}, height {z:+.3f} {units}"
