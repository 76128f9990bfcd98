"""Figures of a teaching study, from its tidy rows (matplotlib; save as PNG, SVG or PDF).

- ``plot_error_by_episode``: mean teaching error per group across every phase and episode,
  with error bars (the paper's Fig. 3a).
- ``plot_changes``: box and strip plots of each participant's change per group (Fig. 3b-d).
- ``plot_trajectories``: what the robot learnt from each participant, rolled out beside the
  target, phase by phase (Fig. 5).
- ``teaching_report``: one page a participant or a student takes home.

Every function returns a ``matplotlib.figure.Figure`` built without pyplot (nothing is kept
open behind the caller's back; a notebook shows the returned figure). ``save_figure`` writes
it. Groups use the Okabe-Ito palette plus line styles and markers, so they stay apart in grey
and for colour-blind readers.
"""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import matplotlib as mpl
import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from mt_widgets.core import SKILLS, Box
from mt_widgets.core.validation import as_bool
from mt_widgets.study.analysis_plan import PAPER_CHANGES

from .tables import ERROR_LABELS, episodes_frame, error_measure, participant_changes, phase_summary, study_groups

#: Okabe-Ito colours, a line style and a marker per group.
GROUP_STYLE = {
    "target": {"color": "#0072B2", "linestyle": "-", "marker": "o"},
    "control": {"color": "#E69F00", "linestyle": "--", "marker": "s"},
}
TARGET_STYLE = {"color": "#D55E00", "linewidth": 2.0}
OPTIMAL_STYLE = {"color": "#009E73"}
FORMATS = ("png", "svg", "pdf")


#: Styles of a protocol's groups by position (the first compared group looks like the paper's target).
_BY_POSITION = (GROUP_STYLE["target"], GROUP_STYLE["control"], {"color": "#555555", "linestyle": ":", "marker": "^"})


def _style(group: str, groups=()) -> dict:
    if group in GROUP_STYLE:
        return GROUP_STYLE[group]
    position = list(groups).index(group) if group in groups else len(_BY_POSITION) - 1
    return _BY_POSITION[min(position, len(_BY_POSITION) - 1)]


def save_figure(figure: Figure, path, dpi: int = 150) -> Path:
    """Writes a figure as PNG, SVG or PDF, chosen by the file's suffix.

    Args:
        figure: the figure.
        path: where; the suffix (.png, .svg, .pdf) picks the format.
        dpi: resolution of PNGs.

    Returns:
        The path written.
    """
    path = Path(path)
    suffix = path.suffix.lower().lstrip(".")
    if suffix not in FORMATS:
        raise ValueError(f"path: expected a file name ending in one of {['.' + f for f in FORMATS]}, got {path.name!r}")
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=dpi, bbox_inches="tight")
    return path


# -- Fig. 3a -------------------------------------------------------------------------------------

