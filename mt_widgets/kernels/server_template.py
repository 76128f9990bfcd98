"""A class's server template: one process that has imported a student's Jupyter server and kernel,
and forks each student's server as that student, with a kernel template of their own.

On the class hub (deploy/jupyterhub/jupyterhub_config.py) a student's server used to spend about
1.5 of its 2 CPU-seconds of start importing (jupyter_server, JupyterLab's server side, jsonschema,
tornado, JupyterHub's single-user extension), and their first kernel 2.2 CPU-seconds more
(ipykernel, numpy, numba, ipywidgets, this package): thirty students starting together on two
cores waited half a minute for the servers and twenty seconds more for a first episode
(docs/guide/scaling.md). The template imports all of it once; a fork starts with it in memory,
shared copy-on-write between every student's processes.

Run by the hub, as root: ``python -m mt_widgets.kernels.server_template SOCKET SERVERS KERNELS
PRELOAD NUMBA_PACKAGES BACKLOG`` (comma-separated lists: the server modules a request may run, the
kernel modules a student's kernel template may run, the modules to import first, the packages whose
cached numba functions are loaded; ``KERNELS`` are imported before everything else, as what they
set up, ``mt_hub_kernel``'s ipykernel without debugpy, must precede the rest; ``BACKLOG``: how many
spawns may wait for the template at once, the hub's concurrent spawn limit).
:class:`ServerTemplate` is the hub's side.

What keeps it safe (the template forks as root, and every student's server starts as its copy):

- **Only the hub asks.** The socket is 0600 in a 0700 folder of root's, and each connection's peer
  credentials must carry the template's own uid (root: the hub).
- **Nothing of one student reaches another.** The template forks *before* it reads a request: the
  request (the student's environment, with their API token) is read by the child, which becomes
  that student's server, so the template's own memory, which every later fork copies, never holds
  a request. The template is started with a minimal environment of its own (no hub secret) and a
  home, numba cache and matplotlib folder that are empty and root's.
- **The child is the student before it runs anything of theirs**: it joins the student's cgroups
  (as root: the groups' files are root's), sets their supplementary groups, gid and uid (real,
  effective and saved: it checks afterwards that it cannot become root again), and only then takes
  the request's environment and folder and runs the server module (one of ``SERVERS``, with the
  template's own Python). Neither uid nor gid may be 0. After the change of user the process is
  made dumpable again, as a process the student started themselves would be (Linux clears the flag
  on a change of user: the student's own tools could not read their own processes).
- **The student's kernels** come from a kernel template forked from their server at its start
  (``template.py``, serving their uid only, its socket in their private runtime folder): it runs as
  the student, in their cgroups, so a kernel never forks from anything but its owner's process.
- Every numba function imported by the template is pointed at the student's own cache folder
  (``NUMBA_CACHE_DIR``) in the child: a cache folder shared between students would let one plant
  compiled code that another loads.
- The template refuses to fork when it has a second thread (a fork copies a lock another thread
  holds) or when a preloaded module made a widget (it would be mute in every kernel).

The hub learns a server's pid at once (``{"pid": N}``) and, when it ends, its exit code
(``{"status": CODE}``): the template reaps its children at once, so a server's pid stops existing
when the server ends, as the hub's ``LocalProcessSpawner.poll`` expects.
"""

from __future__ import annotations

import asyncio
import ctypes
import json
import logging
import os
import socket
import sys
import tempfile
import threading

from . import template
from .provisioner import KernelTemplate, TemplateProcess, ask_template

#: linux/prctl.h
PR_SET_DUMPABLE = 4
#: The cgroup v1 and v2 mount a request's groups must be under.
CGROUP_ROOT = "/sys/fs/cgroup/"

log = logging.getLogger(__name__)


