"""The frozen protocol report states the hash, every parameter, the analysis plan and the power."""

import json

import numpy as np
import pandas as pd
import pytest
from scipy import stats

from mt_widgets.analysis.figures import plot_trajectories
from mt_widgets.analysis.protocol_report import protocol_report, report_markdown, write_protocol_report
from mt_widgets.analysis.statistics import analyse_changes, between_group_tests, participant_changes
from mt_widgets.core import SKILLS
from mt_widgets.in_silico import run_in_silico
from mt_widgets.study import load_protocol, parse_protocol
from mt_widgets.study.protocol import PROTOCOL_FOLDER


def test_the_report_holds_the_hash_every_parameter_the_plan_and_the_papers_sample_size(tmp_path):
    protocol = load_protocol("paper-sim")
    report = protocol_report(protocol)
    assert report["hash"] == protocol.hash
    names = {p["name"]: p["value"] for p in report["parameters"]}
    assert names["lambda"] == 0.01 and names["phases[2].episodes"] == 8 and names["guidance_modality"] == "arrows"
    assert names["before[0].sha256"] == protocol.step("video").video_sha256
    assert report["analysis_plan"]["test"] == "student" and report["analysis_plan"]["alternative"] == "less"
    # The paper: d = 0.9, alpha 0.05, power 0.8, one-tailed -> 16 per group (32), power 0.8003.
    power = report["power_analysis"]
    assert (power["n_per_group"], power["n_total"]) == (16, 32)
    assert power["power_reached"] == pytest.approx(0.8003, abs=1e-4)
    md, js = write_protocol_report("paper-sim", tmp_path)
    text = md.read_text()
    assert protocol.hash in text and "**16 per group**" in text and "Student's t-test" in text
    assert json.loads(js.read_text())["hash"] == protocol.hash


def test_a_protocols_own_plan_changes_the_report():
    source = (PROTOCOL_FOLDER / "paper_sim.toml").read_text() + """
[analysis]
test = "welch"
alternative = "two-sided"
effect_size = 0.9
"""
    protocol = parse_protocol(source, str(PROTOCOL_FOLDER / "custom.toml"))
    report = protocol_report(protocol)
    assert report["power_analysis"]["n_per_group"] == 21 and report["power_analysis"]["tails"] == 2
    assert "Welch's t-test, two-sided" in report_markdown(report)
    assert protocol.hash != load_protocol("paper-sim").hash


def test_students_t_is_computed_beside_welch_and_the_primary_test_is_recorded():
    rng = np.random.default_rng(3)
    rows = []
    for i in range(12):
        group = "target" if i % 2 else "control"
        before = 3 + rng.normal()
        rows += [{"participant": f"p{i}", "group": group, "phase": "P1", "episode": 1, "teaching_error": before},
                 {"participant": f"p{i}", "group": group, "phase": "P2", "episode": 1, "teaching_error": before + 0.1},
                 {"participant": f"p{i}", "group": group, "phase": "P4", "episode": 1,
                  "teaching_error": before - (1.0 if group == "target" else 0.0) + rng.normal(0, 0.5 + (i % 2))}]
    from mt_widgets.study.analysis_plan import Change
    changes = [Change("P1_to_P4", ("P1", 1), ("P4", 1), "P1 -> P4", "retention")]
    table = participant_changes(pd.DataFrame(rows), changes)
    row = between_group_tests(table).iloc[0]
    target = table[table.group == "target"].delta.to_numpy()
    control = table[table.group == "control"].delta.to_numpy()
    pooled = np.sqrt(((len(target) - 1) * target.var(ddof=1) + (len(control) - 1) * control.var(ddof=1))
                     / (len(target) + len(control) - 2))
    t = (target.mean() - control.mean()) / (pooled * np.sqrt(1 / len(target) + 1 / len(control)))
    assert row["student_t"] == pytest.approx(t) and row["student_df"] == len(target) + len(control) - 2
    assert row["student_p"] == pytest.approx(stats.t.cdf(t, len(target) + len(control) - 2))
    assert row["student_p"] != pytest.approx(row["welch_p"])
    result = analyse_changes(pd.DataFrame(rows), changes, test="student")
    assert result.test == "student" and list(result.primary_p) == [row["student_p"]]
    assert "Student's t-test (primary)" in result.summary()
    assert set(result.results_table()["primary_test"]) == {"student"}
    with pytest.raises(ValueError, match="test"):
        analyse_changes(pd.DataFrame(rows), changes, test="anova")


def test_fig5_draws_the_true_skills_rollout_and_a_zoom_on_the_goal():
    study = run_in_silico(4, seed=1, reproduce=True, progress=False)
    participant = study.episodes.participant.iloc[0]
    figure = plot_trajectories(study.episodes, [participant], trajectories=study.reproductions)
    axes = figure.axes
    zooms = [child for ax in axes for child in ax.child_axes if child.get_gid() == "zoom"]
    assert len(zooms) == len(axes) == 3
    for ax in axes + zooms:
        assert any(str(line.get_gid()).startswith("true/") for line in ax.lines)
    truth = SKILLS["sim-point"].reproduce(SKILLS["sim-point"].theta, record_every=20)
    line = [ln for ln in axes[0].lines if ln.get_gid() == "true/sim-point"][0]
    assert np.allclose(line.get_xydata(), truth.positions)
    x0, x1 = zooms[0].get_xlim()
    assert x0 < 0.8 < x1 and (x1 - x0) < 0.25 * 4.4   # around skill 1's point, much smaller than the view
    plain = plot_trajectories(study.episodes, [participant], trajectories=study.reproductions, true_skill=False,
                              zoom=False)
    assert not any(child.get_gid() == "zoom" for ax in plain.axes for child in ax.child_axes)
    assert not any(str(ln.get_gid()).startswith("true/") for ax in plain.axes for ln in ax.lines)


def test_a_followup_protocols_report_lists_its_sessions_windows_and_every_step(tmp_path):
    markdown, data = write_protocol_report("paper-sim-followup", tmp_path)
    text = markdown.read_text()
    assert "## Sessions" in text
    assert "- `followup`: phases F1, F2 (4 w to 6 w after the previous session; too early: refuse, too late: flag)" \
        in text
    assert "| F1 | sim-point | 1 | 5 | - |" in text and "(target minus control)" in text
    report = json.loads(data.read_text())
    assert [p["session"] for p in report["phases"]][-2:] == ["followup", "followup"]
    assert "followup_questionnaire" in [s["id"] for s in report["steps"]]