def plot_error_by_episode(episodes, error_bars: str = "sem", confidence: float = 0.95, ax=None,
                          groups=None) -> Figure:
    """Mean teaching error of each group across every phase and episode (the paper's Fig. 3a).

    Args:
        episodes: episode rows (a DataFrame or ``read_study``'s list of dicts).
        error_bars: "sem" (standard error), "sd", or "ci" (t confidence interval).
        confidence: coverage when ``error_bars`` is "ci".
        ax: draw into this Axes instead of a new figure.
        groups: the protocol's groups, in order (None: the paper's, then any others).

    Returns:
        The figure. One errorbar line per group (``gid`` = the group), x = 0, 1, ... in
        protocol order, ticks labelled "P1E1", "P3E2", ...; guided phases are shaded.
    """
    if error_bars not in ("sem", "sd", "ci"):
        raise ValueError(f"error_bars: expected 'sem', 'sd' or 'ci', got {error_bars!r}")
    frame = episodes_frame(episodes, groups)
    groups = study_groups(frame, groups)
    table = phase_summary(frame, confidence, groups)
    labels = list(dict.fromkeys(table["label"]))
    position = {label: i for i, label in enumerate(labels)}
    figure, ax = _figure_and_axes(ax, (9, 4))
    for group in [g for g in groups if g in set(table["group"])]:
        part = table[table["group"] == group]
        x = np.array([position[label] for label in part["label"]])
        y = part["mean"].to_numpy()
        if error_bars == "ci":
            yerr = np.vstack([y - part["ci_low"].to_numpy(), part["ci_high"].to_numpy() - y])
        else:
            yerr = part[error_bars].to_numpy()
        style = _style(group, groups)
        container = ax.errorbar(x, y, yerr=yerr, capsize=3, label=f"{group} (n = {part['n'].max()})", **style)
        container.lines[0].set_gid(group)
    # Shade the episodes in which some group saw guidance, so the treatment phase stands out.
    shown_to = []
    if "guidance" in frame.columns:
        shown_to = sorted(set(frame.loc[frame["guidance"].astype(bool), "group"]), key=list(groups).index)
        guided = frame.groupby(["phase", "episode"])["guidance"].max()
        for (phase, episode), shown in guided.items():
            if shown and f"{phase}E{episode}" in position:
                i = position[f"{phase}E{episode}"]
                ax.axvspan(i - 0.5, i + 0.5, color="#CCCCCC", alpha=0.35, lw=0, zorder=0)
    ax.set_xticks(range(len(labels)))
    ax.set_xticklabels(labels, rotation=45, ha="right")
    measure = error_measure(frame)
    ax.set_ylabel(f"{measure}: {ERROR_LABELS[measure]}")
    ax.set_xlabel("phase and episode" + (f" (grey: guidance shown to the {' and '.join(shown_to)} group)"
                                         if shown_to else ""))
    what = {"sem": "mean ± SEM", "sd": "mean ± SD", "ci": f"mean, {confidence:.0%} CI"}[error_bars]
    ax.set_title(f"{ERROR_LABELS[measure].split(' ||')[0].capitalize()} ({measure}) across the study ({what})")
    ax.set_ylim(bottom=0)
    ax.legend(frameon=False)
    return figure


def _figure_and_axes(ax, size):
    if ax is None:
        figure = Figure(figsize=size, layout="constrained")
        return figure, figure.add_subplot()
    return ax.figure, ax


# -- Fig. 3b-d -----------------------------------------------------------------------------------

def plot_changes(episodes, changes=PAPER_CHANGES, seed: int = 0, groups=None) -> Figure:
    """Box and strip plots of each participant's change of error, per group (Fig. 3b-d).

    Args:
        episodes: episode rows.
        changes: the comparisons, one panel each (default the paper's three).
        seed: seeds the horizontal jitter of the strip points (for reproducible figures).
        groups: the protocol's groups, in order (None: the paper's, then any others).

    Returns:
        The figure. In each panel (title = the change's label) group i is at x = i: a box
        (``gid`` "box-<group>") and a scatter of the participants' changes (``gid`` "strip-<group>").
    """
    frame = episodes_frame(episodes, groups)
    order = study_groups(frame, groups)
    table = participant_changes(frame, changes)
    rng = np.random.default_rng(seed)
    figure = Figure(figsize=(3.2 * len(changes), 3.8), layout="constrained")
    axes = figure.subplots(1, len(changes), sharey=True, squeeze=False)[0]
    for ax, change in zip(axes, changes):
        part = table[table["change"] == change.name]
        groups = [g for g in order if g in set(part["group"])]
        data = [part.loc[part["group"] == g, "delta"].to_numpy() for g in groups]
        boxes = ax.boxplot(data, positions=range(len(groups)), widths=0.5, showfliers=False, patch_artist=True)
        for i, (group, values) in enumerate(zip(groups, data)):
            style = _style(group, order)
            boxes["boxes"][i].set(facecolor=style["color"], alpha=0.25, edgecolor=style["color"])
            boxes["boxes"][i].set_gid(f"box-{group}")
            boxes["medians"][i].set(color=style["color"], linewidth=2)
            jitter = rng.uniform(-0.12, 0.12, size=values.size)
            strip = ax.scatter(i + jitter, values, s=18, color=style["color"], marker=style["marker"], zorder=3,
                               edgecolors="white", linewidths=0.5)
            strip.set_gid(f"strip-{group}")
            ax.plot([i - 0.25, i + 0.25], [values.mean()] * 2, color="black", lw=1, ls=":", gid=f"mean-{group}")
        ax.axhline(0, color="#888888", lw=0.8)
        ax.set_xticks(range(len(groups)))
        ax.set_xticklabels(groups)
        ax.set_title(f"{change.label}\n({change.meaning})", fontsize=10)
    axes[0].set_ylabel(f"change of {error_measure(frame)} (after - before)")
    return figure


