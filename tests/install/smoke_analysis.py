"""The analysis shape (``pip install "mt-widgets[analysis]"``): the analysis of the shipped synthetic study."""

import matplotlib

matplotlib.use("Agg")  # no display: the figures are drawn, not shown

from mt_widgets.analysis import EXAMPLE_STUDY, analyse_study  # noqa: E402

analysis = analyse_study(EXAMPLE_STUDY, trajectories_for=[])
participants = analysis.episodes["participant"].nunique()
assert participants >= 8, participants
assert {"error_by_episode", "changes"} <= set(analysis.figures), set(analysis.figures)
summary = analysis.summary()
assert "Hedges' g" in summary, summary
print(f"analysis: {participants} participants, {len(analysis.episodes)} episode rows")
