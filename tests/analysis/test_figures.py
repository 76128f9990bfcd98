"""Figures from a synthetic study: the plotted data is the study's data."""

import json

import numpy as np
import pytest

from mt_widgets.analysis.figures import (
    plot_changes,
    plot_error_by_episode,
    plot_trajectories,
    save_figure,
    teaching_report,
)
from mt_widgets.analysis.statistics import participant_changes
from mt_widgets.core import SKILLS
from mt_widgets.in_silico.engine import run_in_silico


@pytest.fixture(scope="module")
def study():
    return run_in_silico(8, seed=3, reproduce=False)


def _line(figure, gid):
    for ax in figure.axes:
        for line in ax.lines:
            if line.get_gid() == gid:
                return line
    raise AssertionError(f"no line {gid!r}")


def _collection(figure, gid, axis=0):
    for collection in figure.axes[axis].collections:
        if collection.get_gid() == gid:
            return collection
    raise AssertionError(f"no collection {gid!r}")


def test_fig3a_plots_each_groups_mean_error_per_episode(study):
    figure = plot_error_by_episode(study.episodes, error_bars="sd")
    rows = study.episodes
    for group in ("target", "control"):
        line = _line(figure, group)
        expected = rows[rows.group == group].groupby(["phase_index", "episode"]).theta_error.mean().to_numpy()
        assert line.get_ydata() == pytest.approx(expected)
        assert list(line.get_xdata()) == list(range(12))
    labels = [t.get_text() for t in figure.axes[0].get_xticklabels()]
    assert labels[0] == "P1E1" and labels[2] == "P3E1" and labels[-1] == "P5E1"


def test_fig3a_error_bars_are_the_standard_error(study):
    figure = plot_error_by_episode(study.episodes, error_bars="sem")
    rows = study.episodes[(study.episodes.group == "target") & (study.episodes.phase == "P1")]
    errors = rows.theta_error.to_numpy()
    sem = errors.std(ddof=1) / np.sqrt(errors.size)
    # The error bar's segment for P1E1 spans mean - sem to mean + sem.
    bars = [c for c in figure.axes[0].collections if len(c.get_segments()) == 12]
    spans = {round(float(s[1, 1] - s[0, 1]), 9) for c in bars for s in c.get_segments()[:1]}
    assert round(2 * sem, 9) in spans


def test_fig3bd_strips_hold_every_participants_change(study):
    figure = plot_changes(study.episodes)
    changes = participant_changes(study.episodes)
    for axis, name in enumerate(["P1_to_P3E8", "P1_to_P4", "P2_to_P5"]):
        for group in ("target", "control"):
            points = _collection(figure, f"strip-{group}", axis).get_offsets()
            expected = changes[(changes.change == name) & (changes.group == group)].delta.to_numpy()
            assert sorted(points[:, 1]) == pytest.approx(sorted(expected))
            mean = _line_in(figure.axes[axis], f"mean-{group}")
            assert mean.get_ydata()[0] == pytest.approx(expected.mean())


def _line_in(ax, gid):
    return next(line for line in ax.lines if line.get_gid() == gid)


def test_fig5_draws_the_reproduction_of_each_learnt_skill_beside_the_target(study):
    participant = study.episodes.participant.iloc[0]
    figure = plot_trajectories(study.episodes, [participant], duration=1.0)
    row = study.episodes[(study.episodes.participant == participant) & (study.episodes.phase == "P4")].iloc[0]
    theta = np.array(json.loads(row.theta_hat))
    expected = SKILLS["sim-point"].reproduce(theta, duration=1.0, record_every=20).positions
    line = _line(figure, f"{participant}/P4E1")
    assert np.column_stack([line.get_xdata(), line.get_ydata()]) == pytest.approx(expected)
    target = _line(figure, "target")
    assert (target.get_xdata()[0], target.get_ydata()[0]) == pytest.approx((0.8, 1.2))
    assert len(figure.axes) == 3
    p3 = [line for line in figure.axes[0].lines if str(line.get_gid()).startswith(f"{participant}/P3E")]
    assert len(p3) == 8


@pytest.mark.slow
def test_the_report_shows_the_participants_own_errors_and_arrows(study, tmp_path):
    participant = study.episodes.participant.iloc[-1]
    figure = teaching_report(study.episodes, study.demonstrations, participant)
    mine = study.episodes[study.episodes.participant == participant]
    assert _line(figure, "participant-error").get_ydata() == pytest.approx(mine.theta_error.to_numpy())
    demos = study.demonstrations
    demos = demos[(demos.participant == participant) & (demos.phase == "P1")]
    u = demos[["action_1", "action_2"]].to_numpy()
    o = demos[["optimal_1", "optimal_2"]].to_numpy()
    ratio = np.mean(np.linalg.norm(u, axis=1) / np.linalg.norm(o, axis=1))
    assert _line(figure, "length-ratio").get_ydata()[0] == pytest.approx(ratio)
    text = " ".join(t.get_text() for ax in figure.axes for t in ax.texts)
    assert "P1 -> P4" in text
    assert save_figure(figure, tmp_path / "report.pdf").stat().st_size > 1000


def test_save_figure_refuses_unknown_formats(study, tmp_path):
    figure = plot_changes(study.episodes)
    with pytest.raises(ValueError, match="path"):
        save_figure(figure, tmp_path / "figure.jpg")
    assert save_figure(figure, tmp_path / "figure.svg").read_text().lstrip().startswith("<?xml")
