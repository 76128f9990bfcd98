"""A class JupyterHub on loopback for tests and benchmarks/bench_hub.py.

``ClassHub`` starts ``deploy/jupyterhub/jupyterhub_config.py`` as root with its own roster, state,
homes, class folder, course folder and nbgrader exchange in a fresh folder, on free ports of
127.0.0.1, and drives it as people do: the login form (real passwords), the hub's REST API
(servers), each student's Jupyter server (kernels over websockets, contents, nbgrader's
assignment handlers). Test accounts are system users ``mtt-...``, removed at ``stop`` with
their cgroups. Nothing here retries: a lost kernel is a failure.
"""

from __future__ import annotations

import fcntl
import grp
import json
import os
import pwd
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import uuid
import warnings
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import psutil
import requests
import websocket

REPO = Path(__file__).resolve().parents[2]
CONFIG = REPO / "deploy" / "jupyterhub" / "jupyterhub_config.py"
CLASS_ADMIN = REPO / "deploy" / "jupyterhub" / "class_admin.py"
BIN = Path(sys.executable).parent
#: Made by scripts/install-hub.sh when students cannot run .venv's own interpreter.
STUDENT_PYTHON = REPO / ".venv" / "students" / "bin" / "python"
sys.path.insert(0, str(REPO / "tests"))
from browser_support import free_port  # noqa: E402


def proxy_folder() -> Path:
    """Where configurable-http-proxy is; scripts/install-hub.sh installs it (and the students' Python)."""
    result = subprocess.run(["bash", str(REPO / "scripts" / "install-hub.sh")], capture_output=True, text=True,
                            timeout=300)
    if result.returncode != 0:
        raise RuntimeError(f"configurable-http-proxy could not be installed:\n{result.stderr[-2000:]}")
    return Path(result.stdout.strip().splitlines()[-1])


def warm_numba_template(folder: Path) -> Path:
    """A numba cache warmed by deploy/jupyterhub/warm_numba_cache.py (what an install step does once)."""
    if not folder.exists():
        env = dict(os.environ, NUMBA_CACHE_DIR=str(folder), PYTHONPATH=str(REPO))
        python = STUDENT_PYTHON if STUDENT_PYTHON.exists() else Path(sys.executable)  # the students' numba
        subprocess.run([str(python), str(REPO / "deploy" / "jupyterhub" / "warm_numba_cache.py")], env=env,
                       check=True, capture_output=True, timeout=600)
    return folder


#: The kernel websocket protocol JupyterLab 4 speaks (jupyter_server's ``kernel_ws_protocol``): the
#: server relays each kernel message's frames as they are, where the legacy JSON protocol has it
#: decode and encode every message again; measuring with the legacy one would overstate what
#: a class's browsers cost a server.
WS_PROTOCOL = "v1.kernel.websocket.jupyter.org"


def _encode_v1(channel: str, message: dict) -> bytes:
    """A message in the v1 protocol's framing: the part count, each part's offset, the channel,
    then the header, parent header, metadata and content as JSON (no buffers)."""
    parts = [json.dumps(message[key]).encode() for key in ("header", "parent_header", "metadata", "content")]
    offsets = [8 * (1 + 1 + len(parts) + 1)]
    offsets.append(offsets[-1] + len(channel.encode()))
    for part in parts:
        offsets.append(offsets[-1] + len(part))
    return b"".join([len(offsets).to_bytes(8, "little"), *(o.to_bytes(8, "little") for o in offsets),
                     channel.encode(), *parts])


def _decode(frame: bytes) -> dict:
    """A kernel message from a v1 frame (buffers, as a canvas's drawing commands carry, are skipped)."""
    count = int.from_bytes(frame[:8], "little")
    offsets = [int.from_bytes(frame[8 * (i + 1):8 * (i + 2)], "little") for i in range(count)]
    parts = [frame[offsets[i]:offsets[i + 1]] for i in range(1, min(count - 1, 5))]
    header, parent_header, _, content = (json.loads(part) for part in parts[:4])
    return {"msg_type": header["msg_type"], "header": header, "parent_header": parent_header, "content": content}


