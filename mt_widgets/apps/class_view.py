"""The instructor's live view of a class: who is where, each student's teaching error over their
episodes, the distribution per exercise, and who is stuck, refreshed on a timer.

It reads the class folder that students' lessons and exercises write to
(``mt_widgets.classroom``), and draws what ``summarise`` says; it never fits or scores anything
itself. A folder that cannot be read shows its message and keeps the last good picture; a
student's damaged file is named under the table while everyone else is shown.

In a notebook (``notebooks/class_view.ipynb`` under Voila)::

    from mt_widgets.apps.class_view import ClassView
    ClassView("/srv/class/lfd-2025")      # default: $MT_WIDGETS_CLASS_FOLDER

Names: the folder holds pseudonyms only. An instructor who gives the view a names file
(``names=`` or ``$MT_WIDGETS_CLASS_NAMES``, written from the roster by
``python -m mt_widgets.classroom.names``, readable by its owner only) sees each student's name
beside the pseudonym; without one, only pseudonyms are shown.
"""

from __future__ import annotations

import asyncio
import datetime as _dt
import html
import io
import math

import numpy as np
from ipywidgets import HTML, Button, FloatText, HBox, Image, Layout, VBox
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from mt_widgets.classroom import (
    STUCK_AFTER_S,
    ClassFolderError,
    ClassSummary,
    class_folder_from_env,
    read_class,
    summarise,
)
from mt_widgets.classroom.names import NamesFileError, names_from_env, read_names
from mt_widgets.widgets.theme import OKABE_ITO

_PALETTE = [OKABE_ITO[k] for k in ("blue", "orange", "bluish_green", "reddish_purple", "vermillion", "sky_blue",
                                   "yellow")]
_LINESTYLES = ["-", "--", ":", "-."]


