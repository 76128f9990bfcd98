"""The servers: JupyterLab on the tutorials, Voila for the demo and the study pages.

Each replaces this process with the server (``os.execv``), as the shell scripts' ``exec`` did,
so Ctrl-C and a service manager's signals reach the server itself. The online study's pages
are the exception: they are served from a temporary folder this process removes afterwards.
"""

from __future__ import annotations

import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
from pathlib import Path

from mt_widgets.study.protocol import load_protocol

from .shipped import START_HERE, copy_notebooks, copy_report, shipped_folder

#: The environment variable the experimenter's panel reads its code from.
EXPERIMENTER_CODE_ENV = "MT_WIDGETS_EXPERIMENTER_CODE"
#: The online study's pages (and the pilot protocol they read): nothing else is served.
ONLINE_PAGES = ("study_sim.ipynb", "study_online.ipynb", "study_online_pilot.toml")
#: What both study pages read (notebooks/study_online.ipynb, study_sim.ipynb): the protocol and the
#: log folder. ``serve_online`` sets them for the server, so the experimenter's page opens on the
#: study the participants' page runs.
PROTOCOL_ENV = "MT_WIDGETS_STUDY_PROTOCOL"
LOGS_ENV = "MT_WIDGETS_STUDY_LOGS"
#: JupyterLab, as ``python -m jupyterlab``, showing library DeprecationWarnings as Python does by
#: default (not at all). Voila's import turns traitlets' on for the whole server (voila/__init__.py's
#: filter), and notebook_shim, a JupyterLab dependency, reads every attribute of the server, the
#: deprecated ServerApp.token among them: "ServerApp.token config is deprecated" at every start, about
#: a setting this command never uses (it sets IdentityProvider.token). Voila is imported first and
#: its filter taken out; the lab's own warnings and log are as they were.
LAB_LAUNCHER = (
    "import sys, warnings, voila; "
    "warnings.filters[:] = [f for f in warnings.filters if not (f[0] == 'default' and f[2] is DeprecationWarning "
    "and getattr(f[3], 'pattern', f[3]) == 'traitlets')]; "
    "from jupyterlab.labapp import main; sys.exit(main())")
#: Voila's own default port, used when it is free.
VOILA_PORT = 8866


def free_port(host: str = "127.0.0.1") -> int:
    """A port nothing listens on now (the server binds it right after)."""
    with socket.socket() as probe:
        probe.bind((host, 0))
        return probe.getsockname()[1]


def _is_free(port: int, host: str = "127.0.0.1") -> bool:
    with socket.socket() as probe:
        try:
            probe.bind((host, port))
        except OSError:
            return False
        return True


def _has_screen() -> bool:
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")) or sys.platform != "linux"


def _sets(extra: list[str], option: str) -> bool:
    return any(arg == f"--{option}" or arg.startswith(f"--{option}=") or arg.startswith(f"--ServerApp.{option}")
               for arg in extra)


def lab_command(folder, port: int | None, browser: bool, extra: list[str]) -> tuple[list[str], str | None]:
    """Copies the notebooks into ``folder`` and returns JupyterLab's command line and, when the
    port and token are chosen here, the start-here URL to print."""
    folder = Path(folder).expanduser().resolve()
    copied, kept = copy_notebooks(folder)
    print(f"== {copy_report(folder, copied, kept)}")
    args = [sys.executable, "-c", LAB_LAUNCHER, f"--ServerApp.root_dir={folder}"]
    if hasattr(os, "getuid") and os.getuid() == 0:
        args.append("--allow-root")
    url = None
    if not browser or not _has_screen():
        args.append("--no-browser")
    if port is not None or (not _has_screen() and not _sets(extra, "port")):
        # JupyterLab prints its root URL; with the port and token chosen here the printed link
        # opens the start-here tutorial itself.
        port = port if port is not None else free_port()
        token = secrets.token_hex(24)
        args += [f"--port={port}", "--port-retries=0", f"--IdentityProvider.token={token}"]
        url = f"http://localhost:{port}/lab/tree/{START_HERE}?token={token}"
    return [*args, *extra, str(folder / START_HERE)], url


def voila_command(notebook: Path, port: int | None, extra: list[str]) -> list[str]:
    """Voila serving ``notebook`` (a file or a folder) with the kiosk settings of deploy/voila."""
    settings = shipped_folder("deploy/voila")
    args = [sys.executable, "-m", "voila", "--no-browser", f"--Voila.config_file_paths={settings}"]
    if port is not None:
        args.append(f"--port={port}")
    return [*args, *extra, str(notebook)]


