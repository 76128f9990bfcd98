"""mt-widgets: teach novices to teach robots, with exact machine-teaching guidance.

The science lives in ``mt_widgets.core`` (no Jupyter dependency); the widgets in
``mt_widgets.widgets``; the study runner and analysis in ``mt_widgets.study``; the uArm
Swift Pro connector in ``mt_widgets.hardware``.
"""

from .core import (
    DEFAULT_LAMBDA,
    SKILLS,
    RidgeLearner,
    SeedSchedule,
    Skill,
    TeachingEpisode,
    TwoLinkArm,
    analyse_demonstrations,
    optimal_actions,
    teaching_risk,
)

__version__ = "0.1.0"

__all__ = ["DEFAULT_LAMBDA", "SKILLS", "RidgeLearner", "SeedSchedule", "Skill", "TeachingEpisode", "TwoLinkArm",
           "analyse_demonstrations", "optimal_actions", "teaching_risk", "__version__"]
