"""Kernels forked from a template (``template.py``), for Jupyter servers and Voila alike.

``ForkingProvisioner`` is jupyter_client's documented extension point for launching a kernel
another way (a ``KernelProvisionerBase``; here a ``LocalProvisioner`` whose launch differs): it
writes the connection file as usual, then asks the server's template to fork the kernel with
that file, the kernel's environment and folder. ``ForkingKernelManager`` makes every kernel of a
server use it (``c.MultiKernelManager.kernel_manager_class``), without an entry point to install:
the study and demo pages' Voila (deploy/voila/voila.py) names it.

A kernel is forked only when its spec runs this server's own Python with ``-m`` and a module
the template may run (``ipykernel_launcher``, or one named in ``MT_KERNEL_TEMPLATE_MODULES``,
such as the hub's ``mt_hub_kernel``); any other kernel starts as jupyter_client starts it. When
the template is not there (it died, or cannot start) the kernel starts the usual way too, with a
warning in the server's log, and a new template is started for the next kernel; a template still
importing is waited for (at most ``MT_KERNEL_TEMPLATE_WAIT``, 60 s), since a fork after it is
still sooner than a cold start competing with it for the cores.

Signals, interrupt, restart and shutdown go through ``LocalProvisioner``'s code unchanged: the
forked kernel leads its own process group, as a launched kernel does, and ``ForkedProcess``
answers ``poll``/``wait``/``send_signal`` as a ``Popen`` would, its exit code coming from the
template, which reaps it. A restart asks for a fresh fork.

Settings (environment of the server): ``MT_KERNEL_TEMPLATE`` (``on``; ``off`` starts every
kernel the usual way), ``MT_KERNEL_TEMPLATE_PRELOAD`` (modules the template imports; by default
numpy, numba, ipywidgets, ``mt_widgets``, its study, widgets and study pages: no module whose
import makes a widget, ipycanvas's canvas manager excepted).
"""

from __future__ import annotations

import asyncio
import atexit
import json
import logging
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path

from jupyter_client.provisioning import LocalProvisioner
from jupyter_server.services.kernels.kernelmanager import ServerKernelManager

# No module whose import makes a widget: a widget made in the template has no kernel to talk to,
# and forked it would stay mute. The one exception is ipycanvas's canvas manager (every canvas
# draws through it), which each forked kernel makes again once it has a kernel (template.py);
# the template refuses to serve when a preloaded module made any other widget.
DEFAULT_PRELOAD = ("numpy", "numba", "ipywidgets", "mt_widgets", "mt_widgets.study", "mt_widgets.widgets",
                   "mt_widgets.apps.study")
#: The exit code reported for a kernel whose end the template could not report (it died first).
UNKNOWN_EXIT = -1

log = logging.getLogger(__name__)


def _setting(name: str, default: str) -> str:
    return os.environ.get(name, default)


class TemplateProcess:
    """A template process this process starts (``command``), whose standard input is a pipe: when
    this process ends, so does the template. Started once, started again when found dead."""

    #: What the log calls it.
    what = "template"
    socket: str
    process = None
    started_at = 0.0

    def command(self) -> tuple[list[str], dict | None, str]:
        """The template's command, environment (None: this process's) and folder."""
        raise NotImplementedError

    def ensure_started(self) -> None:
        if self.process is not None and self.process.poll() is None:
            return
        if self.process is not None:
            log.warning("%s (pid %s) ended with %s: starting a new one; until it is ready, what it forks "
                        "starts the usual way", self.what, self.process.pid, self.process.returncode)
        if os.path.exists(self.socket):
            os.unlink(self.socket)
        argv, env, cwd = self.command()
        self.process = subprocess.Popen(argv, stdin=subprocess.PIPE, env=env, cwd=cwd, start_new_session=True)
        self.started_at = time.monotonic()

    def stop(self) -> None:
        if self.process is not None and self.process.poll() is None and self.process.stdin is not None:
            self.process.stdin.close()
            try:
                self.process.wait(5)
            except subprocess.TimeoutExpired:
                self.process.kill()