def replace_process(args: list[str], cwd: Path) -> None:
    """Runs ``args`` in place of this process, in ``cwd``."""
    sys.stdout.flush()
    sys.stderr.flush()
    os.chdir(cwd)
    os.execv(args[0], args)


def experimenter_code() -> str:
    """The experimenter's code from the environment, or a new one, printed, put in the environment."""
    code = os.environ.get(EXPERIMENTER_CODE_ENV, "")
    if not code:
        code = secrets.token_urlsafe(9)
        os.environ[EXPERIMENTER_CODE_ENV] = code
        print(f"Experimenter code for this server: {code}", flush=True)
    return code


def online_study(environ) -> tuple[str, Path]:
    """(protocol, log folder) of the online study: ``$MT_WIDGETS_STUDY_PROTOCOL`` (default: the shipped
    pilot, notebooks/study_online_pilot.toml) and ``$MT_WIDGETS_STUDY_LOGS`` (default:
    ~/mt-widgets-studies/online, the participants' page's own default)."""
    protocol = environ.get(PROTOCOL_ENV, "").strip() or str(shipped_folder("notebooks") / "study_online_pilot.toml")
    logs = environ.get(LOGS_ENV, "").strip()
    return protocol, (Path(logs) if logs else Path.home() / "mt-widgets-studies" / "online").expanduser()


def participant_link(base_url: str, protocol) -> str:
    """A link to the participants' page for a made-up test participant, with the URL parameters the
    protocol's ``[online]`` table asks for (Prolific's PROLIFIC_PID, STUDY_ID and SESSION_ID: a test
    ID of Prolific's 24 hexadecimal characters, new at every call, so each try is a new participant)."""
    online = load_protocol(protocol).online
    if online is None:
        raise ValueError(f"{PROTOCOL_ENV}: expected a protocol with an [online] table, got {protocol}")
    parameters = {online.id_parameter: secrets.token_hex(12)}
    parameters.update({name: f"TEST{secrets.token_hex(10)}" for name in online.recorded_parameters})
    return f"{base_url}/voila/render/study_online.ipynb?" + "&".join(f"{k}={v}" for k, v in parameters.items())


def serve_online(port: int | None, extra: list[str]) -> int:
    """Serves only the online pages, linked (or copied) into a temporary folder removed at the end;
    prints a participant link to try, the experimenter's page and the log folder."""
    notebooks = shipped_folder("notebooks")
    protocol, logs = online_study(os.environ)
    os.environ[PROTOCOL_ENV], os.environ[LOGS_ENV] = protocol, str(logs)
    if port is None and not _sets(extra, "port"):
        port = VOILA_PORT if _is_free(VOILA_PORT) else free_port()
    base = f"http://localhost:{port}" if port is not None else "http://localhost:PORT"
    completed = load_protocol(protocol).online.completion("completed")
    print(f"Protocol: {protocol}\nLogs: {logs}\n"
          f"Participant link to try (a made-up test ID): {participant_link(base, protocol)}\n"
          f"Experimenter's page: {base}/voila/render/study_sim.ipynb\n"
          + (f"At the end: the page shows the completion code ({completed.code}), then goes to the protocol's "
             f"completion URL, {completed.url}" if completed.url is not None else
             f"At the end: the page shows the completion code ({completed.code}) and stays (the protocol gives "
             f"no completion URL, as a pilot's: for a pool, copy it, mt-widgets study copy-protocol online-pilot, "
             f"and give each ending its url)"), flush=True)
    pages = Path(tempfile.mkdtemp(prefix="mt-widgets-study-pages."))
    try:
        for name in ONLINE_PAGES:
            try:
                (pages / name).symlink_to(notebooks / name)
            except OSError:  # no symbolic links (Windows without the privilege): a copy serves as well
                shutil.copyfile(notebooks / name, pages / name)
        server = subprocess.Popen(voila_command(pages, port, extra), cwd=pages)
        # A service manager stops the command with SIGTERM: pass it on, then clean up.
        signal.signal(signal.SIGTERM, lambda number, frame: server.terminate())
        try:
            return server.wait()
        except KeyboardInterrupt:
            server.send_signal(signal.SIGINT)
            return server.wait()
    finally:
        shutil.rmtree(pages, ignore_errors=True)