# -- Fig. 5 --------------------------------------------------------------------------------------

#: Panels of the trajectory figure, as in the paper's Fig. 5: the training phase, then the
#: trained skill before and after, then the new skill before and after.
TRAJECTORY_PANELS = (("P3",), ("P1", "P4"), ("P2", "P5"))


def trajectory_panels(protocol) -> tuple[tuple[str, ...], ...]:
    """The trajectory figure's panels for a protocol: its guided phases first (each on its own),
    then, per skill, the unguided phases of that skill in order (every session's). For the
    paper's protocols this is ``TRAJECTORY_PANELS``."""
    phases = protocol.all_phases
    guided = [(phase.id,) for phase in phases if phase.guidance]
    by_skill: dict[str, list[str]] = {}
    for phase in phases:
        if not phase.guidance:
            by_skill.setdefault(phase.skill, []).append(phase.id)
    return tuple(guided) + tuple(tuple(ids) for ids in by_skill.values())


def learnt_trajectories(episodes, participants, phases, duration: float | None = None, record_every: int = 20,
                        skills=None):
    """Rolls out the skill each participant taught in each episode of ``phases``.

    Args:
        episodes: episode rows with ``skill`` and ``theta_hat`` (JSON list of rows).
        participants: participant codes.
        phases: phase ids.
        duration: seconds per rollout (default the plant's).
        record_every: control steps between recorded samples.
        skills: where the episodes' skill keys are looked up (default the paper's ``SKILLS``; a
            protocol's ``skills`` for a study of a user's own skills).

    Returns:
        {(participant, phase, episode): Trajectory}.
    """
    frame = episodes_frame(episodes)
    if "theta_hat" not in frame.columns or "skill" not in frame.columns:
        raise ValueError("episodes: expected the columns 'skill' and 'theta_hat' to roll out the learnt skills")
    rows = frame[frame["participant"].isin([str(p) for p in participants]) & frame["phase"].isin(phases)]
    out = {}
    for skill_key, part in rows.groupby("skill", sort=False):
        thetas = np.array([_theta(value) for value in part["theta_hat"]])
        skill = (SKILLS if skills is None else skills)[skill_key]
        batch = skill.reproduce(thetas, duration=duration, record_every=record_every)
        for k, (_, row) in enumerate(part.iterrows()):
            out[(row["participant"], row["phase"], int(row["episode"]))] = batch[k]
    return out


def _has_theta(value) -> bool:
    return isinstance(value, list) or (isinstance(value, str) and value.strip() not in ("", "null"))


def _theta(value) -> np.ndarray:
    return np.asarray(json.loads(value) if isinstance(value, str) else value, dtype=float)


