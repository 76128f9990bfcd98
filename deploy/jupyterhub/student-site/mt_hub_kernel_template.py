"""Starts a class member's kernel template with their server (a Jupyter server extension).

The template (mt_widgets/kernels/template.py) imports numpy, numba, ipycanvas and the widgets
once; the member's kernels are then forked from it in milliseconds
(mt_widgets/kernels/provisioner.py, named by student-config/jupyter_server_config.py). Started
here, at the server's start, it has done its imports by the time the member opens a notebook.
It runs as the server runs, as the member: the hub's spawner put the server into the member's
cgroups and dropped to their uid, gid and groups before the server ran anything, and the
template and every kernel it forks inherit exactly that; nothing in it holds a privilege.
"""

from mt_widgets.kernels.provisioner import start_template


def _jupyter_server_extension_points():
    return [{"module": "mt_hub_kernel_template"}]


def _load_jupyter_server_extension(server_app):
    start_template()
    server_app.log.info("kernel template started: kernels are forked from it (mt_widgets/kernels/)")