#: Every system user, group and cgroup the tests make starts with this, and is removed at the end.
TEST_PREFIX = "mtt-"
#: The instructors' group of test hubs.
TEST_INSTRUCTORS = "mtt-instructors"


class LoginRefused(RuntimeError):
    """The hub's login page refused a login (wrong password, not on the roster, locked)."""


class ClassHub:
    """A JupyterHub for a class, in a fresh folder under /tmp (state, homes, class folder, exchange,
    course), started as root with a roster of ``students`` and ``admins``.

    Test accounts are system users named ``mtt-...``; ``stop`` ends the hub and every process of
    theirs, and removes those users, their group, their cgroups and the folder.
    """

    def __init__(self, students, admins=(), numba_template: Path | None = None, spawn_limit: int = 100,
                 mem_limit: str = "1G", cpu_limit: str = "1.0", extra_roster: str = "", env: dict | None = None,
                 state_size: str | None = None, config: Path = CONFIG):
        for login in (*students, *admins):
            if not login.startswith(TEST_PREFIX):
                raise ValueError(f"test logins start with {TEST_PREFIX!r} (so cleanup finds them), got {login!r}")
        # Held while this hub lives: remove_leftovers sweeps nothing while any test hub runs.
        self._lock = open(HUB_LOCK, "a")  # noqa: SIM115 (closed by stop)
        fcntl.flock(self._lock, fcntl.LOCK_SH)
        # Students must be able to enter the hub's folders: /tmp, then this 0711 folder.
        self.root = Path(tempfile.mkdtemp(prefix=f"{TEST_PREFIX}hub-", dir="/tmp"))
        os.chmod(self.root, 0o711)
        self.students, self.admins = list(students), list(admins)
        self.port, self.proxy_api_port, self.hub_port = free_port(), free_port(), free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.token = secrets.token_hex(24)
        self.cgroup = f"{TEST_PREFIX}hub-{secrets.token_hex(3)}"
        self.homes = self.root / "homes"
        self.homes.mkdir()
        self.runtime = Path("/tmp", self.cgroup)  # short: kernels' IPC socket paths have at most 107 bytes
        os.chmod(self.homes, 0o711)
        self.class_folder = self.root / "class"
        self.exchange = self.root / "exchange"
        self.course = self.root / "course"
        self.course.mkdir()
        self.exchange.mkdir()
        os.chmod(self.exchange, 0o777)  # nbgrader's exchange root: nbgrader sets the permissions below it
        self.roster = self.root / "roster.csv"
        # The hub's state (its database, cookie secret, password hashes) on a filesystem of its own of
        # ``state_size`` (a tmpfs, "2m"), to fill up as a full disk does; unmounted at stop.
        self.state = self.root / "state"
        self.state_mounted = False
        if state_size is not None:
            self.state.mkdir()
            subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={state_size},mode=0700", "tmpfs", str(self.state)],
                           check=True, capture_output=True, text=True, timeout=30)
            self.state_mounted = True
        self.roster.write_text("login,name,email,role\n"
                               + "".join(f"{login},Test Admin,,instructor\n" for login in self.admins)
                               + "".join(f"{login},Student {login},,student\n" for login in self.students)
                               + extra_roster)
        extra_env, env = env, dict(os.environ)
        env.update({
            "PATH": f"{proxy_folder()}{os.pathsep}{BIN}{os.pathsep}{env.get('PATH', '')}",
            "PYTHONPATH": str(REPO),
            "MT_HUB_PORT": str(self.port), "MT_HUB_PROXY_API_PORT": str(self.proxy_api_port),
            "MT_HUB_INTERNAL_PORT": str(self.hub_port), "MT_HUB_ROSTER": str(self.roster),
            "MT_HUB_STATE": str(self.state), "MT_HUB_HOMES": str(self.homes),
            "MT_HUB_RUNTIME": str(self.runtime),
            "MT_HUB_INSTRUCTORS_GROUP": TEST_INSTRUCTORS, "MT_HUB_COURSE": str(self.course),
            "MT_HUB_CGROUP": self.cgroup, "MT_HUB_MEM_LIMIT": mem_limit, "MT_HUB_CPU_LIMIT": cpu_limit,
            "MT_HUB_API_TOKEN": self.token, "MT_HUB_SPAWN_LIMIT": str(spawn_limit),
            "MT_WIDGETS_CLASS_FOLDER": str(self.class_folder), "MT_WIDGETS_EXCHANGE": str(self.exchange),
        })
        env.pop("MT_WIDGETS_STUDENT", None)
        env["MT_HUB_STUDENT_PYTHON"] = str(STUDENT_PYTHON if STUDENT_PYTHON.exists() else sys.executable)
        if numba_template is not None:
            env["MT_HUB_NUMBA_TEMPLATE"] = str(numba_template)
        env.update(extra_env or {})  # the test's own settings (an LTI hub's, a server limit)
        self.env = env
        self.config = config  # the class hub's, or one that loads it (benchmarks/bench_spawn_hook.py)
        self.log = self.root / "jupyterhub.log"
        self._log_file = open(self.log, "w")
        self.session = requests.Session()
        self.session.headers["Authorization"] = f"token {self.token}"
        # A fresh connection for every request: the proxy (configurable-http-proxy, node) closes a
        # keep-alive connection after 5 s idle, and a request sent on a pooled connection at that
        # moment fails with "connection reset by peer" (seen once in bench_hub.py, a few seconds
        # after the lecture, on the next phase's first request). A browser resends such a request
        # on a new connection by itself; requests does not, and resending a POST blindly could
        # start two kernels. Loopback connections cost next to nothing; the kernels' websockets
        # are separate connections.
        self.session.headers["Connection"] = "close"
        adapter = requests.adapters.HTTPAdapter(pool_connections=4, pool_maxsize=64)
        self.session.mount("http://", adapter)
        try:
            self._start()
        except BaseException:
            self.stop()
            raise

    def _start(self) -> float:
        """Starts the hub and waits until its API answers; the seconds that took."""
        started = time.monotonic()
        self.process = subprocess.Popen([str(BIN / "jupyterhub"), "-f", str(self.config)], cwd=self.root, env=self.env,
                                        stdout=self._log_file, stderr=subprocess.STDOUT, start_new_session=True)
        return self.wait_until_answering(started)

    def wait_until_answering(self, started: float | None = None) -> float:
        """Waits (at most 120 s) until the hub's API answers through the proxy; the seconds since ``started``."""
        started = time.monotonic() if started is None else started
        deadline = started + 120
        while True:
            if self.process.poll() is not None:
                raise RuntimeError(f"jupyterhub exited with {self.process.returncode}:\n{self.tail()}")
            try:
                if self.session.get(f"{self.url}/hub/api/", timeout=2).status_code == 200:
                    return time.monotonic() - started
            except requests.ConnectionError:
                pass
            if time.monotonic() > deadline:
                raise RuntimeError(f"jupyterhub did not answer within 120 s:\n{self.tail()}")
            time.sleep(0.25)

    def restart(self, signum: int) -> float:
        """Ends the hub process alone with ``signum`` (SIGTERM: the documented stop; SIGKILL: a crash),
        leaving its proxy and the students' servers as they are, and starts it again; the seconds
        until the new hub answers."""
        self.end(signum)
        self._log_file.write(f"\n=== hub ended by signal {signum}, started again ===\n")
        self._log_file.flush()
        return self._start()

    def end(self, signum: int) -> int:
        """Ends the hub process alone with ``signum`` and waits for it; its exit code."""
        os.kill(self.process.pid, signum)
        return self.process.wait(60)

    def start_again(self) -> float:
        """Starts the hub again after ``end``; the seconds until it answers (RuntimeError, with its
        log's end, when it exits instead)."""
        self._log_file.write("\n=== hub started again ===\n")
        self._log_file.flush()
        return self._start()

    def _end_proxy(self) -> None:
        try:
            proxy = psutil.Process(int((self.state / "proxy.pid").read_text()))
            if "configurable-http-proxy" in " ".join(proxy.cmdline()):
                proxy.kill()
                proxy.wait(10)
        except (FileNotFoundError, ValueError, psutil.NoSuchProcess, psutil.ZombieProcess):
            pass

    def tail(self, chars: int = 4000) -> str:
        self._log_file.flush()
        return self.log.read_text()[-chars:]

    # -- the instructor's command ----------------------------------------------------------------------
    def class_admin(self, *args: str, stdin: str | None = None) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, str(CLASS_ADMIN), *args], input=stdin, capture_output=True,
                              text=True, env=self.env, timeout=120)

    def set_password(self, login: str, password: str) -> None:
        result = self.class_admin("set-password", login, "--stdin", stdin=password + "\n")
        if result.returncode != 0:
            raise RuntimeError(f"set-password {login}: {result.stderr}")

    # -- a member's own commands, as their system user -------------------------------------------------
    def member_env(self, login: str, **extra: str | None) -> dict:
        """The environment ``login``'s own shell on the hub has (their server's: home, the commands
        they can run first on PATH, their numba cache, the class's folders), plus ``extra`` (a
        value None leaves that variable out)."""
        home = self.homes / login
        students_bin = Path(self.env["MT_HUB_STUDENT_PYTHON"]).parent
        env = {key: value for key, value in self.env.items() if not key.startswith("MT_HUB_")}
        env.update({"HOME": str(home), "USER": login, "LOGNAME": login,
                    "PATH": f"{students_bin}{os.pathsep}{self.env['PATH']}",
                    "NUMBA_CACHE_DIR": str(home / ".cache" / "numba"),
                    "MPLCONFIGDIR": str(home / ".cache" / "matplotlib"),
                    "PYTHONDONTWRITEBYTECODE": "1", "JUPYTER_RUNTIME_DIR": str(self.runtime / login)})
        for key, value in extra.items():  # None leaves a variable out
            if value is None:
                env.pop(key, None)
            else:
                env[key] = value
        return env

    def run_as(self, login: str, argv, cwd: Path, timeout: float = 600,
               **env: str | None) -> subprocess.CompletedProcess:
        """Runs ``argv`` as ``login``'s system user (their groups, umask 027, their environment), as
        they would in a terminal of their own server; returns the finished process (output as text).
        ``argv[0]`` is looked up on their PATH (``scripts/install-hub.sh`` puts the installation's
        commands beside the students' Python)."""
        user = pwd.getpwnam(login)
        member_env = self.member_env(login, **env)
        command = shutil.which(argv[0], path=member_env["PATH"]) or argv[0]
        groups = [group.gr_gid for group in grp.getgrall() if login in group.gr_mem]
        return subprocess.run([command, *argv[1:]], cwd=cwd, env=member_env, user=user.pw_uid, group=user.pw_gid,
                              extra_groups=groups, umask=0o027, capture_output=True, text=True, timeout=timeout)

    # -- logging in as a person does ------------------------------------------------------------------
    def login(self, name: str, password: str) -> requests.Session:
        """Logs in through the hub's login form; returns the browser-like session with its cookie.

        Raises:
            LoginRefused: the hub answered with its login page again (403).
        """
        browser = requests.Session()
        page = browser.get(f"{self.url}/hub/login", timeout=60)
        page.raise_for_status()
        xsrf = browser.cookies.get("_xsrf") or ""
        answer = browser.post(f"{self.url}/hub/login", data={"username": name, "password": password, "_xsrf": xsrf},
                              allow_redirects=False, timeout=120)
        if answer.status_code == 403:
            raise LoginRefused(f"{name}: login refused")
        if answer.status_code != 302 or not any(c.name.startswith("jupyterhub-session") for c in browser.cookies):
            raise RuntimeError(f"{name}: unexpected login answer {answer.status_code}: {answer.text[:300]}")
        return browser

    # -- the hub's API -------------------------------------------------------------------------------
    def api(self, method: str, path: str, **kwargs):
        response = self.session.request(method, f"{self.url}/hub/api{path}", timeout=60, **kwargs)
        if response.status_code >= 400:
            raise RuntimeError(f"{method} /hub/api{path}: {response.status_code} {response.text[:500]}")
        return response.json() if response.content else None

    def create_users(self, names) -> None:
        self.api("POST", "/users", json={"usernames": list(names)})

    def ensure_running(self, name: str) -> None:
        """Creates ``name`` if the hub does not know them and starts their server if it is not running."""
        users = {user["name"]: user for user in self.api("GET", "/users")}
        if name not in users:
            self.create_users([name])
        if not ((users.get(name) or {}).get("servers") or {}).get(""):
            self.spawn(name)

    def spawn(self, name: str, timeout: float = 420) -> float:
        """Starts ``name``'s server; returns the seconds until the hub reports it ready.

        Follows the hub's progress event stream (no polling: thirty students polling the hub
        would slow the very spawns being measured).
        """
        started = time.perf_counter()
        self.api("POST", f"/users/{name}/server")
        with self.session.get(f"{self.url}/hub/api/users/{name}/server/progress", stream=True,
                              timeout=timeout) as stream:
            if stream.status_code != 200:
                raise RuntimeError(f"{name}'s spawn progress: {stream.status_code} {stream.text[:300]}")
            for line in stream.iter_lines(decode_unicode=True):
                if not line or not line.startswith("data:"):
                    continue
                event = json.loads(line[len("data:"):])
                if event.get("ready"):
                    return time.perf_counter() - started
                if event.get("failed"):
                    raise RuntimeError(f"{name}'s server failed to start: {event.get('message')}\n{self.tail()}")
        raise RuntimeError(f"{name}'s spawn progress ended without the server ready:\n{self.tail()}")

    def spawn_class(self, names) -> dict[str, float]:
        """Starts every student's server at once; returns name -> spawn seconds."""
        with ThreadPoolExecutor(len(names)) as pool:
            return dict(zip(names, pool.map(self.spawn, names)))

    # -- a student's server ---------------------------------------------------------------------------
    def user_url(self, name: str, path: str) -> str:
        return f"{self.url}/user/{name}{path}"

    def server_api(self, name: str, method: str, path: str, **kwargs):
        response = self.session.request(method, self.user_url(name, path), timeout=120, **kwargs)
        if response.status_code >= 400:
            raise RuntimeError(f"{method} /user/{name}{path}: {response.status_code} {response.text[:800]}")
        return response.json() if response.content else None

    def run_in_kernel(self, name: str, code: str, timeout: float = 180, kernel_id: str | None = None,
                      cell: str | None = None) -> dict:
        """Runs ``code`` in a new kernel of ``name``'s server (or in their kernel ``kernel_id``) and
        returns its output and timings. ``cell``: the notebook cell's id, sent as JupyterLab does
        (``cellId``): running one cell again retires the episodes it made (mt_widgets/widgets/cells.py).

        Returns:
            {"stdout": text printed, "error": the error's name and value or None,
             "died": True when the kernel died (was restarted) before answering,
             "kernel_id": ..., "seconds": wall time of the execution,
             "total_s": from asking for the kernel (when new) to the execution's end}
        """
        requested = time.perf_counter()
        if kernel_id is None:
            kernel_id = self.server_api(name, "POST", "/api/kernels", json={"name": "python3"})["id"]
        kernel = {"id": kernel_id}
        ws_url = self.user_url(name, f"/api/kernels/{kernel['id']}/channels").replace("http://", "ws://")
        connection = websocket.create_connection(ws_url, header=[f"Authorization: token {self.token}"],
                                                 timeout=timeout, subprotocols=[WS_PROTOCOL])
        started = time.perf_counter()
        stdout, error, replied, idle, died = [], None, False, False, False
        session, deadline = uuid.uuid4().hex, time.monotonic() + timeout

        def request(msg_type: str, content: dict, metadata: dict | None = None) -> str:
            msg_id = uuid.uuid4().hex
            connection.send_binary(_encode_v1("shell", {
                "header": {"msg_id": msg_id, "username": name, "session": session,
                           "msg_type": msg_type, "version": "5.3", "date": ""},
                "parent_header": {}, "metadata": metadata or {}, "content": content}))
            return msg_id

        try:
            # As JupyterLab does: nothing but a kernel_info_request until its reply. The server relays
            # a kernel's messages only once its own IOPub subscription for this connection is live
            # (jupyter_server's nudge); IOPub messages published before that are dropped, so an
            # execution sent at once can finish unseen (its idle status lost: a wait forever).
            info_id = request("kernel_info_request", {})
            while True:
                if time.monotonic() > deadline:
                    raise TimeoutError(f"{name}'s kernel did not answer kernel_info within {timeout} s")
                message = _decode(connection.recv())
                if (message["msg_type"] == "kernel_info_reply"
                        and message.get("parent_header", {}).get("msg_id") == info_id):
                    break
            msg_id = request("execute_request", {"code": code, "silent": False, "store_history": False,
                                                 "user_expressions": {}, "allow_stdin": False,
                                                 "stop_on_error": True},
                             metadata={"cellId": cell} if cell is not None else {})
            while not (replied and idle) and not died:
                if time.monotonic() > deadline:
                    raise TimeoutError(f"{name}'s kernel did not finish within {timeout} s")
                message = _decode(connection.recv())
                kind = message["msg_type"]
                if kind == "status" and message["content"]["execution_state"] in ("restarting", "dead"):
                    died = True  # the server says so on every channel, whatever the parent
                if message.get("parent_header", {}).get("msg_id") != msg_id:
                    continue
                if kind == "stream":
                    stdout.append(message["content"]["text"])
                elif kind == "error":
                    error = f"{message['content']['ename']}: {message['content']['evalue']}"
                elif kind == "execute_reply":
                    replied = True
                elif kind == "status" and message["content"]["execution_state"] == "idle":
                    idle = True
        finally:
            connection.close()
        ended = time.perf_counter()
        return {"stdout": "".join(stdout), "error": error, "died": died, "kernel_id": kernel["id"],
                "seconds": ended - started, "total_s": ended - requested}

    def read_json(self, name: str, path: str) -> dict:
        """A JSON file in ``name``'s home, read through their server's contents API."""
        model = self.server_api(name, "GET", f"/api/contents/{path}", params={"type": "file", "format": "text"})
        return json.loads(model["content"])

    def processes(self, name: str) -> list[psutil.Process]:
        """The processes of ``name``'s system user (their server and kernels)."""
        return _processes_of({pwd.getpwnam(name).pw_uid})

    def memory(self, name: str) -> int:
        """Resident bytes of ``name``'s server and its kernels."""
        total = 0
        for process in self.processes(name):
            try:
                total += process.memory_info().rss
            except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
                continue
        return total

    def stop(self) -> None:
        """Ends the hub and everything of its accounts; removes the accounts, group, cgroups and folder."""
        if self.process.poll() is None:
            # The hub and the proxy are in this process group; the students' servers in sessions of their own.
            try:
                os.killpg(self.process.pid, signal.SIGTERM)
                self.process.wait(30)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait(5)
        # The hub leaves its proxy running when it stops (cleanup_proxy=False), and a restarted hub
        # adopts the proxy the last one started, in that hub's process group: end it by its pid file.
        self._end_proxy()
        try:
            _remove_hub_accounts([*self.students, *self.admins], [self.cgroup])
        finally:
            # The log is kept and the folders go even when an account would not go (that error
            # is raised after this, and the log says why).
            self._log_file.close()
            self.kept_log = Path(tempfile.gettempdir()) / f"{self.root.name}-jupyterhub.log"
            shutil.copy(self.log, self.kept_log)
            if self.state_mounted:
                subprocess.run(["umount", "--lazy", str(self.state)], capture_output=True, timeout=30)
            shutil.rmtree(self.root, ignore_errors=True)
            shutil.rmtree(self.runtime, ignore_errors=True)
            self._lock.close()
            _remove_instructors_group_unless_used()