def _draw_target(ax, skill) -> None:
    target = skill.target
    if target is None:
        return
    # The target draws itself (Target.shape), any kind of target alike; clipped to a view a
    # workspace wider on each side than the workspace, so a line runs off the axes.
    box = skill.workspace
    span = max(box.xlim[1] - box.xlim[0], box.ylim[1] - box.ylim[0])
    shape = target.shape(Box((box.xlim[0] - span, box.xlim[1] + span), (box.ylim[0] - span, box.ylim[1] + span)))
    if shape.is_point:
        ax.plot(shape.points[:, 0], shape.points[:, 1], marker="*", markersize=14, linestyle="none", gid="target",
                label="target", color=TARGET_STYLE["color"])
    elif len(shape.points):
        ax.plot(shape.points[:, 0], shape.points[:, 1], gid="target", label="target", **TARGET_STYLE)


def _zoom_box(skill, trajectories, fraction: float = 0.12):
    """(xlim, ylim) of a square around where the rollouts end near the target (Fig. 5's zoom)."""
    box = skill.workspace
    half = fraction * max(box.xlim[1] - box.xlim[0], box.ylim[1] - box.ylim[0]) / 2
    end = np.asarray(trajectories[0].positions[-1], dtype=float)
    # A point target is where to zoom; a line (or any target with extent) has no single point:
    # centre on where the true skill stops on it.
    centre = end if skill.target is None or skill.target.dimension > 0 else skill.target.nearest(end)
    return (centre[0] - half, centre[0] + half), (centre[1] - half, centre[1] + half)


