"""A kernel template: one process that has imported a kernel's heavy modules and forks kernels.

A Python kernel spends about 2.2 s importing ipykernel, numpy, numba, ipywidgets, ipycanvas and
this package's widgets before it runs a cell (measured on this project's 2-core machine at load
average 3.4, with six other engineers' work running: ipykernel 0.7 s, numba 0.8 s, numpy 0.2 s,
the widgets 0.5 s). A template imports them once; a kernel forked from it starts with all of
them in memory, shared copy-on-write with the template and its sibling kernels, in
milliseconds. ``mt_widgets/kernels/provisioner.py`` asks it for kernels.

Run as ``python -m mt_widgets.kernels.template SOCKET MODULES`` (``MODULES``: comma-separated
names to import; the kernel modules a request may name are ``ipykernel_launcher`` and any of
``MODULES``). The template

- listens on the Unix socket ``SOCKET`` (made 0600, in a folder the caller keeps private) and
  serves only its own user: a request's peer credentials (SO_PEERCRED) must carry the template's
  uid. A request runs code as that user, which its peer can do anyway. It never changes user:
  it runs as the server that started it (on the class hub, the student: their uid, gid,
  groups and cgroups, set before their server ran anything), and so does every kernel it forks,
  with nothing to drop and nothing to get wrong;
- per request (one JSON line: ``argv`` of the kernel spec, ``env``, ``cwd``) forks; the child
  becomes its own session (so the server's interrupt, a signal to the kernel's process group,
  reaches only that kernel), takes the request's environment and folder, re-reads numba's
  configuration from that environment, reseeds numpy's global generator (a fork copies it, and
  sibling kernels would otherwise draw the same numbers) and runs the kernel module as
  ``__main__``. ZeroMQ contexts, sockets and threads are all made by the kernel after the fork:
  the template never creates one (it checks, below, that it has no other thread when it forks).
  Functions numba compiles with ``cache=True`` that the template imported keep the cache folder
  of the template's environment, which is the server's and so the kernel's in both deployments
  (on the hub, the student's own ``NUMBA_CACHE_DIR``);
- answers ``{"pid": N}``, keeps the connection and writes ``{"status": CODE}`` when that kernel
  ends (its exit code, or minus the signal that ended it), so the server learns a kernel's end
  as it does from a child process;
- ends when its standard input closes (the server that started it went away); the kernels it
  forked end with it (ipykernel's parent poller watches the template), as launched kernels end
  with their server.
"""

from __future__ import annotations

import importlib
import json
import os
import runpy
import selectors
import signal
import socket
import struct
import sys
import threading
import time

#: Kernel modules a request may always name: the standard Python kernel's.
KERNEL_MODULES = ("ipykernel_launcher",)
#: What a request may be at most (a kernel's environment is a few kilobytes).
MAX_REQUEST_BYTES = 1 << 20
#: Connections a kernel template's socket holds waiting before one is accepted: one server's
#: kernels, a handful at once. A server template is given its hub's spawn limit instead
#: (``server_template.py``): a request beyond the backlog is refused at connect, and the asker
#: retries (``provisioner.ask_template``).
KERNEL_BACKLOG = 64


def preload(modules: list[str]) -> list[str]:
    """Import ``modules``, in order, then ipykernel's application, before any fork; the names that
    failed. Order matters: a kernel module such as the hub's ``mt_hub_kernel`` keeps debugpy out
    of ipykernel's import, so it comes first."""
    failed = []
    for name in [*modules, "ipykernel.kernelapp"]:
        try:
            importlib.import_module(name)
        except Exception as error:  # a module that cannot import is a kernel that imports it later
            print(f"kernel template: could not preload {name}: {error!r}", file=sys.stderr, flush=True)
            failed.append(name)
    return failed


def _widgets_made() -> list[str]:
    """The classes of the ipywidgets widgets that exist in this process, but for those a forked
    kernel makes again (``_remake_canvas_manager``)."""
    # ipywidgets 8's registry of live widgets (``Widget.widgets``, deprecated, reads the same).
    module = sys.modules.get("ipywidgets.widgets.widget")
    registry = getattr(module, "_instances", {}) if module is not None else {}
    remade = _canvas_manager_remade()
    return sorted({type(instance).__name__ for instance in registry.values() if instance is not remade})


