"""Each class member's Jupyter server on the hub (found through JUPYTER_CONFIG_PATH, set by the spawner).

- Kernels talk to the server over IPC sockets in the member's own runtime folder
  (``~/.local/share/jupyter/runtime``, private to them), not TCP ports: jupyter_client picks a
  kernel's five ports by binding port 0 and closing it again, and with thirty servers starting
  kernels at once another kernel binds the same port in between (``ZMQError: Address already in
  use``, then a lost kernel). Files cannot collide: each kernel's names come from its own id.
- umask 027: nothing a member writes is readable by classmates.
- Students get what a lesson uses: JupyterLab, Voila's pages and nbgrader's assignment list and
  validation (these two loaded at first use: ``student-site/mt_hub_voila.py`` and
  ``student-site/mt_hub_nbgrader.py``, on the servers' PYTHONPATH); not the language server,
  terminals (their shell is nologin anyway), the classic Notebook interface (``notebook``: the
  hub opens JupyterLab) or nbgrader's formgrader, which only instructors
  (``MT_HUB_ROLE=instructor``) load. Each extension left out is start-up time and memory a
  student does not pay (benchmarks/bench_hub.py measures a student's server).
"""

import os
import sys

c = get_config()  # noqa: F821 - provided by Jupyter's config loader

c.KernelManager.transport = "ipc"
# Kernels' activity (the idle clock the culler and the hub read) kept from the messages' headers:
# a tenth of a server's CPU in a lecture's first minute was jupyter_server's own watch
# (mt_widgets/kernels/activity.py says why reading the headers is as safe).
c.ServerApp.kernel_manager_class = "mt_widgets.kernels.activity.HeaderActivityKernelManager"
# Nobody installs extensions from a class member's server (the installation is root's): the
# read-only extension manager lists them without PyPI's HTTP client, whose SSL context and
# imports were another seventh of a student's server start.
c.LabApp.extension_manager = "readonly"
# Files a member's server and kernels create are readable by their own group at most (on the
# class folder, that group is the instructors'): deploy/jupyterhub/class_hub.py.
os.umask(0o027)
if os.environ.get("MT_HUB_ROLE") != "instructor":
    c.ServerApp.terminals_enabled = False
    c.ServerApp.jpserver_extensions = {
        "jupyter_lsp": False,
        "jupyter_server_terminals": False,
        "nbgrader.server_extensions.formgrader": False,
        # nbgrader's student side, imported at its first use rather than at every start (35 MiB
        # a server): the same handlers, routed by student-site/mt_hub_nbgrader.py.
        "nbgrader.server_extensions.assignment_list": False,
        "nbgrader.server_extensions.validate_assignment": False,
        "nbgrader.server_extensions.course_list": False,
        "mt_hub_nbgrader": True,
        # Voila's pages, from student-site/mt_hub_voila.py at the first page a student opens.
        "voila.server_extension": False,
        "mt_hub_voila": True,
        "notebook": False,
        # The classic Notebook's config shim: nothing here configures NotebookApp, and its check of
        # every config member was a twentieth of a student's server start (py-spy, bench_hub.py).
        "notebook_shim": False,
    }
    # Students' kernels run without JupyterLab's debugger: the hub puts student-share/ first on
    # their JUPYTER_PATH, whose kernels/python3 spec starts student-site/mt_hub_kernel.py.

# A server forked by the class's server template (mt_widgets/kernels/server_template.py) was given
# a kernel template of its own: its kernels are forked from it, with everything imported.
_provisioner = sys.modules.get("mt_widgets.kernels.provisioner")
if _provisioner is not None and _provisioner.KernelTemplate.adopted():
    c.MappingKernelManager.kernel_manager_class = "mt_widgets.kernels.provisioner.ForkingKernelManager"