def plot_trajectories(episodes, participants, panels=TRAJECTORY_PANELS, duration: float | None = None,
                      trajectories: dict | None = None, true_skill: bool = True, zoom: bool = True,
                      skills=None) -> Figure:
    """The skills participants taught, reproduced from the fixed start beside the target (Fig. 5).

    Args:
        episodes: episode rows with ``skill`` and ``theta_hat``.
        participants: participant codes, one row of panels each.
        panels: phase ids per column (default: P3; P1 and P4; P2 and P5).
        duration: seconds per rollout.
        trajectories: precomputed ``{(participant, phase, episode): Trajectory}`` (e.g. an
            in-silico study's reproductions); missing ones are rolled out.
        true_skill: draw the true skill's own rollout beside the learnt ones (gid
            "true/<skill>"), as the paper's Fig. 5 does.
        zoom: add to each panel a zoomed inset around the goal (gid "zoom"), where learnt and
            true rollouts part, as the paper's zoomed panel does.
        skills: where the episodes' skill keys are looked up (default the paper's ``SKILLS``).

    Returns:
        The figure. Each trajectory is a line with ``gid`` "<participant>/<phase>E<episode>"
        through the end-effector positions; earlier episodes of a phase are lighter.
    """
    true_skill, zoom = as_bool("true_skill", true_skill), as_bool("zoom", zoom)
    frame = episodes_frame(episodes)
    participants = [str(p) for p in participants]
    if not participants:
        raise ValueError("participants: expected at least one participant code, got none")
    unknown = sorted(set(participants) - set(frame["participant"]))
    if unknown:
        raise ValueError(f"participants: expected codes with episodes, got {unknown} without any")
    needed = [phase for panel in panels for phase in panel]
    rolled = dict(trajectories or {})
    missing = [p for p in participants if any((p, row.phase, int(row.episode)) not in rolled for row in
                                              frame[(frame.participant == p) & frame.phase.isin(needed)].itertuples())]
    if missing:
        fresh = learnt_trajectories(frame, missing, needed, duration, skills=skills)
        rolled.update({k: v for k, v in fresh.items() if k not in rolled})
    groups = frame.groupby("participant")["group"].first()
    figure = Figure(figsize=(3.6 * len(panels), 3.4 * len(participants)), layout="constrained")
    axes = figure.subplots(len(participants), len(panels), squeeze=False)
    palette = mpl.colormaps["viridis"]
    for r, participant in enumerate(participants):
        for c, panel in enumerate(panels):
            ax = axes[r, c]
            rows = frame[(frame.participant == participant) & frame.phase.isin(panel)]
            if rows.empty:
                ax.set_axis_off()
                continue
            skill = (SKILLS if skills is None else skills)[rows["skill"].iloc[0]]
            # Lower right: the start and the goal of the paper's skills lie in the upper half.
            inset = ax.inset_axes([0.62, 0.03, 0.36, 0.36]) if zoom else None
            drawn = []
            for target_ax in [ax] + ([inset] if inset is not None else []):
                _draw_target(target_ax, skill)
            if true_skill:
                truth = skill.reproduce(skill.theta, duration=duration, record_every=20)
                drawn.append(truth)
                for target_ax in [ax] + ([inset] if inset is not None else []):
                    target_ax.plot(truth.positions[:, 0], truth.positions[:, 1], color=OPTIMAL_STYLE["color"],
                                   lw=1.6, linestyle="--", gid=f"true/{skill.key}", label="true skill")
            for k, row in enumerate(rows.itertuples()):
                trajectory = rolled[(participant, row.phase, int(row.episode))]
                drawn.append(trajectory)
                shade = palette(0.15 + 0.7 * k / max(len(rows) - 1, 1))
                several = (frame[(frame.participant == participant) & (frame.phase == row.phase)]["episode"].nunique()
                           > 1)
                label = f"{row.phase}E{row.episode}" if several else row.phase
                for target_ax in [ax] + ([inset] if inset is not None else []):
                    target_ax.plot(trajectory.positions[:, 0], trajectory.positions[:, 1], color=shade, lw=1.4,
                                   gid=f"{participant}/{row.phase}E{row.episode}",
                                   label=label + (" (diverged)" if trajectory.diverged else ""))
            if inset is not None:
                xlim, ylim = _zoom_box(skill, drawn)
                inset.set_xlim(*xlim)
                inset.set_ylim(*ylim)
                inset.set_aspect("equal")
                inset.set_gid("zoom")
                inset.tick_params(labelsize=5)
                ax.indicate_inset_zoom(inset, edgecolor="0.4")
            start = skill.end_effector(skill.start)[0]
            ax.plot([start[0]], [start[1]], marker="o", color="black", linestyle="none", gid="start", label="start")
            box = skill.workspace
            ax.set_xlim(*box.xlim)
            ax.set_ylim(*box.ylim)
            ax.set_aspect("equal")
            ax.set_title(f"{participant} ({groups[participant]}): {' & '.join(panel)}", fontsize=9)
            ax.legend(fontsize=6, frameon=False, loc="upper left", ncol=2)
            ax.set_xlabel(f"r1 ({skill.units})")
            ax.set_ylabel(f"r2 ({skill.units})")
    return figure


# -- the take-home report ----------------------------------------------------------------------

