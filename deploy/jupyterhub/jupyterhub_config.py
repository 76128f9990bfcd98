"""A JupyterHub for a class on one machine: mt-widgets installed once, read-only, for everyone.

Run it from a folder the hub may write its state to::

    MT_HUB_STATE=/srv/mt-hub MT_WIDGETS_CLASS_FOLDER=/srv/mt-hub/class \\
        jupyterhub -f deploy/jupyterhub/jupyterhub_config.py

Settings come from environment variables so the same file serves a course and the test suite
(tests/course/test_hub.py):

- ``MT_HUB_PORT`` (8000): the port, on 127.0.0.1 only; put a TLS proxy in front for a real class.
  ``MT_HUB_PROXY_API_PORT`` (8001) and ``MT_HUB_INTERNAL_PORT`` (8081): the proxy's and the hub's own.
- ``MT_HUB_STATE`` (./mt-hub-state): the hub's database, cookie secret and proxy token.
- ``MT_HUB_HOMES`` (<state>/homes): one home folder per student.
- ``MT_HUB_PASSWORD``: the dummy authenticator's shared password (unset: any password). The
  dummy authenticator is for trying things out and tests; a course uses its institution's
  (OAuthenticator, LTI) in its place.
- ``MT_HUB_API_TOKEN``: a token for the ``class-admin`` service (creating students, starting
  servers), used by tests and by ``benchmarks/bench_hub.py``.
- ``MT_WIDGETS_CLASS_FOLDER``: the class folder students' lessons write progress to (the
  instructor's ``notebooks/class_view.ipynb`` reads it); unset: no progress is recorded.
- ``MT_WIDGETS_EXCHANGE``: nbgrader's exchange folder (release, submit, collect, feedback).
- ``MT_HUB_NUMBA_TEMPLATE``: a warm numba cache (``deploy/jupyterhub/warm_numba_cache.py``)
  copied into a student's empty cache at spawn, so nobody's first episode waits for compiling.

Every student's server runs the same Python (this hub's) with the package installed once;
nothing is written into the installation: numba's cache goes to ``~/.cache/numba`` of each
student (``NUMBA_CACHE_DIR``) and Python writes no bytecode there (``PYTHONDONTWRITEBYTECODE``).
"""

import os
import random
import shutil
import socket
import sys
from pathlib import Path

c = get_config()  # noqa: F821 - provided by JupyterHub's config loader

HERE = Path(__file__).resolve().parent
STATE = Path(os.environ.get("MT_HUB_STATE", "mt-hub-state")).resolve()
HOMES = Path(os.environ.get("MT_HUB_HOMES", STATE / "homes")).resolve()
STATE.mkdir(parents=True, exist_ok=True)

# -- the hub: loopback only ------------------------------------------------------------------------
c.JupyterHub.ip = "127.0.0.1"
c.JupyterHub.port = int(os.environ.get("MT_HUB_PORT", "8000"))
c.JupyterHub.hub_ip = "127.0.0.1"
c.JupyterHub.hub_port = int(os.environ.get("MT_HUB_INTERNAL_PORT", "8081"))
c.JupyterHub.db_url = f"sqlite:///{STATE / 'jupyterhub.sqlite'}"
c.JupyterHub.cookie_secret_file = str(STATE / "jupyterhub_cookie_secret")
c.ConfigurableHTTPProxy.pid_file = str(STATE / "proxy.pid")
c.ConfigurableHTTPProxy.api_url = f"http://127.0.0.1:{int(os.environ.get('MT_HUB_PROXY_API_PORT', '8001'))}"
# A whole class logs in at the start of a lesson: let them all spawn at once.
c.JupyterHub.concurrent_spawn_limit = int(os.environ.get("MT_HUB_SPAWN_LIMIT", "40"))
c.JupyterHub.active_server_limit = 0

# -- who comes in ----------------------------------------------------------------------------------
c.JupyterHub.authenticator_class = "dummy"
if os.environ.get("MT_HUB_PASSWORD"):
    c.DummyAuthenticator.password = os.environ["MT_HUB_PASSWORD"]
c.Authenticator.allow_all = True
c.Authenticator.admin_users = {"instructor"}
if os.environ.get("MT_HUB_API_TOKEN"):
    c.JupyterHub.services = [{"name": "class-admin", "api_token": os.environ["MT_HUB_API_TOKEN"]}]
    c.JupyterHub.load_roles = [{
        "name": "class-admin",
        "scopes": ["admin:users", "admin:servers", "tokens", "access:servers", "read:users"],
        "services": ["class-admin"],
    }]

# -- each student's server -------------------------------------------------------------------------
# Local processes (no system accounts needed): each server gets its own home folder. As root,
# Jupyter servers refuse to start without --allow-root.
c.JupyterHub.spawner_class = "simple"
c.SimpleLocalProcessSpawner.home_dir_template = str(HOMES / "{username}")
c.Spawner.cmd = [str(Path(sys.executable).parent / "jupyterhub-singleuser")]
c.Spawner.args = ["--allow-root"] if os.geteuid() == 0 else []
c.Spawner.default_url = "/lab/tree/index.ipynb"
c.Spawner.start_timeout = 180
c.Spawner.http_timeout = 180
c.Spawner.mem_limit = os.environ.get("MT_HUB_MEM_LIMIT") or None  # enforced by container spawners only

# Passed on from the hub's environment: the class folder, the exchange, and (tests) the checkout.
_passed_on = ("MT_WIDGETS_CLASS_FOLDER", "MT_WIDGETS_EXCHANGE", "MT_WIDGETS_FAST")
c.Spawner.environment = {
    # numba's compiled rollouts go to each student's home, never into the shared installation.
    "NUMBA_CACHE_DIR": lambda spawner: str(Path(spawner.home_dir) / ".cache" / "numba"),
    "MPLCONFIGDIR": lambda spawner: str(Path(spawner.home_dir) / ".cache" / "matplotlib"),
    "PYTHONDONTWRITEBYTECODE": "1",
    # nbgrader's student side (exchange, course, who submits) comes from this folder.
    "JUPYTER_CONFIG_PATH": str(HERE / "student-config"),
    **{name: os.environ[name] for name in _passed_on if os.environ.get(name)},
}


def _port_outside_ephemeral_range() -> int:
    """A free port below Linux's ephemeral range (32768-60999). JupyterHub's own choice comes from
    that range, where every kernel's ZMQ sockets also bind: when a class starts at once, a kernel
    can take a server's port between the hub choosing it and the server binding it."""
    for _ in range(500):
        port = random.randint(20000, 32000)
        with socket.socket() as probe:
            try:
                probe.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    raise RuntimeError("no free port between 20000 and 32000 for a student's server")


def _prepare_home(spawner) -> None:
    """Before a student's server starts: its port, and a home with a warm numba cache (if the hub has one)."""
    spawner.port = _port_outside_ephemeral_range()
    home = Path(spawner.home_dir)
    cache = home / ".cache" / "numba"
    template = os.environ.get("MT_HUB_NUMBA_TEMPLATE")
    if template and Path(template).is_dir() and not cache.exists():
        shutil.copytree(template, cache)
    cache.mkdir(parents=True, exist_ok=True)


c.Spawner.pre_spawn_hook = _prepare_home
