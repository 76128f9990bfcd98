"""Teaching widgets (ipycanvas + ipywidgets): draw demonstrations, see guidance, watch the robot.

- ``EpisodeWidget``: a whole episode (the three-line entry point).
- ``TeachingCanvas``: query states one after another, an arrow drawn at each.
- ``ArmView``: the workspace, target and robot on layered canvases.
- ``ReproductionPlayer``: the learnt skill's rollout as an animation.
- ``DemoPage``: the visitors' one-click page (skill chooser, guidance switch, try again).
- ``EffortProgress``, ``GuidancePanel``: the progress bars and the guidance in words.
- ``ViewTransform``: world <-> pixel mapping; ``draw_arrow``: arrow rendering;
  ``play_frames``: animation (``stop_animations`` / ``retire`` when a view is replaced);
  ``THEMES``: colour-blind-safe default and the paper's look.

Widgets hold no science: they call ``mt_widgets.core`` and draw the result.
"""

from .animation import Animation, frame_times, play_frames, retire, sample_at, stop_animations
from .arm_view import LAYERS, ArmView
from .arrows import draw_arrow, draw_arrow_pair
from .coords import ViewTransform
from .demo import DEMO_SKILLS, DemoPage
from .episode import DemonstrationRecord, EpisodeResult, EpisodeWidget, keep_canvas_size
from .guidance import GuidancePanel, explain_difference, legend_html
from .legend import MARKS, CanvasLegend, legend_entries
from .progress import EffortProgress
from .redraw import drawing_batch, repaint_on_new_view
from .reproduction import ReproductionPlayer
from .robots import RobotPainter, painter_for
from .teaching import ConfirmedAction, TeachingCanvas, describe_action
from .theme import (
                    COLOR_NAMES,
                    DEFAULT_THEME,
                    PAPER_THEME,
                    PAPER_UARM_THEME,
                    THEMES,
                    ArrowStyle,
                    Theme,
                    fill_words,
                    get_theme,
)

__all__ = [
    "COLOR_NAMES", "MARKS", "Animation", "ArmView", "ArrowStyle", "CanvasLegend", "ConfirmedAction", "DEFAULT_THEME",
    "DEMO_SKILLS", "DemoPage", "DemonstrationRecord", "EffortProgress", "EpisodeResult", "EpisodeWidget",
    "GuidancePanel", "LAYERS", "PAPER_THEME", "PAPER_UARM_THEME", "ReproductionPlayer", "RobotPainter", "THEMES",
    "TeachingCanvas", "Theme", "ViewTransform", "describe_action", "draw_arrow", "draw_arrow_pair", "drawing_batch",
    "explain_difference", "fill_words", "frame_times", "get_theme", "keep_canvas_size", "legend_entries",
    "legend_html", "painter_for", "play_frames", "repaint_on_new_view", "retire", "sample_at", "stop_animations",
]