def teaching_report(episodes, demonstrations, participant, changes=PAPER_CHANGES) -> Figure:
    """One page for a participant or student: how their teaching went, in plain words.

    Panels: their teaching error per episode beside their group's mean; how their arrows
    compared with the optimal ones per episode (mean length ratio |u| / |u_bar| and mean
    direction error); what the robot learnt from them at the start and at the end of the
    trained skill, beside the target; and a few sentences on their changes.

    Args:
        episodes: episode rows.
        demonstrations: demonstration rows (``action_1/2``, ``optimal_1/2``), or None to leave
            the arrow panel out.
        participant: the participant's code.
        changes: the comparisons described in the text.

    Returns:
        An A4-portrait figure (save it with ``save_figure`` as PDF or PNG). The error line has
        ``gid`` "participant-error", the group mean "group-error", the length ratios
        "length-ratio" and the direction errors "direction-error".
    """
    frame = episodes_frame(episodes)
    participant = str(participant)
    mine = frame[frame["participant"] == participant]
    if mine.empty:
        raise ValueError(f"participant: expected one of {sorted(frame['participant'].unique())[:10]}..., "
                         f"got {participant!r}")
    group = mine["group"].iloc[0]
    labels = [f"{r.phase}E{r.episode}" for r in mine.itertuples()]
    x = np.arange(len(labels))
    figure = Figure(figsize=(8.27, 11.69), layout="constrained")
    grid = figure.add_gridspec(4, 2, height_ratios=[0.5, 1.2, 1.1, 1.0])
    header = figure.add_subplot(grid[0, :])
    header.set_axis_off()
    study = str(mine["study"].iloc[0]) if "study" in mine.columns else ""
    header.text(0, 0.85, "Your robot-teaching report", fontsize=18, weight="bold", va="top")
    header.text(0, 0.35, f"participant {participant}  ·  study {study}  ·  {len(mine)} episodes", fontsize=10,
                va="top", color="#444444")

    ax = figure.add_subplot(grid[1, :])
    same = frame[frame["group"] == group]
    measure = error_measure(frame)
    group_mean = same.groupby(["phase", "episode"], sort=False)[measure].mean()
    ax.plot(x, [group_mean[(r.phase, r.episode)] for r in mine.itertuples()], color="#999999", lw=1.5, ls="--",
            marker=".", gid="group-error", label=f"average of the {group} group (n = {same.participant.nunique()})")
    style = _style(group)
    ax.plot(x, mine[measure].to_numpy(), color=style["color"], marker="o", lw=2, gid="participant-error",
            label="you")
    if "guidance" in mine.columns:
        for i, shown in enumerate(mine["guidance"].astype(int)):
            if shown:
                ax.axvspan(i - 0.5, i + 0.5, color="#CCCCCC", alpha=0.35, lw=0, zorder=0)
    ax.set_xticks(x)
    ax.set_xticklabels(labels, rotation=45, ha="right", fontsize=8)
    ax.set_ylabel(f"{ERROR_LABELS[measure].split(' ||')[0]} (lower is better)")
    ax.set_ylim(bottom=0)
    ax.set_title("How close the robot's learnt skill came to the true one" +
                 (" (grey: with guidance)" if mine.get("guidance", pd.Series([0])).astype(int).any() else ""),
                 fontsize=10)
    ax.legend(frameon=False, fontsize=8)

    arrows = figure.add_subplot(grid[2, 0])
    if demonstrations is not None:
        demos = pd.DataFrame(list(demonstrations)) if not isinstance(demonstrations, pd.DataFrame) else demonstrations
        demos = demos[demos["participant"].astype(str) == participant]
        ratio, angle = _arrow_agreement(demos, mine)
        arrows.plot(x, ratio, color=style["color"], marker="o", gid="length-ratio", label="length: yours / optimal")
        arrows.axhline(1, color=OPTIMAL_STYLE["color"], lw=1, ls=":")
        arrows.set_ylabel("arrow length ratio (1 = right)")
        twin = arrows.twinx()
        twin.plot(x, angle, color="#CC79A7", marker="^", ls="--", gid="direction-error", label="direction error")
        twin.set_ylabel("direction error (degrees)")
        twin.set_ylim(bottom=0)
        arrows.set_xticks(x)
        arrows.set_xticklabels(labels, rotation=90, fontsize=7)
        arrows.set_title("Your arrows against the optimal ones", fontsize=10)
        handles = arrows.get_legend_handles_labels()[0] + twin.get_legend_handles_labels()[0]
        arrows.legend(handles, [h.get_label() for h in handles], fontsize=7, frameon=False)
    else:
        arrows.set_axis_off()

    paths = figure.add_subplot(grid[2, 1])
    trained = mine["skill"].iloc[0] if "skill" in mine.columns else None
    # Only ridge logs a Theta_hat (another learner's is empty: analysis.refitted_trajectories).
    if trained is not None and "theta_hat" in mine.columns and mine["theta_hat"].map(_has_theta).all():
        skill_rows = mine[mine["skill"] == trained]
        first, last = skill_rows.iloc[0], skill_rows.iloc[-1]
        skill = SKILLS[trained]
        batch = skill.reproduce(np.array([_theta(first["theta_hat"]), _theta(last["theta_hat"]), skill.theta]),
                                record_every=20)
        _draw_target(paths, skill)
        for trajectory, label, colour, gid in ((batch[2], "true skill", OPTIMAL_STYLE["color"], "true"),
                                               (batch[0], f"{first['phase']}E{first['episode']} (start)", "#999999",
                                                "first"),
                                               (batch[1], f"{last['phase']}E{last['episode']} (end)", style["color"],
                                                "last")):
            paths.plot(trajectory.positions[:, 0], trajectory.positions[:, 1], color=colour, lw=1.6, gid=gid,
                       label=label + (" - ran away" if trajectory.diverged else ""))
        box = skill.workspace
        paths.set_xlim(*box.xlim)
        paths.set_ylim(*box.ylim)
        paths.set_aspect("equal")
        paths.set_title(f"What the robot learnt: {skill.title}", fontsize=10)
        paths.legend(fontsize=7, frameon=False, loc="lower left")
    else:
        paths.set_axis_off()

    text = figure.add_subplot(grid[3, :])
    text.set_axis_off()
    # Wrapped here rather than by matplotlib: wrap=True ignores the page margin under a
    # constrained layout, and a take-home page must not lose the ends of its sentences.
    sentences = _report_sentences(frame, participant, changes)
    lines = [textwrap.fill(line, 100, subsequent_indent="  ") for line in sentences]
    text.text(0, 1, "\n".join(lines), va="top", fontsize=9.5)
    return figure