#: The GECOS field the class hub's config gives the accounts it makes (``class_hub.MARKER`` in
#: deploy/jupyterhub/class_hub.py; tests/course/test_hub_config.py checks they agree).
HUB_ACCOUNT = "mt-widgets class hub"
#: Every live ClassHub holds this file locked (shared); remove_leftovers needs it exclusively.
HUB_LOCK = Path("/tmp", f"{TEST_PREFIX}hub.lock")


def _processes_of(uids: set[int]) -> list[psutil.Process]:
    found = []
    for process in psutil.process_iter(["uids"]):
        if process.info["uids"] and process.info["uids"].real in uids:
            found.append(process)
    return found


def _end_processes(find) -> None:
    """Kills what ``find()`` lists until it lists nothing, waiting for each (at most 50 rounds)."""
    for _ in range(50):
        alive = find()
        if not alive:
            return
        for process in alive:
            try:
                process.kill()
            except psutil.NoSuchProcess:
                pass
        psutil.wait_procs(alive, timeout=5)
    left = find()
    if left:
        raise RuntimeError(f"these processes would not end: {left}")


def _hub_processes() -> list[psutil.Process]:
    """Processes of test hubs (JupyterHub, its proxy) found by their working folder or environment."""
    found = []
    for process in psutil.process_iter(["pid"]):
        if process.pid == os.getpid():
            continue
        try:
            cwd = process.cwd()
            cgroup = process.environ().get("MT_HUB_CGROUP", "")
        except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
            continue
        if cwd.startswith(f"/tmp/{TEST_PREFIX}hub-") or cgroup.startswith(f"{TEST_PREFIX}hub-"):
            found.append(process)
    return found


