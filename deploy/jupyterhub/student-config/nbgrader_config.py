"""nbgrader's student side on the class hub (found through JUPYTER_CONFIG_PATH, set by the spawner).

The exchange folder is the hub's ``MT_WIDGETS_EXCHANGE``. Submissions are filed under the hub
user's name: on a hub whose servers all run as one system user (the local test spawner, or
containers running as jovyan), the system name would be the same for every student.
"""

import os

c = get_config()  # noqa: F821 - provided by nbgrader's config loader

c.CourseDirectory.course_id = "mt-widgets"
if os.environ.get("MT_WIDGETS_EXCHANGE"):
    c.Exchange.root = os.environ["MT_WIDGETS_EXCHANGE"]
if os.environ.get("JUPYTERHUB_USER"):
    c.CourseDirectory.student_id = os.environ["JUPYTERHUB_USER"]
