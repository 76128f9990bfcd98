"""A JupyterHub for a real class on one machine: the roster's people, each as their own system user.

Run it as root (it starts every student's server as that student's own user), from a folder the
hub may write its state to::

    MT_HUB_ROSTER=/srv/mt-hub/roster.csv MT_HUB_STATE=/srv/mt-hub \\
    MT_WIDGETS_CLASS_FOLDER=/srv/mt-hub/class MT_WIDGETS_EXCHANGE=/srv/nbgrader/exchange \\
        jupyterhub -f deploy/jupyterhub/jupyterhub_config.py

and set the instructors' passwords first (``deploy/jupyterhub/class_admin.py set-password``).
What it does (deploy/jupyterhub/README.md says why and how to change it):

- **Who comes in** (``roster_authenticator.py``): exactly the roster's logins; a student sets
  their password at their first login, instructors and TAs have theirs set by
  ``class_admin.py``; wrong passwords are slowed and, repeated, locked.
- **Isolation** (``class_hub.py``): each login is a system user with a private home (0700);
  its server and kernels run as that user with umask 027, never root. The class folder lets a
  student append to their own progress file only; the course folder (``MT_HUB_COURSE``) is the
  instructors'; the installation is read-only to students, and the hub refuses to start when
  students could not read it.
- **Limits**: cgroup v1 memory and CPU groups per student (``MT_HUB_MEM_LIMIT``, 1G;
  ``MT_HUB_CPU_LIMIT``, 1.0 core); the hub refuses to start without them unless
  ``MT_HUB_LIMITS=off``. Idle servers are stopped by jupyterhub-idle-culler after
  ``MT_HUB_CULL_IDLE_SECONDS`` (3600); saved work stays in the home.
- **Thirty at once**: kernels talk to their server over IPC sockets in the student's runtime
  folder (``student-config/jupyter_server_config.py``), not TCP ports that thirty servers
  starting kernels at once would race for.

Settings (environment variables, so one file serves a course and the tests, tests/course/test_hub.py):

- ``MT_HUB_ROSTER`` (required): the roster CSV (``mt_widgets/classroom/roster.py``).
- ``MT_HUB_LOGIN`` (roster): ``lti`` takes LTI 1.3 launches from a learning platform as the login
  (``lti_authenticator.py``, with ``MT_HUB_LTI_*``: docs/guide/lms.md); launches add people to the roster.
- ``MT_HUB_STATE`` (./mt-hub-state): the hub's database, cookie secret, proxy token, password hashes.
- ``MT_HUB_HOMES`` (/home): where each login's home is made.
- ``MT_HUB_RUNTIME`` (/run/mt-hub): where each login's Jupyter runtime folder is made (kernel sockets).
- ``MT_HUB_STUDENT_PYTHON`` (the hub's): the Python students' servers run (``scripts/install-hub.sh``).
- ``MT_HUB_INSTRUCTORS_GROUP`` (mt-instructors): the system group of instructors and TAs.
- ``MT_HUB_COURSE``: the instructor's nbgrader course folder, made the instructors' only.
- ``MT_HUB_PORT`` (8000): the port, on 127.0.0.1 only (README.md: HTTPS for a class beyond the
  machine). ``MT_HUB_PROXY_API_PORT`` (8001), ``MT_HUB_INTERNAL_PORT`` (8081).
- ``MT_HUB_SPAWN_LIMIT`` (100): servers starting at once (the server template's backlog too);
  ``MT_HUB_SERVER_LIMIT`` (100; 0: none): servers running at once, the next student being told
  the class server is full.
- ``MT_HUB_API_TOKEN``: a token for the ``class-admin`` service (tests, ``benchmarks/bench_hub.py``).
- ``MT_WIDGETS_CLASS_FOLDER``, ``MT_WIDGETS_EXCHANGE``: the class folder and nbgrader's exchange.
- ``MT_HUB_NUMBA_TEMPLATE``: a warm numba cache (``warm_numba_cache.py``) copied into a
  student's empty cache at spawn, so nobody's first episode waits for compiling.
- ``MT_HUB_SERVER_TEMPLATE`` (on): students' servers are forked, as each student, from a template
  that has imported their server and kernel (``mt_widgets/kernels/server_template.py``), and
  their kernels from a template of their own; ``off`` starts every server and kernel the usual
  way. Instructors' servers always start the usual way (their extensions differ).
"""