def _remove_hub_accounts(logins, cgroups) -> None:
    """Kills every process of ``logins``, removes ``cgroups`` and then the accounts.

    userdel refuses an account while a process of it runs, so the killed processes are waited
    for; a refusal is an error, not something to ignore (an account left behind stops the next
    run's fixture).
    """
    accounts = {}
    for login in logins:
        try:
            account = pwd.getpwnam(login)
        except KeyError:
            continue
        if account.pw_gecos == HUB_ACCOUNT:  # not made by the hub: not ours to touch
            accounts[login] = account
    _end_processes(lambda: _processes_of({account.pw_uid for account in accounts.values()}))
    for cgroup in cgroups:
        for controller in ("memory", "cpu"):
            base = Path("/sys/fs/cgroup", controller, _own_cgroup(controller).lstrip("/"), cgroup)
            for group in sorted(base.glob("*"), reverse=True) if base.is_dir() else []:
                if group.is_dir():
                    _rmdir_when_empty(group)
            if base.is_dir():
                _rmdir_when_empty(base)
    for login in accounts:
        done = subprocess.run(["userdel", login], capture_output=True, text=True, timeout=60)
        if done.returncode not in (0, 6):  # 6: the account is already gone
            raise RuntimeError(f"userdel {login} failed ({done.returncode}): {done.stderr.strip()}")


