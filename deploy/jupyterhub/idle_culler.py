"""jupyterhub-idle-culler, ended with the hub that started it.

JupyterHub starts a managed service in a session of its own and stops it when the hub stops the
documented way. A hub that is killed (SIGKILL, a crash, the OOM killer) stops nothing: its culler
went on running, orphaned, beside the culler of the next hub (found by tests/course/test_hub.py's
restart test). Run as ``python idle_culler.py ARGS...`` (jupyterhub_config.py does), it asks Linux to
send it SIGTERM when its parent, the hub, ends (``PR_SET_PDEATHSIG``), then runs the culler with ARGS.
"""

import ctypes
import os
import runpy
import signal
import sys

#: linux/prctl.h
PR_SET_PDEATHSIG = 1


def main() -> None:
    hub = os.getppid()
    if ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_PDEATHSIG) failed")
    if os.getppid() != hub:  # the hub ended before the request above took effect
        sys.exit("idle culler: the hub that started it has ended")
    sys.argv = ["jupyterhub_idle_culler", *sys.argv[1:]]
    runpy.run_module("jupyterhub_idle_culler", run_name="__main__", alter_sys=True)


if __name__ == "__main__":
    main()