def _check_request(request: dict, server_modules: tuple[str, ...]) -> dict:
    """``request`` if it is a well-formed request to start a server as someone other than root."""
    argv, env, cwd = request.get("argv"), request.get("env"), request.get("cwd")
    if not (isinstance(argv, list) and len(argv) >= 3 and all(isinstance(a, str) for a in argv)):
        raise ValueError(f"request: argv: expected [python, '-m', module, ...], got {argv!r}")
    if argv[0] != sys.executable or argv[1] != "-m" or argv[2] not in server_modules:
        raise ValueError(f"request: argv: expected [{sys.executable!r}, '-m', one of {sorted(server_modules)}, ...], "
                         f"got {argv[:3]!r}")
    if not (isinstance(env, dict) and all(isinstance(k, str) and isinstance(v, str) for k, v in env.items())):
        raise ValueError("request: env: expected a mapping of strings to strings")
    if not isinstance(cwd, str):
        raise ValueError(f"request: cwd: expected a folder, got {cwd!r}")
    for name in ("uid", "gid"):
        value = request.get(name)
        if not (type(value) is int and value > 0):
            raise ValueError(f"request: {name}: expected a positive integer (never root's 0), got {value!r}")
    groups = request.get("groups")
    if not (isinstance(groups, list) and all(type(g) is int and g > 0 for g in groups)):
        raise ValueError(f"request: groups: expected a list of positive group ids (never root's 0), got {groups!r}")
    procs = request.get("cgroup_procs")
    if not (isinstance(procs, list) and all(
            isinstance(p, str) and p.startswith(CGROUP_ROOT) and p.endswith("/cgroup.procs")
            and ".." not in p.split("/") for p in procs)):
        raise ValueError(f"request: cgroup_procs: expected cgroup.procs files under {CGROUP_ROOT}, got {procs!r}")
    return request


def _become_user(request: dict) -> None:
    """Join the request's cgroups, then drop root for its user for good (checked)."""
    for path in request["cgroup_procs"]:
        with open(path, "w") as handle:
            handle.write(str(os.getpid()))
    uid, gid = request["uid"], request["gid"]
    os.setgroups(request["groups"])
    os.setresgid(gid, gid, gid)
    os.setresuid(uid, uid, uid)
    if os.getresuid() != (uid, uid, uid) or os.getresgid() != (gid, gid, gid):
        raise PermissionError(f"could not become uid {uid}, gid {gid}")
    try:
        os.setuid(0)
    except PermissionError:
        pass
    else:
        raise PermissionError("the server could become root again after the change of user")
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_DUMPABLE, 1, 0, 0, 0)


def _fork_kernel_template(kernel_modules: tuple[str, ...]) -> tuple[str, int, int]:
    """In a student's server, before it starts: a kernel template forked from it (``template.py``),
    listening in the student's runtime folder. Its socket, its pid, and the pipe's write end whose
    closing (the server's end) ends the template."""
    runtime = os.environ.get("JUPYTER_RUNTIME_DIR")
    folder = tempfile.mkdtemp(prefix="mt-kt-", dir=runtime if runtime and os.path.isdir(runtime) else None)
    path = os.path.join(folder, "s")
    listener = template.listen(path)
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:
        code = 1
        try:
            os.close(write_end)
            try:
                import setproctitle

                setproctitle.setproctitle("mt-widgets kernel template")
            except ImportError:
                pass
            template.serve(listener, kernel_modules, stop_fd=read_end)
            code = 0
        except BaseException:
            import traceback

            traceback.print_exc()
        finally:
            os._exit(code)
    os.close(read_end)
    listener.close()
    return path, pid, write_end


def _become_server(conn: socket.socket, closing: list, server_modules: tuple[str, ...],
                   kernel_modules: tuple[str, ...]) -> None:
    """In the forked child: read the request, become its user, start their kernel template, run
    their server. Never returns."""
    try:
        request = _check_request(template.read_line(conn), server_modules)
        conn.close()
        _become_user(request)
        template.start_child(closing, request["env"], request["cwd"], " ".join(request["argv"]))
        path, pid, _ = _fork_kernel_template(tuple(dict.fromkeys([*template.KERNEL_MODULES, *kernel_modules])))
        KernelTemplate.adopt(path, pid, list(kernel_modules))
    except BaseException:
        import traceback

        traceback.print_exc()
        sys.stderr.flush()
        os._exit(2)
    template.run_as_main(request["argv"][2], request["argv"][3:])