import asyncio
import logging
import os
import random
import shutil
import socket
import sys
import tempfile
from pathlib import Path

import jupyterhub
from jupyterhub.spawner import LocalProcessSpawner

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import class_hub  # noqa: E402
from class_hub import CgroupLimits, ClassHubError  # noqa: E402
from roster_authenticator import RosterAuthenticator  # noqa: E402

import mt_widgets  # noqa: E402
from mt_widgets.classroom.roster import read_roster  # noqa: E402
from mt_widgets.kernels.server_template import ServerTemplate  # noqa: E402

c = get_config()  # noqa: F821 - provided by JupyterHub's config loader

if os.geteuid() != 0:
    raise SystemExit("the class hub runs as root: it starts each student's server as that student's own "
                     "system user (and never as root)")
if not os.environ.get("MT_HUB_ROSTER"):
    raise SystemExit("MT_HUB_ROSTER: expected the class roster (a CSV of logins, mt_widgets/classroom/roster.py)")
ROSTER = Path(os.environ["MT_HUB_ROSTER"]).resolve()
roster = read_roster(ROSTER)  # a bad roster stops the hub here, naming every bad line
STATE = Path(os.environ.get("MT_HUB_STATE", "mt-hub-state")).resolve()
HOMES = Path(os.environ.get("MT_HUB_HOMES", "/home")).resolve()
INSTRUCTORS = os.environ.get("MT_HUB_INSTRUCTORS_GROUP", "mt-instructors")
# Each login's Jupyter runtime folder (its kernels' IPC sockets): short, since a socket's path has
# at most 107 bytes, and each login's own (0700).
RUNTIME = Path(os.environ.get("MT_HUB_RUNTIME", "/run/mt-hub")).resolve()
_longest_socket = len(f"{RUNTIME}/{'x' * 32}/kernel-{'0' * 36}-ipc-99")
if _longest_socket > 107:
    raise SystemExit(f"MT_HUB_RUNTIME: {RUNTIME} is too long for kernels' IPC socket paths ({_longest_socket} "
                     "bytes of at most 107): choose a shorter folder")
STATE.mkdir(parents=True, exist_ok=True)
os.chmod(STATE, 0o700)
RUNTIME.mkdir(parents=True, exist_ok=True)
os.chmod(RUNTIME, 0o711)
HOMES.mkdir(parents=True, exist_ok=True)

# -- the installation: every student must read it, none may write it ---------------------------------
# The Python students' servers and kernels run: the hub's own unless MT_HUB_STUDENT_PYTHON names
# another (scripts/install-hub.sh makes one when the hub's is out of students' reach, as a pyenv
# Python under /root is).
STUDENT_PYTHON = Path(os.environ.get("MT_HUB_STUDENT_PYTHON") or sys.executable)
_installation = [STUDENT_PYTHON, Path(mt_widgets.__file__).parent, HERE, Path(jupyterhub.__file__).parent]
_problems = class_hub.installation_problems(_installation)
if _problems:
    raise SystemExit("students could not use this installation (they are neither its owner nor its group):\n  "
                     + "\n  ".join(_problems) + "\n(or set MT_HUB_STUDENT_PYTHON to a Python they can run: "
                     "scripts/install-hub.sh makes one)")



def _count_setting(name: str, default: str, zero_means: str | None = None) -> int:
    """The environment's ``name`` as a count of at least 1 (or 0, where ``zero_means`` says what it means)."""
    text = os.environ.get(name, default)
    smallest = 0 if zero_means else 1
    if not text.isdigit() or int(text) < smallest:
        meaning = f" (0: {zero_means})" if zero_means else ""
        raise SystemExit(f"{name}: expected a whole number of at least {smallest}{meaning}, got {text!r}")
    return int(text)


