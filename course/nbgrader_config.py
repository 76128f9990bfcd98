"""nbgrader settings for the mt-widgets course (run nbgrader commands from this folder).

The exchange folder (where released assignments and submissions travel on a shared machine
or a JupyterHub) comes from ``MT_WIDGETS_EXCHANGE``, so a test or a hub can point it at its
own folder; nbgrader's default is /srv/nbgrader/exchange.
"""

import os
from pathlib import Path

c = get_config()  # noqa: F821 - provided by nbgrader's config loader

c.CourseDirectory.root = str(Path(__file__).resolve().parent)
c.CourseDirectory.course_id = "mt-widgets"
if os.environ.get("MT_WIDGETS_EXCHANGE"):
    c.Exchange.root = os.environ["MT_WIDGETS_EXCHANGE"]
# nbgrader's placeholder; the exercises' checks recognise it and say "not written yet".
c.ClearSolutions.code_stub = {"python": "# YOUR CODE HERE\nraise NotImplementedError()"}
# The widget exercises roll the arm out for 10 s at 1 kHz; a cold numba cache compiles first.
c.Execute.timeout = 300
# A submission with a test cell deleted gets the instructor's cell back, with a note that says so,
# and is graded in full; nothing else changes for the other cells or the other students.
c.OverwriteCells.add_missing_cells = True
c.OverwriteCells.missing_cell_notification = (
    "NOTE: this test cell (id: {cell_id}) was missing from your submission (deleted?). "
    "nbgrader put the instructor's version back and graded your work with it.\n\n")