def _canvas_manager_remade():
    """ipycanvas's canvas manager made at its import, when a forked kernel can make it again: the
    one widget every canvas draws through (ipycanvas 0.14: the module's ``_CANVAS_MANAGER``, the
    default of ``_CanvasBase._canvas_manager``); None when ipycanvas is not imported or differs."""
    canvas = sys.modules.get("ipycanvas.canvas")
    if canvas is None or not hasattr(canvas, "_CanvasBase") or not hasattr(canvas, "_CANVAS_MANAGER"):
        return None
    trait = canvas._CanvasBase.class_traits().get("_canvas_manager")
    if trait is None or trait.default_value is not canvas._CANVAS_MANAGER:
        return None
    return canvas._CANVAS_MANAGER


def _remake_canvas_manager() -> None:
    """In a forked kernel, once it has a kernel: a canvas manager of its own, with a real comm.
    The template's was made at ipycanvas's import, before any kernel: its comm goes nowhere, and
    every canvas drawing through it would stay blank."""
    stale = _canvas_manager_remade()
    if stale is None:
        return
    canvas = sys.modules["ipycanvas.canvas"]
    fresh = canvas._CanvasManager()
    canvas._CANVAS_MANAGER = fresh
    canvas._CanvasBase.class_traits()["_canvas_manager"].default_value = fresh
    # Out of ipywidgets' registry of live widgets (a page asking for every widget's state would
    # get it); not closed: its comm belongs to no comm manager, and closing it would ask the
    # kernel's to forget a comm it never had.
    sys.modules["ipywidgets.widgets.widget"]._instances.pop(stale.comm.comm_id, None)


class _SysWithoutModuleList:
    """``sys`` as ipykernel's kernel module sees it while a forked kernel without a debugger is made.

    ``IPythonKernel.__init__`` lists the file of every loaded module, for debugpy's "just my code",
    and nothing else reads that list. A kernel forked from a template holds every module the
    template imported (about 2,000 with a server's): reading each one's ``__file__`` writes its
    reference count, and so copies page after page the kernel had shared with its template,
    copy-on-write (13 ms of CPU a kernel measured in a bare fork, an eighth of a hub kernel's
    start in a lecture's py-spy profile). Where debugpy is absent the list is never read, so
    here ``sys.modules`` looks empty to that one line; every other name is the real ``sys``'s.
    """

    @property
    def modules(self) -> dict:
        return {}

    def __getattr__(self, name):
        return getattr(sys, name)


def _lighter_kernel_init() -> None:
    """Make the forked kernel's ``IPythonKernel`` without the unread module list (above), and have
    ipywidgets register its comm targets once the kernel exists.

    ipywidgets registers ``jupyter.widget`` and ``jupyter.widget.control`` with the kernel's comm
    manager when it is imported inside a kernel, and the template imported it before there was
    one. Without ``jupyter.widget.control`` a page's widget manager cannot ask for every widget's
    state in one message (it falls back to a round trip per widget), and without
    ``jupyter.widget`` a widget made by the page's front end has no kernel side.
    """
    try:
        from ipykernel import ipkernel
        from ipykernel.kernelapp import IPKernelApp
    except ImportError:  # a kernel module other than ipykernel's
        return

    init_kernel = IPKernelApp.init_kernel

    def init_kernel_lighter(app):
        # Asked here, once the kernel module has run (as ipykernel itself asks): a module such as
        # the hub's mt_hub_kernel keeps debugpy out when it runs.
        from ipykernel import debugger

        skip_module_list = not debugger._is_debugpy_available
        if skip_module_list:
            ipkernel.sys = _SysWithoutModuleList()
        try:
            init_kernel(app)
        finally:
            ipkernel.sys = sys
        if "ipywidgets" in sys.modules:
            sys.modules["ipywidgets"].register_comm_target()
            _remake_canvas_manager()

    IPKernelApp.init_kernel = init_kernel_lighter


def _peer_uid(conn: socket.socket) -> int:
    creds = conn.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, struct.calcsize("3i"))
    return struct.unpack("3i", creds)[1]