# -- the hub: loopback only ------------------------------------------------------------------------
c.JupyterHub.ip = "127.0.0.1"
c.JupyterHub.port = int(os.environ.get("MT_HUB_PORT", "8000"))
c.JupyterHub.hub_ip = "127.0.0.1"
c.JupyterHub.hub_port = int(os.environ.get("MT_HUB_INTERNAL_PORT", "8081"))
c.JupyterHub.db_url = f"sqlite:///{STATE / 'jupyterhub.sqlite'}"
c.JupyterHub.cookie_secret_file = str(STATE / "jupyterhub_cookie_secret")
c.ConfigurableHTTPProxy.pid_file = str(STATE / "proxy.pid")
c.ConfigurableHTTPProxy.api_url = f"http://127.0.0.1:{int(os.environ.get('MT_HUB_PROXY_API_PORT', '8001'))}"
# A whole class logs in at the start of a lesson: let them all spawn at once (a forked server
# starts in about 0.2 CPU-seconds: sixty at once are ready well within a minute, docs/guide/scaling.md).
# The server template's socket holds as many waiting spawns (its backlog, below): a backlog of 64
# under a limit of 100 lost a quarter of a class started at once (docs/guide/faults.md).
SPAWN_LIMIT = _count_setting("MT_HUB_SPAWN_LIMIT", "100")
c.JupyterHub.concurrent_spawn_limit = SPAWN_LIMIT
# The servers this machine holds at once (0: no limit): the next student is told the class server
# is full, in words (templates/429.html), instead of a server that never comes up.
c.JupyterHub.active_server_limit = _count_setting("MT_HUB_SERVER_LIMIT", "100", zero_means="no limit")
c.JupyterHub.template_paths = [str(HERE / "templates")]
# The disk holding the hub's state full (its database, the password hashes): the request is
# refused with a page in words (templates/500.html) and the log says which folder to free.
logging.getLogger("tornado.application").addFilter(class_hub.DiskFullLog(STATE))
# A hub stopped (an upgrade, a restart) or killed during a lesson leaves students' servers and kernels
# running: the restarted hub finds each by the pid in its database and routes to it again
# (docs/guide/faults.md). JupyterHub's default stops every server with the hub. To end a class's
# servers, stop them first (the admin page's "Stop All", or the idle culler).
c.JupyterHub.cleanup_servers = False
# The proxy stays up too (as it does when the hub is killed): the students' pages keep their kernels'
# websockets through it while the hub is down, and the restarted hub adopts it by its pid file. With
# JupyterHub's default the proxy stopped with the hub, and every student's JupyterLab lost its kernel
# and said "Your server ... is not running" until the hub was back (tests/course/test_hub.py). To end
# the class server for good, stop the proxy after the hub (its pid is in proxy.pid, deploy/jupyterhub/README.md).
c.JupyterHub.cleanup_proxy = False

# -- who comes in ----------------------------------------------------------------------------------
c.JupyterHub.authenticator_class = RosterAuthenticator
c.RosterAuthenticator.roster_path = str(ROSTER)
c.RosterAuthenticator.password_file = str(STATE / "passwords.json")
c.Authenticator.admin_users = {entry.login for entry in roster.admins}
c.Authenticator.auth_refresh_age = 300  # a student removed from the roster is logged out within 5 minutes
c.JupyterHub.services = []
c.JupyterHub.load_roles = []
if os.environ.get("MT_HUB_API_TOKEN"):
    c.JupyterHub.services.append({"name": "class-admin", "api_token": os.environ["MT_HUB_API_TOKEN"]})
    c.JupyterHub.load_roles.append({
        "name": "class-admin",
        "scopes": ["admin:users", "admin:servers", "tokens", "access:servers", "read:users"],
        "services": ["class-admin"],
    })