def serve(listener: socket.socket, server_modules: tuple[str, ...], kernel_modules: tuple[str, ...]) -> None:
    """Fork a server per connection from this process's own user (the hub) until standard input ends."""
    uid = os.getuid()
    selector, wake_read, wake_write = template.fork_loop(listener, 0)
    watchers: dict[int, socket.socket] = {}
    print(f"server template ready on {listener.getsockname()} (pid {os.getpid()})", file=sys.stderr, flush=True)
    running = True
    while running:
        for key, _ in selector.select():
            if key.data == "stop":
                if not os.read(0, 4096):
                    running = False
            elif key.data == "wake":
                template.drain(wake_read)
                template._reap(watchers)
            else:
                conn, _ = listener.accept()
                try:
                    if template._peer_uid(conn) != uid:
                        raise PermissionError("refused: the request came from another user than the hub's")
                    if threading.active_count() != 1:
                        raise RuntimeError("the template has a thread: forking it would copy a lock held")
                except (OSError, RuntimeError) as error:
                    template._send(conn, {"error": str(error)})
                    conn.close()
                    continue
                pid = os.fork()
                if pid == 0:
                    _become_server(conn, [listener, wake_read, wake_write, *watchers.values()],
                                   server_modules, kernel_modules)
                template._send(conn, {"pid": pid})
                watchers[pid] = conn
                template._reap(watchers)
    listener.close()


def main(argv: list[str] | None = None) -> None:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 6 or not args[5].isdigit():
        raise SystemExit("usage: python -m mt_widgets.kernels.server_template SOCKET SERVER_MODULES "
                         "KERNEL_MODULES PRELOAD NUMBA_PACKAGES BACKLOG")
    path, backlog = args[0], int(args[5])
    servers, kernels, preload, numba_packages = ([name for name in arg.split(",") if name] for arg in args[1:5])
    template.preload([*kernels, *servers, *preload])
    made = template._widgets_made()
    if made:
        raise SystemExit(f"server template: importing {preload} made widgets ({made}); preload modules that make none")
    _system_facts_once()
    _kernel_provisioners_once()
    template.settle(numba_packages)
    serve(template.listen(path, backlog), tuple(servers), tuple(kernels))


def _system_facts_once() -> None:
    """Every server's web app asks jupyter_server for its system facts at start (its version, Python,
    platform, and the git commit of the folder it is installed in, found by running ``git rev-parse``
    in a subprocess when that folder lies in a git checkout, as a clone's ``.venv`` does): a fork and
    exec of git per student's server, for facts that are the template's own and the same for all.
    They are gathered once here, without git (nothing here runs git as root), and every fork shares
    them."""
    serverapp = sys.modules.get("jupyter_server.serverapp")
    sysinfo = sys.modules.get("jupyter_server._sysinfo")
    if serverapp is None or sysinfo is None or not callable(getattr(serverapp, "get_sys_info", None)):
        return
    sysinfo.pkg_commit_hash = lambda pkg_path: ("", "")
    facts = sysinfo.get_sys_info()
    serverapp.get_sys_info = lambda: dict(facts)


def _kernel_provisioners_once() -> None:
    """A server's first kernel asks jupyter_client which kernel provisioners are installed, and
    jupyter_client answers by reading the entry points of every installed distribution (every
    package's metadata files), about a twentieth of a forked server's start (py-spy,
    benchmarks/bench_hub.py). The answer is the installation's, the same for every student (a
    server runs the template's Python and packages): read once here, every fork shares it."""
    factory = sys.modules.get("jupyter_client.provisioning.factory")
    if factory is None or not callable(getattr(factory.KernelProvisionerFactory, "_get_all_provisioners", None)):
        return
    installed = factory.KernelProvisionerFactory._get_all_provisioners()
    factory.KernelProvisionerFactory._get_all_provisioners = staticmethod(lambda: installed)


def untrusted(folder: str) -> str | None:
    """Why ``folder`` may not be read by a root process that unpickles it, or None: everything in it
    must be this process's user's (root's, on the hub) and writable by nobody else."""
    me = os.geteuid()
    if not os.path.isdir(folder):
        return "not a folder"
    for where, folders, files in os.walk(folder):
        for path in [where, *(os.path.join(where, name) for name in folders + files)]:
            info = os.lstat(path)
            if info.st_uid != me or info.st_mode & 0o022:
                return f"{path} is not only its owner's to write (uid {info.st_uid}, mode {oct(info.st_mode & 0o777)})"
    return None


