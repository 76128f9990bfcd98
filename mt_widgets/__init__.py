"""mt-widgets: teach novices to teach robots, with exact machine-teaching guidance.

The science lives in ``mt_widgets.core`` (no Jupyter dependency, no file read); robot models read
from their URDFs in ``mt_widgets.robot_models``; the arms built from them on core's engine (the
shipped UR5, Panda and SO-101, whose skills join ``SKILLS`` here, and a user's own) in
``mt_widgets.arms``; the widgets in
``mt_widgets.widgets``; the study runner (protocol, participants, session, log, export) in
``mt_widgets.study``; synthetic teachers and in-silico studies in ``mt_widgets.in_silico``;
statistics, power, figures and the comparison with the paper in ``mt_widgets.analysis``; a
class's progress files and checks in ``mt_widgets.classroom``; the uArm Swift Pro connector in
``mt_widgets.hardware``; the pages and kiosks built from them in ``mt_widgets.apps``.
Kernels forked from an already-imported template (the class hub, the study pages) in
``mt_widgets.kernels``.
The ``mt-widgets`` command (the lab, the demo, a study, a class's checks) is ``mt_widgets.cli``.
"""

from importlib.metadata import PackageNotFoundError, version

# The shipped arms' skills join SKILLS (each arm read from its URDF when one of its skills is first
# asked for): imported here so every ``SKILLS`` a program reaches holds them.
from .arms import SHIPPED_ARMS  # noqa: F401
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

try:  # The one version source is pyproject.toml; the installed package's metadata carries it.
    __version__ = version("mt-widgets")
except PackageNotFoundError:  # imported from a source tree that was never installed
    __version__ = "0+unknown"

__all__ = ["DEFAULT_LAMBDA", "SKILLS", "RidgeLearner", "SeedSchedule", "Skill", "TeachingEpisode", "TwoLinkArm",
           "analyse_demonstrations", "optimal_actions", "teaching_risk", "__version__"]