CULL_IDLE_S = int(os.environ.get("MT_HUB_CULL_IDLE_SECONDS", str(class_hub.DEFAULT_CULL_IDLE_S)))
if CULL_IDLE_S > 0:
    # Stops servers idle that long; a student's saved notebooks and progress stay in their home. Run
    # through idle_culler.py, which ends it with the hub (a killed hub would leave it running).
    c.JupyterHub.services.append({
        "name": "idle-culler",
        "command": [sys.executable, str(HERE / "idle_culler.py"), f"--timeout={CULL_IDLE_S}",
                    f"--cull-every={max(60, CULL_IDLE_S // 10)}"],
    })
    c.JupyterHub.load_roles.append({
        "name": "idle-culler",
        "scopes": ["list:users", "read:users:activity", "read:servers", "delete:servers"],
        "services": ["idle-culler"],
    })

# -- who comes in from a learning platform: LTI 1.3 launches (MT_HUB_LOGIN=lti) ------------------------
# One setting chooses the login: the roster's passwords (above) or launches from the course's page in
# Canvas, Moodle... (lti_authenticator.py; the platform's settings: docs/guide/lms.md). Either way each
# person is a roster login, so the accounts, isolation and limits below are the same.
LOGIN = os.environ.get("MT_HUB_LOGIN", "roster")
if LOGIN not in ("roster", "lti"):
    raise SystemExit(f"MT_HUB_LOGIN: expected 'roster' or 'lti', got {LOGIN!r}")
if LOGIN == "lti":
    from lti_authenticator import configure_lti  # noqa: E402 - only an LTI hub needs jupyterhub-ltiauthenticator

    configure_lti(c, ROSTER, STATE, os.environ)

# -- limits ----------------------------------------------------------------------------------------
LIMITS = None
if os.environ.get("MT_HUB_LIMITS", "on") != "off":
    LIMITS = CgroupLimits(class_hub.parse_bytes(os.environ.get("MT_HUB_MEM_LIMIT", class_hub.DEFAULT_MEM_LIMIT)),
                          float(os.environ.get("MT_HUB_CPU_LIMIT", class_hub.DEFAULT_CPU_LIMIT)),
                          parent=os.environ.get("MT_HUB_CGROUP", "mt-hub"))
    _problem = LIMITS.problem()
    if _problem:
        raise SystemExit(f"per-student limits cannot be enforced here ({_problem}); on a systemd host use "
                         "jupyterhub-systemdspawner (deploy/jupyterhub/README.md), or set MT_HUB_LIMITS=off "
                         "to run a class without them")

# -- accounts and folders, for the whole roster before anyone logs in --------------------------------
INSTRUCTORS_GID = class_hub.ensure_group(INSTRUCTORS)
CLASS_FOLDER = Path(os.environ["MT_WIDGETS_CLASS_FOLDER"]) if os.environ.get("MT_WIDGETS_CLASS_FOLDER") else None
if CLASS_FOLDER is not None:
    class_hub.secure_class_folder(CLASS_FOLDER, INSTRUCTORS_GID)
if os.environ.get("MT_HUB_COURSE"):
    class_hub.secure_course_folder(Path(os.environ["MT_HUB_COURSE"]), INSTRUCTORS_GID)


def _prepare_account(login: str, log=None) -> None:
    """``login``'s system user, home and, for a student, progress files (every student on the roster
    has them from the hub's start, so that no student can take a classmate's file name first; the
    class view lists a student who has not started yet with no events)."""
    entry = read_roster(ROSTER).entry(login)
    class_hub.ensure_system_user(login, HOMES / login, INSTRUCTORS, entry.is_admin)
    if CLASS_FOLDER is not None and not entry.is_admin:
        class_hub.ensure_progress_files(CLASS_FOLDER, login, INSTRUCTORS_GID, log)


for _entry in roster.entries:
    _prepare_account(_entry.login)

# -- each student's server -------------------------------------------------------------------------