def _arrow_agreement(demos: pd.DataFrame, mine: pd.DataFrame):
    """Per episode of ``mine``: mean |u| / |u_bar| and mean angle between u and u_bar (degrees)."""
    ratio, angle = [], []
    for row in mine.itertuples():
        part = demos[(demos["phase"] == row.phase) & (demos["episode"].astype(int) == int(row.episode))]
        u = part[["action_1", "action_2"]].to_numpy(float)
        o = part[["optimal_1", "optimal_2"]].to_numpy(float)
        size = np.linalg.norm(o, axis=1)
        ok = size > 0
        if not ok.any():
            ratio.append(np.nan)
            angle.append(np.nan)
            continue
        ratio.append(float(np.mean(np.linalg.norm(u[ok], axis=1) / size[ok])))
        cross = o[ok, 0] * u[ok, 1] - o[ok, 1] * u[ok, 0]
        angle.append(float(np.mean(np.abs(np.degrees(np.arctan2(cross, np.sum(o[ok] * u[ok], axis=1)))))))
    return np.array(ratio), np.array(angle)


def _report_sentences(frame: pd.DataFrame, participant: str, changes) -> list[str]:
    table = participant_changes(frame, changes)
    mine = table[table["participant"] == participant]
    lines = []
    for change in changes:
        row = mine[mine["change"] == change.name]
        if row.empty:
            continue
        row = row.iloc[0]
        others = table[(table["change"] == change.name) & (table["group"] == row["group"])]["delta"]
        percent = 100 * row["delta"] / row["before"] if row["before"] else float("nan")
        direction = "fell" if row["delta"] < 0 else "rose"
        lines.append(f"• {change.label} ({change.meaning}): your error {direction} from {row['before']:.2f} to "
                     f"{row['after']:.2f} ({percent:+.0f}%); your group's average change was {others.mean():+.2f}.")
    lines.append("")
    lines.append("Teaching error measures how far the skill the robot learnt from your arrows is from the "
                 "true skill (0 = perfect).")
    lines.append("Tip: the best arrows grow with the distance to the target and also brake the arm's motion - "
                 "the length matters as much as the direction.")
    return lines