def other_test_hub_running() -> bool:
    """Whether a test hub (this process's or another's) holds ``HUB_LOCK``."""
    with open(HUB_LOCK, "a") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return True
        return False


def _remove_instructors_group_unless_used() -> None:
    """Removes the test hubs' instructors' group, unless another test hub still runs: they share it
    (the group of a hub stopped while another started went from under the other's config)."""
    with open(HUB_LOCK, "a") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return  # the last hub to stop removes it
        subprocess.run(["groupdel", TEST_INSTRUCTORS], capture_output=True, timeout=60)


def remove_leftovers_unless_busy() -> list[str]:
    """``remove_leftovers``, or nothing (with a warning) while another test hub runs on the machine:
    a test hub's accounts are not leftovers, and test hubs share the machine (``HUB_LOCK`` is shared)."""
    try:
        return remove_leftovers()
    except RuntimeError as error:
        warnings.warn(f"leftovers not swept: {error}", stacklevel=2)
        return []


def remove_leftovers() -> list[str]:
    """Removes what an earlier run that was killed (a CI timeout, a lost machine) could not: its
    hub and proxy, the hub's ``mtt-`` accounts and their processes, the test hubs' cgroups and
    folders under /tmp. Returns the logins it removed. Only the hub's own accounts (the test
    prefix and the hub's GECOS mark) are touched; while any test hub is alive (it holds
    ``HUB_LOCK``) nothing is, and this raises."""
    with open(HUB_LOCK, "a") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise RuntimeError("another test hub is running on this machine: nothing was removed") from None
        _end_processes(_hub_processes)
        logins = sorted(user.pw_name for user in pwd.getpwall()
                        if user.pw_name.startswith(TEST_PREFIX) and user.pw_gecos == HUB_ACCOUNT)
        cgroups = set()
        for controller in ("memory", "cpu"):
            base = Path("/sys/fs/cgroup", controller, _own_cgroup(controller).lstrip("/"))
            cgroups.update(group.name for group in base.glob(f"{TEST_PREFIX}hub-*") if group.is_dir())
        _remove_hub_accounts(logins, sorted(cgroups))
        subprocess.run(["groupdel", TEST_INSTRUCTORS], capture_output=True, timeout=60)
        for folder in Path("/tmp").glob(f"{TEST_PREFIX}hub-*"):
            if folder.is_dir():
                shutil.rmtree(folder, ignore_errors=True)
    return logins