class ClassSpawner(LocalProcessSpawner):
    """A student's server as their own system user, inside their cgroups (umask 027 comes from
    student-config/jupyter_server_config.py, which Zero to JupyterHub's pods load too): forked
    from the class's server template when it is on (``SERVER_TEMPLATE``), else started the usual way."""

    def make_preexec_fn(self, name):
        drop_root = super().make_preexec_fn(name)
        join = LIMITS.join_function(name) if LIMITS is not None else None

        def preexec():
            if join is not None:
                join()  # while still root: the group's files are root's
            drop_root()

        return preexec

    async def start(self):
        if SERVER_TEMPLATE is None or self.user.admin:
            return await super().start()
        import pwd

        account = pwd.getpwnam(self.user.name)
        request = {
            "argv": [*self.cmd, *self.get_args()], "env": self.get_env(), "cwd": account.pw_dir,
            "uid": account.pw_uid, "gid": account.pw_gid,
            "groups": os.getgrouplist(self.user.name, account.pw_gid),
            "cgroup_procs": LIMITS.procs_files(self.user.name) if LIMITS is not None else [],
        }
        pid = await SERVER_TEMPLATE.fork(request)
        if pid is None:
            self.log.warning("%s's server: starting it the usual way", self.user.name)
            return await super().start()
        self.proc, self.pid = None, pid
        self.log.info("%s's server forked from the server template (pid %d)", self.user.name, pid)
        return (self.ip or "127.0.0.1", self.port)


c.JupyterHub.spawner_class = ClassSpawner
c.Spawner.cmd = [str(STUDENT_PYTHON), "-m", "jupyterhub.singleuser"]
c.Spawner.default_url = "/lab/tree/index.ipynb"
# A class of thirty starting at once on two cores takes a minute or more (benchmarks/bench_hub.py).
c.Spawner.start_timeout = 300
c.Spawner.http_timeout = 300

# Passed on from the hub's environment: the class folder, the exchange, and (tests) the checkout.
_passed_on = ("MT_WIDGETS_CLASS_FOLDER", "MT_WIDGETS_EXCHANGE")
# student-site/ first: it leaves out a package that costs every server seconds at start (its docstring).
_python_path = os.pathsep.join([str(HERE / "student-site"), *filter(None, [os.environ.get("PYTHONPATH")])])
c.Spawner.environment = {
    # numba's compiled rollouts go to each student's home, never into the shared installation.
    "NUMBA_CACHE_DIR": lambda spawner: str(HOMES / spawner.user.name / ".cache" / "numba"),
    "MPLCONFIGDIR": lambda spawner: str(HOMES / spawner.user.name / ".cache" / "matplotlib"),
    "PYTHONDONTWRITEBYTECODE": "1",
    "JUPYTER_RUNTIME_DIR": lambda spawner: str(RUNTIME / spawner.user.name),
    # nbgrader's student side and the server's settings (IPC kernels, extensions) come from here.
    "JUPYTER_CONFIG_PATH": str(HERE / "student-config"),
    "MT_HUB_ROLE": lambda spawner: "instructor" if spawner.user.admin else "student",
    # Students' "python3" kernel spec: ipykernel without its debugger (student-site/mt_hub_kernel.py).
    "JUPYTER_PATH": lambda spawner: "" if spawner.user.admin else str(HERE / "student-share"),
    "PYTHONPATH": _python_path,
    # Students' servers find no node: JupyterLab's import asks yarn (a node process, ~2 s) for the
    # npm registry at every start when node is on PATH, for building extensions no student builds.
    # Instructors' terminals find nbgrader and jupyter run by the Python they can run first
    # (scripts/install-hub.sh puts them beside it).
    "PATH": lambda spawner: (os.pathsep.join([str(STUDENT_PYTHON.parent), os.environ.get("PATH", "")])
                             if spawner.user.admin else str(STUDENT_PYTHON.parent)),
    **{name: os.environ[name] for name in _passed_on if os.environ.get(name)},
}