def read_line(conn: socket.socket) -> dict:
    """One request: a JSON object on one line, of at most ``MAX_REQUEST_BYTES``."""
    data = b""
    while not data.endswith(b"\n"):
        chunk = conn.recv(65536)
        if not chunk:
            raise ValueError("request: the connection closed before a full line")
        data += chunk
        if len(data) > MAX_REQUEST_BYTES:
            raise ValueError(f"request: expected at most {MAX_REQUEST_BYTES} bytes")
    request = json.loads(data)
    if not isinstance(request, dict):
        raise ValueError("request: expected a JSON object")
    return request


def _read_request(conn: socket.socket) -> dict:
    request = read_line(conn)
    argv, env, cwd = request.get("argv"), request.get("env"), request.get("cwd")
    if not (isinstance(argv, list) and len(argv) >= 3 and all(isinstance(a, str) for a in argv)):
        raise ValueError(f"request: argv: expected [python, '-m', module, ...], got {argv!r}")
    if not (isinstance(env, dict) and all(isinstance(k, str) and isinstance(v, str) for k, v in env.items())):
        raise ValueError("request: env: expected a mapping of strings to strings")
    if not isinstance(cwd, str):
        raise ValueError(f"request: cwd: expected a folder, got {cwd!r}")
    return request


def start_child(closing: list, env: dict, cwd: str, title: str) -> None:
    """In a forked child, before it runs anything of its own: it leaves what it inherited from the
    template (the template's sockets, signal handlers, standard input, session), takes ``env`` and
    ``cwd``, and re-reads what the heavy modules took from the template's environment at import.
    Shared by the kernels forked here and the servers forked by ``server_template.py``."""
    signal.set_wakeup_fd(-1)  # before its pipe closes: a signal must not write to a closed socket
    for fileobj in closing:
        fileobj.close()
    for signum in (signal.SIGCHLD, signal.SIGINT, signal.SIGTERM, signal.SIGPIPE):
        signal.signal(signum, signal.SIG_DFL)
    os.setsid()
    # The command as its process title (ps, psutil): what the server asked for (for a kernel, with
    # its connection file, which tools find kernels by) instead of the template's.
    try:
        import setproctitle
    except ImportError:
        pass
    else:
        setproctitle.setproctitle(title)
    # The template's standard input is the pipe whose end tells it its server went away.
    devnull = os.open(os.devnull, os.O_RDONLY)
    os.dup2(devnull, 0)
    os.close(devnull)
    os.chdir(cwd)
    os.environ.clear()
    os.environ.update(env)
    if "numba" in sys.modules:
        # NUMBA_CACHE_DIR and the like are read at numba's import: read them again from the
        # child's environment (on the hub, the student's own cache folder), and point every
        # cached function imported so far there too (a function's cache folder is chosen when it
        # is defined, from the template's environment).
        # A child whose cache folder is its template's (a student's kernel forked from their own
        # kernel template) keeps the functions' caches as they are: pointing them again was a tenth
        # of a kernel's CPU in a lecture's first minute (py-spy, benchmarks/bench_hub.py).
        config = sys.modules["numba"].core.config
        cache_folder = config.CACHE_DIR
        config.reload_config()
        if config.CACHE_DIR != cache_folder:
            _point_numba_caches_here()
    if "numpy" in sys.modules:
        sys.modules["numpy"].random.seed()


def _cached_numba_functions(package: str | None = None) -> list:
    """numba functions compiled with ``cache=True`` in the modules imported (of ``package`` only,
    when given): module-level names, where this package defines them."""
    from numba.core.caching import NullCache
    from numba.core.dispatcher import Dispatcher

    found = {}
    for name, module in list(sys.modules.items()):
        if package is not None and name != package and not name.startswith(package + "."):
            continue
        for value in list(getattr(module, "__dict__", {}).values()):
            if isinstance(value, Dispatcher) and not isinstance(value._cache, NullCache):
                found[id(value)] = value
    return list(found.values())


#: The cached numba functions the template imported (``settle``), so that a forked child finds them
#: without walking every module's globals: a walk touches (and so copies) every object's page.
_CACHED_FUNCTIONS: list = []


def _point_numba_caches_here() -> None:
    for function in _CACHED_FUNCTIONS or _cached_numba_functions():
        function.enable_caching()