class KernelTemplate(TemplateProcess):
    """This server's template process: started once, restarted when found dead."""

    what = "kernel template"

    _shared: KernelTemplate | None = None

    def __init__(self, modules: list[str], folder: str | None = None):
        self.modules = modules
        self.folder = tempfile.mkdtemp(prefix="mt-kt-", dir=folder)  # 0700: only this user reaches the socket
        self.socket = os.path.join(self.folder, "s")
        self.process: subprocess.Popen | None = None
        self.started_at = 0.0

    def ensure_started(self) -> None:
        os.makedirs(self.folder, mode=0o700, exist_ok=True)   # removed by an earlier stop
        super().ensure_started()

    def stop(self) -> None:
        """Ends the template and removes its socket's folder, made for it alone (an adopted
        template's folder is the server template's, which removes its own)."""
        super().stop()
        if not isinstance(self.process, ChildProcess):
            shutil.rmtree(self.folder, ignore_errors=True)

    @classmethod
    def adopt(cls, socket_path: str, pid: int, modules: list[str]) -> KernelTemplate:
        """Make the template already listening at ``socket_path``, forked by this process as ``pid``
        (``server_template.py`` forks one in each student's server), this server's template."""
        adopted = cls.__new__(cls)
        adopted.modules = list(modules)
        adopted.folder = os.path.dirname(socket_path)
        adopted.socket = socket_path
        adopted.process = ChildProcess(pid)
        adopted.started_at = time.monotonic()
        cls._shared = adopted
        return adopted

    @classmethod
    def adopted(cls) -> bool:
        """Whether this server was given a template (``adopt``)."""
        return cls._shared is not None and isinstance(cls._shared.process, ChildProcess)

    @classmethod
    def shared(cls) -> KernelTemplate | None:
        """The server's template, started at the first call; None when switched off."""
        if _setting("MT_KERNEL_TEMPLATE", "on") == "off":
            return None
        if cls._shared is None:
            # Kernel modules first: what they set up (mt_hub_kernel: no debugpy) precedes the rest.
            modules = [m for m in _setting("MT_KERNEL_TEMPLATE_MODULES", "").split(",") if m]
            modules += [m for m in _setting("MT_KERNEL_TEMPLATE_PRELOAD", ",".join(DEFAULT_PRELOAD)).split(",") if m]
            # A socket's path has at most 107 bytes: the runtime folder if short enough, else /tmp.
            runtime = os.environ.get("JUPYTER_RUNTIME_DIR")
            folder = runtime if runtime and len(runtime) < 80 and os.path.isdir(runtime) else None
            cls._shared = cls(list(dict.fromkeys(modules)), folder)
            atexit.register(cls._shared.stop)
        cls._shared.ensure_started()
        return cls._shared

    def command(self) -> tuple[list[str], dict | None, str]:
        home = os.path.expanduser("~")
        return ([sys.executable, "-m", "mt_widgets.kernels.template", self.socket, ",".join(self.modules)],
                None, home if os.path.isdir(home) else "/")

    def serves(self, argv: list[str]) -> bool:
        """Whether a kernel spec's command is one this template can fork."""
        return (len(argv) >= 3 and argv[1] == "-m"
                and argv[2] in ("ipykernel_launcher", *self.modules)
                and os.path.abspath(argv[0]) in {sys.executable, os.path.join(sys.prefix, "bin", "python"),
                                                 os.path.join(sys.prefix, "bin", Path(sys.executable).name)})

    async def fork(self, argv: list[str], env: dict, cwd: str) -> ForkedProcess | None:
        """A kernel forked with this command, environment and folder, or None (the reason logged)."""
        request = {"argv": list(argv), "env": {str(k): str(v) for k, v in env.items()}, "cwd": str(cwd)}
        answer = await ask_template(self.what, self, request, float(_setting("MT_KERNEL_TEMPLATE_WAIT", "60")))
        return None if answer is None else ForkedProcess(*answer)


async def ask_template(what: str, template, request: dict, wait_s: float):
    """Sends ``request`` to a template (``template.socket``, ``.process``, ``.started_at``) once it
    listens, waiting at most ``wait_s``; (pid, reader, writer) of the fork, whose connection then
    brings its exit status, or None (the reason logged: the caller starts the usual way)."""
    deadline = time.monotonic() + wait_s
    while not os.path.exists(template.socket):
        if template.process.poll() is not None:
            log.warning("%s ended (%s) before it was ready", what, template.process.returncode)
            return None
        if time.monotonic() > deadline:
            log.warning("%s not ready after %.0f s", what, time.monotonic() - template.started_at)
            return None
        await asyncio.sleep(0.05)
    try:
        connection = await _connect(what, template, deadline)
        reader, writer = await asyncio.open_unix_connection(sock=connection)
    except OSError as error:
        log.warning("%s unreachable (%s)", what, error)
        return None
    try:
        writer.write(json.dumps(request).encode() + b"\n")
        await writer.drain()
        reply = json.loads(await reader.readline() or b"{}")
    except (OSError, ValueError) as error:  # the template died mid-answer
        writer.close()
        log.warning("%s lost the connection before answering (%r)", what, error)
        return None
    if "pid" not in reply:
        writer.close()
        log.warning("%s refused: %s", what, reply.get("error", "it closed the connection"))
        return None
    return int(reply["pid"]), reader, writer


async def _connect(what: str, template, deadline: float) -> socket.socket:
    """A connection to ``template.socket``, retried until ``deadline`` while its backlog is full.

    A Unix socket whose backlog of waiting connections is full refuses a non-blocking connect with
    EAGAIN. asyncio's ``open_unix_connection(path)`` takes that EAGAIN for a TCP connect in
    progress, waits until the socket is writable and finds no error, so it returns a socket that
    was never connected; the first write then fails and ``drain`` raises
    ``ConnectionResetError('Connection lost')``. (A hundred spawns at once against the server
    template's backlog of 64 lost a quarter of the class so.) Here the connect is made by hand: a
    full backlog is waited out, the connection made once the template has accepted others."""
    pause = 0.005
    while True:
        connection = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        connection.setblocking(False)
        try:
            connection.connect(template.socket)
            return connection
        except (BlockingIOError, ConnectionRefusedError) as error:
            # EAGAIN: the backlog is full; ECONNREFUSED: a socket file nobody listens on yet.
            connection.close()
            if template.process.poll() is not None:
                raise ConnectionRefusedError(f"{what} ended ({template.process.returncode})") from error
            if time.monotonic() + pause > deadline:
                raise TimeoutError(f"{what}'s socket still refused connections at the deadline ({error})") from error
            await asyncio.sleep(pause)
            pause = min(2 * pause, 0.1)
        except BaseException:
            connection.close()
            raise