# Students' servers forked from one template that has imported their server and kernel
# (mt_widgets/kernels/server_template.py says what keeps it safe). Its environment is the
# students' without anything of a student's or of the hub's: it imports what they will run.
#: The modules of a student's Jupyter server's REST handlers, which jupyter_server imports by name
#: when its web app starts (``jupyter_server.serverapp.JUPYTER_SERVICE_HANDLERS``): every forked
#: server of a class imported them again (py-spy, benchmarks/bench_hub.py).
SERVER_HANDLER_MODULES = [
    "jupyter_server.services.api.handlers", "jupyter_server.services.config.handlers",
    "jupyter_server.services.contents.handlers", "jupyter_server.files.handlers",
    "jupyter_server.services.kernels.handlers", "jupyter_server.kernelspecs.handlers",
    "jupyter_server.services.kernelspecs.handlers", "jupyter_server.nbconvert.handlers",
    "jupyter_server.services.nbconvert.handlers", "jupyter_server.services.security.handlers",
    "jupyter_server.services.sessions.handlers", "jupyter_server.services.shutdown",
    "jupyter_server.view.handlers", "jupyter_server.services.events.handlers", "jupyter_server.base.handlers",
]
SERVER_TEMPLATE = None
if os.environ.get("MT_HUB_SERVER_TEMPLATE", "on") != "off":
    SERVER_TEMPLATE = ServerTemplate(
        STUDENT_PYTHON, servers=["jupyterhub.singleuser"], kernels=["mt_hub_kernel"],
        preload=["jupyterhub.singleuser.extension", "jupyter_server.serverapp", "jupyterlab.labapp",
                 "jupyterlab_server", "notebook_shim.nbserver", "numpy", "numba", "ipywidgets",
                 "ipykernel.ipkernel", "mt_widgets", "mt_widgets.classroom", "mt_widgets.widgets",
                 # what a server's and a kernel's start imported after the fork (py-spy, bench_hub.py)
                 "mt_widgets.kernels.activity", "jupyterlab.extensions.readonly", "jupyter_core.migrate",
                 "jinja2.ext", "pdb", "IPython.core.debugger", "IPython.core.oinspect",
                 "IPython.core.completerlib", "IPython.extensions.storemagic",
                 # and what they still imported after it (the modules of a forked server and kernel
                 # that its template lacked; docs/guide/scaling.md): the server's REST handlers,
                 # loaded by name at its start, the students' lazy extensions, the kernel spec's
                 # module, tornado's asyncio loop (imported at the first IOLoop), the process
                 # title; in a kernel, ipykernel's debugger module (without debugpy) and IPython's logger
                 *SERVER_HANDLER_MODULES, "mt_hub_nbgrader", "mt_hub_voila", "ipykernel.kernelspec",
                 "tornado.platform.asyncio", "setproctitle", "ipykernel.debugger", "IPython.core.logger"],
        env={"PATH": str(STUDENT_PYTHON.parent), "PYTHONPATH": _python_path, "PYTHONDONTWRITEBYTECODE": "1",
             "JUPYTER_CONFIG_PATH": str(HERE / "student-config"), "JUPYTER_PATH": str(HERE / "student-share"),
             "MT_HUB_ROLE": "student", "LANG": os.environ.get("LANG", "C.UTF-8")},
        # The warm cache's compiled rollouts, loaded once and shared by every student's kernel.
        numba_cache=os.environ.get("MT_HUB_NUMBA_TEMPLATE"),
        # Every spawn the hub lets run at once waits in the template's queue, none refused.
        backlog=SPAWN_LIMIT)
    _hub_app = sys.modules.get("jupyterhub.app")
    if _hub_app is not None and _hub_app.JupyterHub.initialized():
        SERVER_TEMPLATE.ensure_started()  # a hub is starting: the template imports meanwhile
    # (else the config is only being read, as its tests do: the first spawn starts the template)


def _copy_owned(source: Path, target: Path, uid: int, gid: int) -> None:
    """``source`` copied to ``target``, every file ``uid``'s and ``gid``'s; ``target`` appears whole or
    not at all (copied beside it, then renamed): a copy cut short is not taken for a warm cache
    at the next spawn, which copies again. The copy is made in a new folder of root's (0700), where
    the student cannot reach it until it is whole."""
    staging = Path(tempfile.mkdtemp(prefix=f".{target.name}-copying-", dir=target.parent))
    try:
        partial = staging / target.name
        shutil.copytree(source, partial)
        for path in [partial, *partial.rglob("*")]:
            os.chown(path, uid, gid, follow_symlinks=False)
        os.rename(partial, target)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