def load_numba_caches(package: str) -> int:
    """Loads, from numba's cache folder (``NUMBA_CACHE_DIR``), every compiled version of
    ``package``'s cached functions imported so far, for this machine's CPU; how many.

    A forked process then has that machine code in memory, shared with its siblings, instead of
    each loading it again (0.4 CPU-seconds of a student's first episode, measured: 0.53 against
    0.03). Only the cache index and files numba itself would read are read (numba's own loader:
    ``Dispatcher.compile`` of a signature the index lists finds it there); the folder must be
    trusted as much as the package's code, since numba unpickles its index."""
    loaded = 0
    for function in _cached_numba_functions(package):
        magic = function.targetctx.codegen().magic_tuple()
        try:
            # numba's index (numba/core/caching.py, 0.59 to 0.68): {(argument types, codegen's magic
            # tuple, code hashes): data file}. Another numba may differ: then nothing is preloaded
            # and each kernel loads its own, as without a template.
            index = function._cache._cache_file._load_index()
        except AttributeError as error:
            print(f"kernel template: numba's cache index unreadable ({error}); nothing preloaded",
                  file=sys.stderr, flush=True)
            return loaded
        for key in index:
            if key[1] == magic:
                function.compile(key[0])
                loaded += 1
    return loaded


def run_as_main(module: str, args: list[str]) -> None:
    """Runs ``module`` as ``__main__`` with ``args``, then ends the process with its exit code
    (never returns: a forked child must not fall back into its template's loop)."""
    code = 1
    try:
        sys.argv = [module, *args]
        runpy.run_module(module, run_name="__main__", alter_sys=True)
        code = 0
    except SystemExit as stop:
        code = stop.code if isinstance(stop.code, int) else (0 if stop.code is None else 1)
    except BaseException:
        import traceback

        traceback.print_exc()
    finally:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


def _become_kernel(request: dict, closing: list) -> None:
    """In the forked child: the kernel of ``request``. Never returns."""
    try:
        start_child(closing, request["env"], request["cwd"], " ".join(request["argv"]))
        # ipykernel ends when the process that started it goes away (its parent poller); that
        # process is now the template, which ends with the server.
        # (ipykernel read JPY_PARENT_PID when the template imported it, so it is also passed on
        # the command line.)
        os.environ["JPY_PARENT_PID"] = str(os.getppid())
        _lighter_kernel_init()
    except BaseException:
        import traceback

        traceback.print_exc()
        os._exit(1)
    run_as_main(request["argv"][2], [*request["argv"][3:], f"--IPKernelApp.parent_handle={os.getppid()}"])


def fork_loop(listener: socket.socket, stop_fd: int):
    """What a template's loop waits on: ``listener`` ("listen"), a wakeup socket that SIGCHLD writes
    to ("wake": children are reaped in the loop, never in a signal handler) and ``stop_fd``
    ("stop"). SIGINT is ignored: a Ctrl-C is for the server or hub that started the template.
    Returns the selector and the wakeup socket's two ends (a fork closes both)."""
    wake_read, wake_write = socket.socketpair()
    wake_read.setblocking(False)
    wake_write.setblocking(False)
    signal.set_wakeup_fd(wake_write.fileno(), warn_on_full_buffer=False)
    signal.signal(signal.SIGCHLD, lambda *_: None)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    selector = selectors.DefaultSelector()
    selector.register(listener, selectors.EVENT_READ, "listen")
    selector.register(wake_read, selectors.EVENT_READ, "wake")
    selector.register(stop_fd, selectors.EVENT_READ, "stop")
    return selector, wake_read, wake_write


def drain(wake_read: socket.socket) -> None:
    try:
        while wake_read.recv(4096):
            pass
    except BlockingIOError:
        pass


def listen(path: str, backlog: int = KERNEL_BACKLOG) -> socket.socket:
    """A Unix socket listening at ``path``, readable and writable by this user only, holding at most
    ``backlog`` connections not yet accepted (Linux caps it at ``net.core.somaxconn``)."""
    if type(backlog) is not int or backlog < 1:
        raise ValueError(f"backlog: expected a positive integer, got {backlog!r}")
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    old_umask = os.umask(0o177)
    try:
        listener.bind(path)
    finally:
        os.umask(old_umask)
    listener.listen(backlog)
    return listener