def somaxconn() -> int | None:
    """Linux's cap on a listening socket's backlog (``net.core.somaxconn``), or None where unreadable."""
    try:
        with open("/proc/sys/net/core/somaxconn") as handle:
            return int(handle.read())
    except (OSError, ValueError):
        return None


class ServerTemplate(TemplateProcess):
    """The hub's side: starts the template (as the hub's user) and asks it for servers.

    Args:
        python: the Python students' servers run (the template runs it too).
        servers: the server modules a request may run (``jupyterhub.singleuser``).
        kernels: kernel modules students' kernel specs run (``mt_hub_kernel``).
        preload: modules to import before forking.
        env: the template's environment (the hub adds an empty home and cache folders of its own).
        numba_cache: a warm numba cache (deploy/jupyterhub/warm_numba_cache.py) whose compiled
            versions of ``numba_packages``' functions the template loads before forking; used only
            when it is root's and nobody else may write it (numba unpickles its index), else None.
        numba_packages: packages whose cached functions are loaded (``mt_widgets``).
        backlog: spawns that may wait for the template's answer at once: the hub's concurrent spawn
            limit (``jupyterhub_config.py`` passes it), so that a class spawned at once all waits in
            the socket's queue. Linux caps it at ``net.core.somaxconn`` (logged when lower); a spawn
            beyond it waits and tries again (``ask_template``).
    """

    what = "server template"

    def __init__(self, python: str, servers: list[str], kernels: list[str], preload: list[str], env: dict,
                 numba_cache: str | None = None, numba_packages: tuple[str, ...] = ("mt_widgets",),
                 backlog: int = template.KERNEL_BACKLOG):
        if type(backlog) is not int or backlog < 1:
            raise ValueError("backlog: expected a positive integer (the hub's concurrent spawn limit), "
                             f"got {backlog!r}")
        cap = somaxconn()
        if cap is not None and backlog > cap:
            log.warning("server template: a backlog of %d is capped at net.core.somaxconn = %d; spawns beyond it "
                        "wait and try again", backlog, cap)
        self.backlog = backlog
        self.python, self.servers, self.kernels, self.preload = str(python), servers, kernels, preload
        self.folder = tempfile.mkdtemp(prefix="mt-st-")  # 0700, the hub's
        self.socket = os.path.join(self.folder, "s")
        home = os.path.join(self.folder, "home")
        os.mkdir(home, 0o700)
        problem = untrusted(numba_cache) if numba_cache else "none given"
        if numba_cache and problem:
            log.warning("server template: not loading numba's cache %s (%s)", numba_cache, problem)
        self.numba_packages = list(numba_packages) if not problem else []
        self.env = {**env, "HOME": home, "NUMBA_CACHE_DIR": numba_cache if not problem else os.path.join(home, "numba"),
                    "MPLCONFIGDIR": os.path.join(home, "matplotlib")}

    def command(self) -> tuple[list[str], dict | None, str]:
        return ([self.python, "-m", "mt_widgets.kernels.server_template", self.socket, ",".join(self.servers),
                 ",".join(self.kernels), ",".join(self.preload), ",".join(self.numba_packages), str(self.backlog)],
                self.env, self.env["HOME"])

    async def fork(self, request: dict, wait_s: float = 60.0) -> int | None:
        """The pid of a server forked for ``request`` (see ``_check_request``), or None (the reason
        logged; the caller starts the server the usual way)."""
        self.ensure_started()
        answer = await ask_template(self.what, self, request, wait_s)
        if answer is None:
            return None
        pid, reader, writer = answer
        # The connection stays open until the server ends (the template then writes its status):
        # read it so that the hub's log says how a forked server ended.
        asyncio.ensure_future(self._report_end(pid, reader, writer))
        return pid

    async def _report_end(self, pid: int, reader, writer) -> None:
        line = await reader.readline()
        writer.close()
        if line:
            status = json.loads(line).get("status")
            if status not in (0, None):
                log.warning("forked server %d ended with %s", pid, status)


if __name__ == "__main__":
    main()