#: The port chosen for each login's server, from its spawn until it stops. (Keyed by login: a
#: member has one server here, named servers being off; with them on, key by the server too.)
_SERVER_PORTS: dict[str, int] = {}


def _port_outside_ephemeral_range(taken=frozenset()) -> int:
    """A free port below Linux's ephemeral range (32768-60999), none of ``taken``. JupyterHub's own
    choice comes from that range, where every outgoing connection's local port comes from too: with
    a class starting at once, a connection can take a server's port between the hub choosing it and
    the server binding it."""
    for _ in range(500):
        port = random.randint(20000, 32000)
        if port in taken:
            continue
        with socket.socket() as probe:
            try:
                probe.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    raise RuntimeError("no free port between 20000 and 32000 for a student's server")


def _reserve_port(login: str) -> int:
    """The port for ``login``'s server, kept for it until it stops (``_release_port``).

    A free port is free only until a server binds it: thirty servers spawned at once are each given
    a port before any of them has bound one, so the probe alone could give two students the same
    port (about once in thirty classes of thirty; seen in benchmarks/bench_hub.py). The second
    server then cannot bind it and ends, but the hub, which takes any HTTP answer as "up", finds
    the first student's server there and routes the second student to it. The hub runs its spawn
    hooks on its event loop, and this record is read and written with no await between (the hook's
    only await, the preparation in a thread, comes before), so it has no race of its own."""
    taken = {port for other, port in _SERVER_PORTS.items() if other != login}
    _SERVER_PORTS[login] = _port_outside_ephemeral_range(taken)
    return _SERVER_PORTS[login]


def _release_port(login: str) -> None:
    _SERVER_PORTS.pop(login, None)


def _prepare_spawn(login: str, log) -> None:
    """What a spawn needs on disk: the account (the roster may have changed), the runtime folder, a
    warm numba cache, the cgroups. Blocking work (files, the roster, useradd for a new login, the
    cache's copy): ``_before_spawn`` runs it in a thread."""
    import pwd

    try:
        _prepare_account(login, log)
    except KeyError:
        raise ClassHubError(f"{login} is no longer on the roster {ROSTER}") from None
    user = pwd.getpwnam(login)
    runtime = RUNTIME / login
    runtime.mkdir(exist_ok=True)
    os.chown(runtime, user.pw_uid, user.pw_gid)
    os.chmod(runtime, 0o700)
    cache = HOMES / login / ".cache" / "numba"
    template = os.environ.get("MT_HUB_NUMBA_TEMPLATE")
    if template and Path(template).is_dir() and not cache.exists():
        for folder in (HOMES / login / ".cache",):
            folder.mkdir(exist_ok=True)
            os.chown(folder, user.pw_uid, user.pw_gid)
        _copy_owned(Path(template), cache, user.pw_uid, user.pw_gid)
    if LIMITS is not None:
        LIMITS.create(login)


async def _before_spawn(spawner) -> None:
    """Before a server starts: ``_prepare_spawn`` in a thread, then the server's port.

    JupyterHub awaits this hook on its event loop, which serves every other login, spawn and
    progress page meanwhile: nothing of the hook's that blocks (files, the roster, useradd for a
    new login, the warm cache's copy: every compiled version of the package's kernels) runs on it.
    (The loop still stands still for seconds when a class spawns at once: JupyterHub's own start
    of each spawn, before this hook, takes about 0.1 s of the loop on a loaded machine, and a
    class's spawns start in the same turn of it; benchmarks/bench_spawn_hook.py.)"""
    login = spawner.user.name
    await asyncio.get_running_loop().run_in_executor(None, _prepare_spawn, login, spawner.log)
    spawner.port = _reserve_port(login)


def _after_stop(spawner) -> None:
    _release_port(spawner.user.name)
    if LIMITS is not None:
        LIMITS.remove(spawner.user.name)


c.Spawner.pre_spawn_hook = _before_spawn
c.Spawner.post_stop_hook = _after_stop
