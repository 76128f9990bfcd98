"""A student's Python kernel on the class hub: ipykernel without its debugger.

The hub (``jupyterhub_config.py``) puts ``student-share/`` first on students' JUPYTER_PATH, so
their "python3" kernel spec is ``student-share/kernels/python3/`` (``{prefix}/bin/python -m
mt_hub_kernel``: the Python their server runs), which starts this module. ipykernel imports
debugpy (and through it coverage) in every kernel when debugpy is installed: about 7.6 MiB of
every kernel's own memory, measured on this project's 2-core machine, for JupyterLab's visual
debugger, which no lesson uses. An entry of None in ``sys.modules`` makes that import fail as a
missing package does, so ipykernel runs as it does where debugpy is absent; the spec's
``"debugger": false`` tells JupyterLab not to offer it. Instructors' kernels keep the debugger
(their servers keep the usual spec).

Students' kernels are forked from their server's kernel template (mt_widgets/kernels/), which
imports this module before ipykernel: the None entry is set at import, so it holds in the
template and in every kernel forked from it.
"""

import sys

sys.modules["debugpy"] = None

if __name__ == "__main__":
    from ipykernel import kernelapp

    kernelapp.launch_new_instance()