def serve(listener: socket.socket, kernel_modules: tuple[str, ...], stop_fd: int = 0) -> None:
    """Serve fork requests on ``listener`` until ``stop_fd`` (standard input: a pipe from the
    server that started the template) reaches its end."""
    uid = os.getuid()
    path = listener.getsockname()
    selector, wake_read, wake_write = fork_loop(listener, stop_fd)
    watchers: dict[int, socket.socket] = {}  # kernel pid -> the connection that asked for it
    print(f"kernel template ready on {path} (pid {os.getpid()})", file=sys.stderr, flush=True)
    running = True
    while running:
        for key, _ in selector.select():
            if key.data == "stop":
                if not os.read(stop_fd, 4096):
                    running = False
            elif key.data == "wake":
                drain(wake_read)
                _reap(watchers)
            else:
                conn, _ = listener.accept()
                try:
                    if _peer_uid(conn) != uid:
                        raise PermissionError("refused: the request came from another user")
                    request = _read_request(conn)
                    if request["argv"][1] != "-m" or request["argv"][2] not in kernel_modules:
                        raise ValueError(f"request: argv: expected '-m' and one of {sorted(kernel_modules)}, "
                                         f"got {request['argv'][1:3]}")
                    if threading.active_count() != 1:
                        raise RuntimeError("the template has a thread: forking it would copy a lock held")
                except (OSError, ValueError, RuntimeError) as error:
                    _send(conn, {"error": str(error)})
                    conn.close()
                    continue
                pid = os.fork()
                if pid == 0:
                    inherited = [listener, wake_read, wake_write, conn, *watchers.values()]
                    if stop_fd != 0:  # the kernel's standard input is replaced anyway
                        inherited.append(_Descriptor(stop_fd))
                    _become_kernel(request, inherited)
                _send(conn, {"pid": pid})
                watchers[pid] = conn
                _reap(watchers)
    listener.close()
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass


class _Descriptor:
    """A bare file descriptor that a forked child closes with the template's sockets."""

    def __init__(self, fd: int):
        self.fd = fd

    def close(self) -> None:
        os.close(self.fd)


def _send(conn: socket.socket, message: dict) -> None:
    try:
        conn.sendall(json.dumps(message).encode() + b"\n")
    except OSError:
        pass  # the server went away: the kernel's end is nobody's news


def _reap(watchers: dict[int, socket.socket]) -> None:
    while True:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return
        conn = watchers.pop(pid, None)
        if conn is not None:
            _send(conn, {"status": os.waitstatus_to_exitcode(status)})
            conn.close()


def main(argv: list[str] | None = None) -> None:
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 2:
        raise SystemExit("usage: python -m mt_widgets.kernels.template SOCKET MODULE[,MODULE...]")
    path, modules = args[0], [name for name in args[1].split(",") if name]
    preload(modules)
    made = _widgets_made()
    if made:
        # A widget made here has no kernel (its comm is a dummy): in every kernel forked from here
        # it would be mute, and a page drawing through it (ipycanvas's canvas manager) would
        # never draw. Refusing makes the server start its kernels the usual way, logged.
        raise SystemExit(f"kernel template: importing {modules} made widgets ({made}); preload modules "
                         "that make none (MT_KERNEL_TEMPLATE_PRELOAD)")
    # This user's own numba cache (NUMBA_CACHE_DIR, the server's): what earlier kernels compiled.
    settle(["mt_widgets"] if "mt_widgets" in sys.modules else [])
    serve(listen(path), tuple(dict.fromkeys([*KERNEL_MODULES, *modules])))


def settle(numba_packages: list[str]) -> None:
    """The template's last steps before it forks: ``numba_packages``' compiled functions loaded
    from numba's cache (``load_numba_caches``), then every object it holds frozen out of Python's
    garbage collector. A collection in the template would write to the pages of every object it
    visits, and each fork would then copy them; frozen, they stay shared (about 25 MiB less per
    forked kernel, measured below in docs/guide/scaling.md)."""
    import gc

    for package in numba_packages:
        started = time.perf_counter()
        loaded = load_numba_caches(package)
        cache = os.environ.get("NUMBA_CACHE_DIR") or "numba's default cache"
        print(f"template: {loaded} compiled versions of {package}'s functions loaded from {cache} in "
              f"{time.perf_counter() - started:.1f} s", file=sys.stderr, flush=True)
    _CACHED_FUNCTIONS[:] = _cached_numba_functions() if "numba" in sys.modules else []
    gc.collect()
    gc.freeze()


if __name__ == "__main__":
    main()