def _ago(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


def _png(figure: Figure) -> bytes:
    buffer = io.BytesIO()
    FigureCanvasAgg(figure).print_png(buffer)
    return buffer.getvalue()


def errors_figure(summary: ClassSummary) -> Figure:
    """Each student's teaching error over their episodes, and the class mean (the paper's Fig. 3a, for a class)."""
    figure = Figure(figsize=(6.4, 4.4), dpi=100, layout="constrained")
    axes = figure.add_subplot()
    longest = max((len(s.theta_errors) for s in summary.students), default=0)
    for number, student in enumerate(s for s in summary.students if s.theta_errors):
        errors = student.theta_errors
        axes.plot(np.arange(1, len(errors) + 1), errors, marker="o", ms=3, lw=1.2, alpha=0.8,
                  color=_PALETTE[number % len(_PALETTE)], ls=_LINESTYLES[(number // len(_PALETTE)) % 4],
                  label=student.student)
    if longest:
        means = [np.mean([s.theta_errors[i] for s in summary.students if len(s.theta_errors) > i])
                 for i in range(longest)]
        axes.plot(np.arange(1, longest + 1), means, color="black", lw=2.6, label="class mean")
        axes.set_xticks(np.arange(1, longest + 1))
        if sum(1 for s in summary.students if s.theta_errors) <= 14:
            # Below the axes: inside, the legend of a dozen students hides their first episodes.
            axes.legend(fontsize=6, ncols=4, loc="upper center", bbox_to_anchor=(0.5, -0.18), frameon=False)
    else:
        axes.text(0.5, 0.5, "no finished episodes yet", ha="center", va="center", transform=axes.transAxes)
    axes.set_xlabel("episode (each student's own, in order)")
    axes.set_ylabel("teaching error ||Theta_hat - Theta||")
    axes.set_title("Teaching error over episodes", fontsize=10)
    axes.grid(alpha=0.3)
    return figure


def exercises_figure(summary: ClassSummary) -> Figure:
    """Per exercise: each student's share of checks passed (a box and the students as dots)."""
    figure = Figure(figsize=(6.4, 3.2), dpi=100, layout="constrained")
    axes = figure.add_subplot()
    exercises = summary.exercises
    if not exercises:
        axes.text(0.5, 0.5, "no exercise checks run yet", ha="center", va="center", transform=axes.transAxes)
    for position, exercise in enumerate(exercises, start=1):
        shares = summary.exercise_shares(exercise)
        if shares:
            axes.boxplot([shares], positions=[position], widths=0.5, showfliers=False,
                         medianprops={"color": OKABE_ITO["vermillion"]})
            jitter = np.linspace(-0.15, 0.15, len(shares)) if len(shares) > 1 else [0.0]
            axes.plot(position + np.asarray(jitter), shares, "o", ms=4, color=OKABE_ITO["blue"], alpha=0.7)
            axes.text(position, 1.06, f"n={len(shares)}", ha="center", fontsize=7)
    axes.set_xticks(range(1, len(exercises) + 1), [e.split("_", 1)[0] for e in exercises])
    axes.set_ylim(-0.05, 1.12)
    axes.set_ylabel("share of checks passed")
    axes.set_title("Exercises: checks passed per student", fontsize=10)
    axes.grid(alpha=0.3, axis="y")
    return figure


def summary_table(summary: ClassSummary, names: dict[str, str] | None = None) -> str:
    """The class as an HTML table, stuck students first and marked; with ``names``, each name beside its pseudonym."""
    names = names or {}
    rows = []
    order = sorted(summary.students, key=lambda s: (not s.stuck, s.student))

    def name_cell(student: str) -> str:
        if not names:
            return ""
        name = names.get(student)
        return f"<td class='student-name'>{html.escape(name)}</td>" if name else "<td><i>not on the roster</i></td>"

    for s in order:
        latest = f"{s.theta_errors[-1]:.3f}" if s.theta_errors else "–"
        best = f"{min(s.theta_errors):.3f}" if s.theta_errors else "–"
        status = "<b style='color:#b00020'>stuck</b>" if s.stuck else "working"
        if s.stuck and s.last_failure:
            status += f"<br><small>{html.escape(s.last_failure[:160])}</small>"
        style = " style='background:#fde8e8'" if s.stuck else ""
        rows.append(f"<tr{style} class='student-row' data-student='{html.escape(s.student)}'>"
                    f"<td><code>{html.escape(s.student)}</code></td>{name_cell(s.student)}"
                    f"<td>{html.escape(s.place or '–')}</td>"
                    f"<td>{_ago(s.idle_s)}</td><td>{len(s.theta_errors)}</td><td>{latest}</td><td>{best}</td>"
                    f"<td>{status}</td></tr>")
    head = ("<tr><th>student</th>" + ("<th>name</th>" if names else "")
            + "<th>where</th><th>no progress for</th><th>episodes</th><th>latest error</th>"
            "<th>best error</th><th>status</th></tr>")
    places = " · ".join(f"{html.escape(place)}: <b>{len(members)}</b>" for place, members in summary.at_place().items()
                        if members)
    return (f"<div style='margin:4px 0'>Where the class is: {places or 'nobody yet'}</div>"
            f"<table class='class-table' style='border-collapse:collapse;font-size:0.92em' border='1' "
            f"cellpadding='4'>{head}{''.join(rows)}</table>")


class ClassView(VBox):
    """The instructor's page for one class folder.

    Args:
        class_folder: the class folder (default ``$MT_WIDGETS_CLASS_FOLDER``).
        refresh_s: seconds between refreshes while the page is open (0: only the button).
        stuck_after_s: seconds without progress after which a student is marked stuck.
        names: the names file (pseudonym -> name, ``mt_widgets.classroom.names``); default
            ``$MT_WIDGETS_CLASS_NAMES``; None with neither: pseudonyms only.
    """

    def __init__(self, class_folder=None, refresh_s: float = 5.0, stuck_after_s: float = STUCK_AFTER_S,
                 names=None):
        if isinstance(refresh_s, bool) or not isinstance(refresh_s, (int, float)) or refresh_s < 0 \
                or not math.isfinite(refresh_s):
            raise ValueError(f"refresh_s: expected a number of seconds >= 0, got {refresh_s!r}")
        if isinstance(stuck_after_s, bool) or not isinstance(stuck_after_s, (int, float)) or not stuck_after_s > 0:
            raise ValueError(f"stuck_after_s: expected a positive number of seconds, got {stuck_after_s!r}")
        self.folder = class_folder if class_folder is not None else class_folder_from_env()
        self.names_problem = ""
        try:
            self.names = read_names(names) if names is not None else names_from_env()
        except (NamesFileError, OSError) as error:
            # A names file others can read (or none where one was named) shows pseudonyms and says why.
            self.names, self.names_problem = {}, f"names not shown: {error}"
        self.refresh_s = float(refresh_s)
        self.summary: ClassSummary | None = None
        self.refreshes = 0
        self.header = HTML()
        self.status = HTML()
        self.table = HTML()
        self.errors_image = Image(format="png", layout=Layout(max_width="640px"))
        self.exercises_image = Image(format="png", layout=Layout(max_width="640px"))
        self.problems = HTML()
        self.stuck_minutes = FloatText(value=stuck_after_s / 60, description="stuck after (min)",
                                       layout=Layout(width="220px"), style={"description_width": "initial"})
        self.refresh_button = Button(description="Refresh now", icon="refresh")
        self.refresh_button.on_click(lambda _: self.refresh())
        self.stuck_minutes.observe(lambda _: self.refresh(), names="value")
        self._timer = None
        super().__init__([self.header, HBox([self.refresh_button, self.stuck_minutes]), self.status, self.table,
                          HBox([self.errors_image, self.exercises_image], layout=Layout(flex_flow="row wrap")),
                          self.problems])
        self.refresh()
        if self.refresh_s > 0:
            self._schedule()

    def refresh(self, now: _dt.datetime | None = None) -> ClassSummary | None:
        """Reads the class folder again and redraws; returns the summary (None if it cannot be read)."""
        self.header.value = (f"<h3 style='margin:4px 0'>Class view</h3><small>class folder: "
                             f"<code>{html.escape(str(self.folder))}</code></small>")
        if self.folder is None:
            self._say("No class folder is set: set MT_WIDGETS_CLASS_FOLDER (or pass class_folder) to the folder "
                      "your students' lessons write to.", error=True)
            return None
        stuck_after = self.stuck_minutes.value * 60 if self.stuck_minutes.value > 0 else STUCK_AFTER_S
        try:
            summary = summarise(read_class(self.folder), now=now, stuck_after_s=stuck_after)
        except ClassFolderError as error:
            # Keep the last good picture: a folder that is briefly unreachable loses nothing on screen.
            self._say(f"{error}", error=True)
            return None
        self.summary = summary
        self.refreshes += 1
        self.table.value = summary_table(summary, self.names)
        self.errors_image.value = _png(errors_figure(summary))
        self.exercises_image.value = _png(exercises_figure(summary))
        problems = [*summary.problems, *([self.names_problem] if self.names_problem else [])]
        self.problems.value = "".join(f"<div style='color:#8a5300'>{html.escape(p)}</div>" for p in problems)
        self._say(f"<span class='class-status'>{len(summary.students)} students, {len(summary.stuck)} stuck; "
                  f"updated {summary.now.strftime('%H:%M:%S')} UTC (refresh #{self.refreshes})</span>", raw=True)
        return summary

    def _say(self, text: str, error: bool = False, raw: bool = False) -> None:
        body = text if raw else html.escape(text)
        colour = "#b00020" if error else "#1b5e20"
        self.status.value = f"<div class='class-message' style='color:{colour}'>{body}</div>"

    # -- the timer -------------------------------------------------------------------------------------
    def _schedule(self) -> None:
        try:
            loop = asyncio.get_running_loop()
        except RuntimeError:
            loop = asyncio.get_event_loop_policy().get_event_loop()
        if not loop.is_running():
            return  # a plain script: no timer, refresh() by hand
        self._timer = loop.call_later(self.refresh_s, self._tick)

    def _tick(self) -> None:
        # Scheduled first: an error in one refresh (reported by the kernel's loop) never stops the page.
        self._schedule()
        self.refresh()

    def close(self) -> None:
        """Stops the timer and closes the widgets."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        super().close()
