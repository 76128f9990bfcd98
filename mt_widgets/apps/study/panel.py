"""The experimenter's panel: protocol, log folder, participant ID, group; new, resume, lesson, list.

Only the experimenter sees it. It is built only on the experimenter's page (``StudyApp``, which
the lab page opens after the experimenter's code), and it is closed (its widgets leave the
kernel too, so no page can ask for their state) when a participant starts.
"""

from __future__ import annotations

import html

from ipywidgets import HTML, Button, Combobox, Dropdown, HBox, Layout, Text, VBox

from mt_widgets.study import BUILTIN_PROTOCOLS

#: The group dropdown's value for "randomised": a Dropdown whose value is None shows nothing.
RANDOMISED = "randomised"
RANDOMISED_OPTION = ("randomised (block randomisation)", RANDOMISED)


class ExperimenterPanel(VBox):
    """What the experimenter sets before a participant starts."""

    def __init__(self, protocol: str, log_folder, group_options=(RANDOMISED_OPTION,)):
        self.protocol = Combobox(value=protocol, options=sorted(BUILTIN_PROTOCOLS), description="Protocol",
                                 placeholder="paper-sim, paper-uarm or a .toml/.json file",
                                 layout=Layout(width="min(520px, 100%)"), ensure_option=False)
        self.log_folder = Text(value=str(log_folder), description="Log folder",
                               layout=Layout(width="min(520px, 100%)"))
        self.participant = Text(value="", description="Participant", placeholder="pseudonymous code, e.g. P07",
                                layout=Layout(width="320px"))
        self.group = Dropdown(options=list(group_options), value=RANDOMISED, description="Group",
                              layout=Layout(width="320px"))
        wide = dict(width="auto")
        self.start_button = Button(description="Start new participant", button_style="primary", icon="play",
                                   layout=Layout(**wide))
        self.resume_button = Button(description="Resume participant", icon="repeat", layout=Layout(**wide))
        self.lesson_button = Button(description="Lesson (not logged)", icon="graduation-cap", layout=Layout(**wide))
        self.list_button = Button(description="List participants", icon="list", layout=Layout(**wide))
        self.message = HTML()
        self.listing = HTML()
        super().__init__([
            HTML("<h3 style='margin:4px 0'>Experimenter</h3><small>Only you see this panel: it disappears when "
                 "the participant starts, and a reload of the participant's page brings back their page, not "
                 "this one. For the next participant, open the experimenter page again.</small>"),
            self.protocol, self.log_folder, self.participant, self.group,
            HBox([self.start_button, self.resume_button, self.lesson_button, self.list_button],
                 layout=Layout(flex_flow="row wrap")),
            self.message, self.listing,
        ], layout=Layout(border="2px dashed #888", padding="8px", max_width="820px"))

    def say(self, text: str, error: bool = False) -> None:
        colour = "#b00020" if error else "#1b5e20"
        self.message.value = f"<div style='color:{colour};max-width:760px'>{html.escape(text)}</div>"

    def show_groups(self, groups) -> None:
        self.group.options = [RANDOMISED_OPTION] + [(g, g) for g in groups]
        self.group.value = RANDOMISED

    def list_study(self, study) -> None:
        """Every participant of ``study`` with their group and state, and the counts per group."""
        rows = "".join(f"<tr><td>{html.escape(r['participant'])}</td><td>{r['group']}</td><td>{r['method']}</td>"
                       f"<td>{html.escape(r['state'])}</td><td>{r['events']}</td></tr>"
                       for r in study.status())
        counts = study.group_status()
        columns = list(next(iter(counts.values())))
        summary = "".join(f"<tr><td>{html.escape(group)}</td>" + "".join(f"<td>{row[c]}</td>" for c in columns)
                          + "</tr>" for group, row in counts.items())
        problem = study.storage_problem()
        fault = ("" if problem is None else
                 f"<div role='alert' class='mt-storage-fault' style='color:#b00020;max-width:760px'><b>Storage fault:"
                 f"</b> {html.escape(problem)}. A page whose step could not be saved holds its participant there; "
                 f"free space, then they press Try again (no restart needed).</div>")
        self.listing.value = (f"{fault}<small>{html.escape(str(study.folder))}</small><table><tr><th>ID</th>"
                              f"<th>group</th><th>assigned</th><th>state</th><th>events</th></tr>"
                              f"{rows}</table><table><tr><th>group</th>"
                              + "".join(f"<th>{c}</th>" for c in columns) + f"</tr>{summary}</table>")

    def close_all(self) -> None:
        """Closes the panel and every widget in it: their state leaves the kernel's comms too."""
        for widget in (self.protocol, self.log_folder, self.participant, self.group, self.start_button,
                       self.resume_button, self.lesson_button, self.list_button, self.message, self.listing,
                       *self.children):
            widget.close()
        for box in self.children:
            if isinstance(box, HBox):
                for child in box.children:
                    child.close()
        self.close()
