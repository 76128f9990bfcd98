"""A student's Python kernel on the class hub: ipykernel without its debugger.

The hub (``jupyterhub_config.py``) puts ``student-share/`` first on students' JUPYTER_PATH, so
their "python3" kernel spec is ``student-share/kernels/python3/`` (``{prefix}/bin/python -m
mt_hub_kernel``: the Python their server runs), which starts this module. ipykernel imports
debugpy (and through it coverage) in every kernel when debugpy is installed: about 7.6 MiB of
every kernel's own memory, measured on this project's 2-core machine, for JupyterLab's visual
debugger, which no lesson uses. An entry of None in ``sys.modules`` makes that import fail as a
missing package does, so ipykernel runs as it does where debugpy is absent; the spec's
``"debugger": false`` tells JupyterLab not to offer it. The spec also turns IPython's history
database off (``--HistoryManager.enabled=False``): each kernel opened and created a SQLite file in
the student's home and started a thread to write it, a twentieth of a forked kernel's start
(py-spy, benchmarks/bench_hub.py), for the input history of past sessions, which notebooks do not
use (the session's own ``In`` and ``%history`` stay). Instructors' kernels keep the debugger and
the history (their servers keep the usual spec).

The blocking is done at import, not only when run: the class's server template
(``mt_widgets/kernels/server_template.py``) imports this module before ipykernel, so that the
students' kernels it forks have no debugpy either.
"""

import sys

sys.modules["debugpy"] = None

if __name__ == "__main__":
    from ipykernel import kernelapp

    kernelapp.launch_new_instance()
