"""A study of a user's own protocol, analysed end to end as its protocol says: groups "guided" and
"unguided", a user's own skill (a ring, tests/in_silico/circle_skills.py), three phases, its own
changes, primary test and no paper baseline; figures included."""

import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from mt_widgets.analysis import analyse_study
from mt_widgets.analysis.figures import trajectory_panels
from mt_widgets.in_silico import run_through_sessions
from mt_widgets.study import load_protocol

pytestmark = pytest.mark.slow  # runs 8 synthetic participants through the session engine

SKILLS_FILE = Path(__file__).resolve().parents[1] / "in_silico" / "circle_skills.py"
PROTOCOL = """
format = 1
name = "ring-lab"
groups = ["guided", "unguided"]
lambda = 0.01
seed = 5
[skills]
module = "circle_skills.py"
[assignment]
block_size = 2
seed = 1
[texts]
welcome = "Welcome."
consent = "Consent."
instructions = "Instructions."
reproduction = "Reproduction."
thank_you = "Thank you."
[practice]
skill = "sim-point"
duration_s = 0
text = "Practice."
[analysis]
test = "welch"
alternative = "two-sided"
alpha = 0.1
changes = [
  {name = "before_to_after", before = ["R1", 1], after = ["R3", 1], label = "R1 -> R3", meaning = "ring skill kept"},
  {name = "training", before = ["R2", 1], after = ["R2", 3], label = "R2E1 -> R2E3", meaning = "during training"},
]
[[phases]]
id = "R1"
skill = "sim-ring"
episodes = 1
instructions = "Reach the ring."
[[phases]]
id = "R2"
skill = "sim-ring"
episodes = 3
guidance = ["guided"]
instructions = "Reach the ring again."
[[phases]]
id = "R3"
skill = "sim-ring"
episodes = 1
instructions = "Once more."
"""


@pytest.fixture(scope="module")
def analysed(tmp_path_factory):
    lab = tmp_path_factory.mktemp("lab")
    shutil.copy(SKILLS_FILE, lab / "circle_skills.py")
    (lab / "ring.toml").write_text(PROTOCOL, encoding="utf-8")
    protocol = load_protocol(lab / "ring.toml")
    run_through_sessions(lab / "study", n_participants=8, protocol=protocol, seed=3)
    return protocol, analyse_study(lab / "study")


def test_groups_changes_and_the_primary_test_come_from_the_protocol(analysed):
    protocol, result = analysed
    statistics = result.statistics
    assert statistics.groups == ("guided", "unguided") and statistics.test == "welch"
    assert statistics.alternative == "two-sided" and statistics.alpha == 0.1
    assert list(statistics.between["change"]) == ["before_to_after", "training"]
    row = statistics.between.iloc[0]
    assert row["n_guided"] == 4 and row["n_unguided"] == 4
    table = statistics.changes[statistics.changes["change"] == "before_to_after"]
    guided = table.loc[table["group"] == "guided", "delta"].to_numpy()
    unguided = table.loc[table["group"] == "unguided", "delta"].to_numpy()
    assert row["welch_p"] == pytest.approx(stats.ttest_ind(guided, unguided, equal_var=False).pvalue)
    assert list(statistics.primary_p) == list(statistics.between["welch_p"])
    assert statistics.baseline.empty  # the paper's P1 vs P2 check does not apply to this protocol


def test_the_summary_speaks_of_this_protocol_not_the_paper(analysed):
    _, result = analysed
    summary = result.summary()
    assert "4 participants in the guided group (guided in R2) and 4 in the unguided group (never guided)" in summary
    assert "R1 -> R3 (ring skill kept)" in summary and "R2E1 -> R2E3 (during training)" in summary
    assert "Welch's t-test (primary)" in summary
    for paper_word in ("target", "control", "P3", "retention", "transfer", "Baseline check"):
        assert paper_word not in summary


def test_every_figure_is_drawn_for_the_users_groups_phases_and_skill(analysed, tmp_path):
    protocol, result = analysed
    assert set(result.figures) == {"error_by_episode", "changes", "trajectories"}
    lines = {line.get_gid() for line in result.figures["error_by_episode"].axes[0].lines}
    assert {"guided", "unguided"} <= lines
    xlabel = result.figures["error_by_episode"].axes[0].get_xlabel()
    assert "guided group" in xlabel and "target" not in xlabel
    ticks = [t.get_text() for t in result.figures["error_by_episode"].axes[0].get_xticklabels()]
    assert ticks == ["R1E1", "R2E1", "R2E2", "R2E3", "R3E1"]
    titles = [ax.get_title() for ax in result.figures["changes"].axes]
    assert titles == ["R1 -> R3\n(ring skill kept)", "R2E1 -> R2E3\n(during training)"]
    assert trajectory_panels(protocol) == (("R2",), ("R1", "R3"))
    gids = {line.get_gid() for ax in result.figures["trajectories"].axes for line in ax.lines}
    assert "S001/R2E3" in gids and "true/sim-ring" in gids
    # The ring is drawn as the user's target (its 73-point circle), not the paper's point.
    ring = [line for ax in result.figures["trajectories"].axes for line in ax.lines if line.get_gid() == "target"]
    assert ring and len(ring[0].get_xdata()) == 73
    assert np.allclose(np.hypot(np.asarray(ring[0].get_xdata()) - 0.8, np.asarray(ring[0].get_ydata()) - 1.2), 0.3)
    written = result.save(tmp_path / "out", formats=("png",))
    assert {p.name for p in written} >= {"error_by_episode.png", "changes.png", "trajectories.png", "summary.txt"}
