"""The lab shape (``pip install "mt-widgets[lab]"``): JupyterLab opens, with the widgets' front-ends, and
Voila is there. A real open: the server starts on 127.0.0.1, GET /lab serves the lab's page, then it stops."""

import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

import voila  # noqa: F401  (the kiosk and the study pages run under Voila)

import mt_widgets.widgets  # noqa: F401
from mt_widgets.analysis import analyse_study  # noqa: F401
from mt_widgets.hardware import SwiftPro  # noqa: F401

bin_dir = Path(sys.executable).parent
extensions = subprocess.run([bin_dir / "jupyter", "labextension", "list"], capture_output=True, text=True,
                            check=True, timeout=120)
listed = extensions.stdout + extensions.stderr
for front_end in ("@jupyter-widgets/jupyterlab-manager", "ipycanvas"):
    assert front_end in listed, f"{front_end} is not among the lab's extensions:\n{listed}"
voila_version = subprocess.run([bin_dir / "voila", "--version"], capture_output=True, text=True, check=True,
                               timeout=120).stdout.strip()

with socket.socket() as probe:
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
token = "install-shape-smoke"
root = tempfile.mkdtemp()
# As root (a container, a CI runner) the server refuses to start without --allow-root, as for any user.
as_root = ["--allow-root"] if os.geteuid() == 0 else []
server = subprocess.Popen([bin_dir / "jupyter", "lab", "--no-browser", "--ip=127.0.0.1", f"--port={port}",
                           f"--IdentityProvider.token={token}", f"--ServerApp.root_dir={root}", *as_root],
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
try:
    deadline = time.monotonic() + 120
    page = None
    while page is None:
        if server.poll() is not None:
            raise SystemExit(f"jupyter lab exited with {server.returncode}: {server.stderr.read().decode()[-2000:]}")
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/lab?token={token}", timeout=10) as response:
                assert response.status == 200, response.status
                page = response.read().decode()
        except (ConnectionError, urllib.error.URLError):
            if time.monotonic() > deadline:
                raise
            time.sleep(0.5)  # the server is still starting: wait for it to listen
    assert "<title>JupyterLab</title>" in page, page[:500]
finally:
    if server.poll() is None:
        os.killpg(server.pid, signal.SIGTERM)
        server.wait(timeout=60)
print(f"lab: GET /lab served {len(page)} bytes; voila {voila_version}")