def _own_cgroup(controller: str) -> str:
    for line in Path("/proc/self/cgroup").read_text().splitlines():
        _, controllers, path = line.split(":", 2)
        if controller in controllers.split(","):
            return path
    return "/"


def _rmdir_when_empty(group: Path) -> None:
    for _ in range(100):
        try:
            group.rmdir()
            return
        except FileNotFoundError:
            return
        except OSError:
            for pid in (group / "cgroup.procs").read_text().split():
                try:
                    os.kill(int(pid), signal.SIGKILL)
                except ProcessLookupError:
                    pass
            time.sleep(0.1)
    raise RuntimeError(f"cgroup {group} could not be removed")


#: What each student's kernel runs: build a skill, then three episodes with guidance whose slips
#: shrink (a student learning from the arrows), and one exercise check. Printed as one JSON line:
#: the teaching errors, the feedback latencies and where the numba cache is, also written to
#: ``episode-result.json`` in the student's home (read back through the contents API).
EPISODE_CODE = """
import json
import os

import numpy as np
from mt_widgets import SKILLS, Skill
from mt_widgets.core import PointTarget
from mt_widgets.widgets import EpisodeWidget
from mt_widgets.classroom import CheckFailed, ExerciseChecks, ProgressRecorder

base = SKILLS["sim-point"]
goal = np.array([0.6 + 0.05 * {number}, 1.1])
skill = Skill("class-reach", "Reach a point", base.plant, base.feature_map,
              theta=[[-1, 0, -1, 0, goal[0]], [0, -1, 0, -1, goal[1]]], start=base.start,
              target=PointTarget(tuple(goal)))
recorder = ProgressRecorder()
rng = np.random.default_rng({number})
errors, latencies = [], []
for index, slip in enumerate((1.0, 0.5, 0.2)):
    episode = EpisodeWidget(skill, seed=10 * {number} + index, guidance=True, episode_index=index, episodes_total=3)
    recorder.attach(episode, "hub-episode")
    for optimal in episode.optimal:
        episode.demonstrate(optimal + rng.normal(0, slip * {number} / 11, size=2))
        episode.next()
    errors.append(episode.result.theta_error)
    latencies.append(episode.result.feedback_latency_s)
checks = ExerciseChecks("a1_ridge_learner", recorder)
checks.true("ridge-fit", True, "")
try:
    checks.true("teaching-error", {number} % 3 != 0, "E: expected 0.316, got 0.1")
except CheckFailed:
    pass
summary = json.dumps({{"errors": errors, "latencies_s": latencies, "recorded": str(recorder.path),
                      "numba_cache": os.environ.get("NUMBA_CACHE_DIR")}})
with open("episode-result.json", "w") as file:
    file.write(summary)
print(summary)
"""