class ChildProcess:
    """A child of this process that it did not start with ``subprocess``, as a ``Popen`` is polled."""

    stdin = None

    def __init__(self, pid: int):
        self.pid = pid
        self.returncode: int | None = None

    def poll(self) -> int | None:
        if self.returncode is None:
            try:
                pid, status = os.waitpid(self.pid, os.WNOHANG)
            except ChildProcessError:
                self.returncode = UNKNOWN_EXIT
            else:
                if pid:
                    self.returncode = os.waitstatus_to_exitcode(status)
        return self.returncode


class ForkedProcess:
    """A forked kernel as jupyter_client's LocalProvisioner sees a ``Popen``.

    The template writes the kernel's exit status on the connection that asked for the fork. It is
    read without the event loop, by a non-blocking ``recv`` at each ``poll``: a server that stops
    (Voila, jupyter_server on SIGTERM) ends its event loop first and shuts its kernels down in
    another one, where a read waiting in the first loop would never finish: each kernel's shutdown
    then waited its 5 s ("Wait for final termination of kernel timed out") and the loop's close
    left the reads pending ("Task was destroyed but it is pending").
    """

    stdin = stdout = stderr = None

    def __init__(self, pid: int, reader: asyncio.StreamReader, writer: asyncio.StreamWriter):
        self.pid = pid
        self.returncode: int | None = None
        # The connection's own socket, duplicated, and the asyncio transport closed (a Unix socket
        # stays connected while a descriptor of it is open).
        self._connection = socket.socket(fileno=os.dup(writer.get_extra_info("socket").fileno()))
        self._connection.setblocking(False)
        self._received = b""
        writer.close()

    def poll(self) -> int | None:
        if self.returncode is None:
            try:
                data = self._connection.recv(4096)
            except BlockingIOError:
                return None
            except OSError:
                data = b""
            self._received += data
            if b"\n" in self._received:
                self.returncode = int(json.loads(self._received.split(b"\n", 1)[0])["status"])
            elif not data:
                # The template ended before the kernel; the kernel follows it (its parent poller)
                # within a second. Alive until it is gone; its exit code nobody can learn.
                try:
                    os.kill(self.pid, 0)
                except ProcessLookupError:
                    self.returncode = UNKNOWN_EXIT
            if self.returncode is not None:
                self._connection.close()
        return self.returncode

    def wait(self, timeout: float | None = None) -> int | None:
        # LocalProvisioner.wait calls this once poll() says the kernel has ended.
        return self.poll()

    def send_signal(self, signum: int) -> None:
        if self.poll() is None:
            os.kill(self.pid, signum)

    def terminate(self) -> None:
        self.send_signal(signal.SIGTERM)

    def kill(self) -> None:
        self.send_signal(signal.SIGKILL)


class ForkingProvisioner(LocalProvisioner):
    """LocalProvisioner whose kernels come from the server's template when it can fork them."""

    forked = False

    async def launch_kernel(self, cmd: list[str], **kwargs):
        template = KernelTemplate.shared()
        if template is not None and template.serves(cmd):
            env = kwargs.get("env") or os.environ.copy()
            cwd = kwargs.get("cwd") or os.getcwd()
            started = time.perf_counter()
            process = await template.fork(cmd, env, cwd)
            if process is not None:
                self.process = process
                self.pid = process.pid
                self.pgid = process.pid  # the kernel leads its own session and process group
                self.cwd = cwd
                self.forked = True
                log.info("kernel %s forked from the template in %.0f ms (pid %d)", self.kernel_id,
                         1000 * (time.perf_counter() - started), process.pid)
                return self.connection_info
            log.warning("kernel %s: starting it the usual way", self.kernel_id)
            template.ensure_started()  # a template found dead is replaced for the next kernel
        self.forked = False
        return await super().launch_kernel(cmd, **kwargs)


class ForkingKernelManager(ServerKernelManager):
    """jupyter_server's kernel manager with a ForkingProvisioner for every kernel."""

    async def _async_pre_start_kernel(self, **kw):
        if self.provisioner is None:  # a restart keeps its provisioner
            self.kernel_id = self.kernel_id or kw.pop("kernel_id", None) or str(uuid.uuid4())
            self.provisioner = ForkingProvisioner(kernel_id=self.kernel_id, kernel_spec=self.kernel_spec,
                                                  parent=self)
        return await super()._async_pre_start_kernel(**kw)


def start_template() -> None:
    """Start this server's template now (server configuration files call it), so that it has
    imported the heavy modules by the time the first kernel is asked for."""
    KernelTemplate.shared()
