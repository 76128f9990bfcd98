"""Kernels forked from a template (mt_widgets/kernels/): they teach, interrupt, restart, shut down,
take their own environment and folder, and a dead template means a usual start, logged.

Each test runs its own template (the class's shared one reset), as a server would: the first
kernel waits for the template's imports (about 1-2 s), the next ones are forks.
"""

from __future__ import annotations

import asyncio
import logging
import os
import signal
import stat
import time

import psutil
import pytest

from mt_widgets.kernels import provisioner
from mt_widgets.kernels.provisioner import ForkingKernelManager, KernelTemplate

pytestmark = pytest.mark.slow

EPISODE = """
from mt_widgets.widgets import EpisodeWidget
episode = EpisodeWidget("sim-point", seed=3, guidance=True)
for optimal in episode.optimal:
    episode.demonstrate(optimal)
    episode.next()
print("episode", len(episode.optimal), episode.result.feedback_latency_s)
"""


@pytest.fixture
def template(monkeypatch, tmp_path):
    monkeypatch.setenv("MT_KERNEL_TEMPLATE", "on")
    monkeypatch.setenv("MT_KERNEL_TEMPLATE_WAIT", "60")
    monkeypatch.setenv("JUPYTER_RUNTIME_DIR", str(tmp_path))
    monkeypatch.setattr(KernelTemplate, "_shared", None)
    shared = KernelTemplate.shared()
    yield shared
    shared.stop()


async def _run(client, code: str, timeout: float = 60) -> tuple[str, str]:
    out = []
    reply = await client.execute_interactive(
        code, timeout=timeout,
        output_hook=lambda msg: out.append(msg["content"].get("text", "")) if msg["msg_type"] == "stream" else None)
    return reply["content"]["status"], "".join(out)


async def _started(**kwargs):
    manager = ForkingKernelManager(kernel_name="python3")
    await manager.start_kernel(**kwargs)
    client = manager.client()
    client.start_channels()
    await client.wait_for_ready(timeout=60)
    return manager, client


def test_a_forked_kernel_teaches_an_episode_and_interrupt_restart_shutdown_work(template):
    async def scenario():
        manager, client = await _started()
        assert manager.provisioner.forked
        first_pid = manager.provisioner.pid
        status, out = await _run(client, "import os\nprint(os.getppid(), os.getpgid(0), os.getpid())")
        parent, group, pid = map(int, out.split())
        assert (status, parent, group, pid) == ("ok", template.process.pid, first_pid, first_pid)
        # It shows its own command (with its connection file) in ps, not the template's.
        shown = " ".join(psutil.Process(pid).cmdline()).split()
        assert shown[1:3] == ["-m", "ipykernel_launcher"] and shown[shown.index("-f") + 1] == manager.connection_file
        # Widgets talk to this kernel's front end: none was made in the template with a dummy comm
        # (ipycanvas makes its canvas manager at import; made in the template, no canvas would draw).
        status, out = await _run(client, "import ipycanvas, ipywidgets.widgets.widget as w\n"
                                         "print(sorted({type(x.comm).__module__ for x in w._instances.values()}))")
        assert (status, out.strip()) == ("ok", "['ipykernel.comm.comm']"), out
        # ipywidgets' comm targets, which it registers at import only inside a kernel (the
        # template imported it before there was one): a page's widget manager asks for every
        # widget's state through jupyter.widget.control.
        status, out = await _run(client, "import comm\nprint(sorted(comm.get_comm_manager().targets))")
        assert (status, out.strip()) == ("ok", "['jupyter.widget', 'jupyter.widget.control']"), out
        # With debugpy installed (as here) the kernel keeps its list of loaded modules' files for
        # the debugger; the hub's kernels, without one, skip it (tests/course/test_hub.py).
        status, out = await _run(client, "import sys, ipykernel.ipkernel as k\n"
                                         "print(k.sys is sys, len(get_ipython().kernel._kernel_modules) > 100)")
        assert (status, out.strip()) == ("ok", "True True"), out
        status, out = await _run(client, EPISODE, timeout=120)
        word, arrows, latency = out.split()
        assert (status, word) == ("ok", "episode") and int(arrows) > 0 and float(latency) > 0, out

        # Interrupt: a long cell ends with KeyboardInterrupt, the kernel lives on.
        msg_id = client.execute("import time\ntime.sleep(60)")
        await asyncio.sleep(1.0)
        asked = time.monotonic()
        await manager.interrupt_kernel()
        while True:
            msg = await client.get_iopub_msg(timeout=20)
            if msg["msg_type"] == "error":
                assert msg["content"]["ename"] == "KeyboardInterrupt"
                break
        assert time.monotonic() - asked < 10 and await manager.is_alive()
        while (reply := await client.get_shell_msg(timeout=20))["parent_header"].get("msg_id") != msg_id:
            pass
        assert reply["content"]["status"] == "error"
        await asyncio.sleep(0.5)  # ipykernel aborts what arrives just after an error (stop_on_error)
        status, _ = await _run(client, "episode.result")
        assert status == "ok"

        # Restart: a new fork, without the old kernel's names.
        await manager.restart_kernel(now=True)
        await client.wait_for_ready(timeout=60)
        assert manager.provisioner.forked and manager.provisioner.pid != first_pid
        assert not os.path.exists(f"/proc/{first_pid}")
        status, out = await _run(client, "print('episode' in dir())")
        assert (status, out.strip()) == ("ok", "False")

        # Shutdown: the process is gone and its exit code came from the template.
        pid = manager.provisioner.pid
        process = manager.provisioner.process
        client.stop_channels()
        await manager.shutdown_kernel()
        assert not await manager.is_alive() and not os.path.exists(f"/proc/{pid}")
        assert process.returncode is not None and process.returncode != provisioner.UNKNOWN_EXIT

    asyncio.run(scenario())


def test_a_forked_kernel_has_its_environment_folder_numba_cache_and_own_random_numbers(template, tmp_path):
    async def scenario():
        env = dict(os.environ, MT_PROBE="kernel-a", NUMBA_CACHE_DIR=str(tmp_path / "numba-a"))
        folder = tmp_path / "work"
        folder.mkdir()
        managers = []
        outs = []
        for _ in range(2):
            manager, client = await _started(env=env, cwd=str(folder))
            managers.append((manager, client))
            status, out = await _run(client, "import os, numpy, numba.core.config as c\n"
                                             "print(os.environ['MT_PROBE'], os.getcwd(), c.CACHE_DIR, "
                                             "numpy.random.random())")
            assert status == "ok"
            outs.append(out.split())
        for manager, client in managers:
            assert manager.provisioner.forked
            client.stop_channels()
            await manager.shutdown_kernel()
        for probe, cwd, cache, _ in outs:
            assert (probe, cwd, cache) == ("kernel-a", str(folder), str(tmp_path / "numba-a"))
        # A fork copies numpy's global generator: each kernel reseeds its own.
        assert outs[0][3] != outs[1][3]

    asyncio.run(scenario())


def test_a_stopped_template_leaves_no_folder_behind(template, tmp_path):
    folder = template.folder
    assert os.path.dirname(folder) == str(tmp_path) and os.path.basename(folder).startswith("mt-kt-")
    deadline = time.monotonic() + 60
    while not os.path.exists(template.socket):
        assert time.monotonic() < deadline and template.process.poll() is None
        time.sleep(0.05)
    template.stop()
    assert template.process.poll() is not None and not os.path.exists(folder)


def test_the_templates_socket_is_its_users_alone(template):
    deadline = time.monotonic() + 60
    while not os.path.exists(template.socket) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert stat.S_IMODE(os.stat(template.folder).st_mode) == 0o700
    assert stat.S_IMODE(os.stat(template.socket).st_mode) == 0o600


def test_a_dead_template_is_logged_and_replaced_its_kernels_end_with_it(template, caplog):
    async def scenario():
        manager, client = await _started()
        assert manager.provisioner.forked
        old = template.process.pid
        os.kill(old, signal.SIGKILL)
        template.process.wait()
        # The kernel forked from it follows its parent away (ipykernel's parent poller), as a
        # kernel follows its server...
        deadline = time.monotonic() + 20
        while await manager.is_alive() and time.monotonic() < deadline:
            await asyncio.sleep(0.2)
        assert not await manager.is_alive()
        client.stop_channels()
        await manager.shutdown_kernel(now=True)
        # ... and the next kernel comes from a new template, the death logged.
        with caplog.at_level(logging.WARNING, logger=provisioner.__name__):
            second, client = await _started()
        assert any(f"kernel template (pid {old}) ended with -9" in r.getMessage() for r in caplog.records)
        assert second.provisioner.forked and template.process.pid != old
        status, out = await _run(client, "import os\nprint(os.getppid())")
        assert (status, int(out)) == ("ok", template.process.pid)
        client.stop_channels()
        await second.shutdown_kernel()

    asyncio.run(scenario())


def test_a_template_not_ready_in_time_means_a_usual_start_logged(template, caplog, monkeypatch):
    async def scenario():
        template.stop()
        monkeypatch.setenv("MT_KERNEL_TEMPLATE_WAIT", "0")
        with caplog.at_level(logging.WARNING, logger=provisioner.__name__):
            manager, client = await _started()  # the replacement template has not imported yet
        assert not manager.provisioner.forked
        assert any("not ready" in r.getMessage() for r in caplog.records)
        assert any("starting it the usual way" in r.getMessage() for r in caplog.records)
        status, out = await _run(client, "import os\nprint(6 * 7, os.getppid())")
        assert status == "ok" and out.split() == ["42", str(os.getpid())]
        client.stop_channels()
        await manager.shutdown_kernel()

    asyncio.run(scenario())


def test_a_template_whose_imports_make_a_widget_refuses_and_kernels_start_the_usual_way(template, monkeypatch,
                                                                                        caplog, tmp_path):
    async def scenario():
        template.stop()
        monkeypatch.setattr(KernelTemplate, "_shared", None)
        (tmp_path / "mtt_makes_widget.py").write_text("import ipywidgets\nSLIDER = ipywidgets.IntSlider()\n")
        monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")])))
        monkeypatch.setenv("MT_KERNEL_TEMPLATE_PRELOAD", "numpy,mtt_makes_widget")
        with caplog.at_level(logging.WARNING, logger=provisioner.__name__):
            manager, client = await _started()
        assert not manager.provisioner.forked
        assert any("ended (1) before it was ready" in r.getMessage() for r in caplog.records), caplog.text
        client.stop_channels()
        await manager.shutdown_kernel()
        KernelTemplate._shared.stop()

    asyncio.run(scenario())


CANVAS_PROBE = """
import ipycanvas, ipycanvas.canvas as module, ipywidgets
canvas = ipycanvas.Canvas(width=10, height=10)
manager = canvas._canvas_manager
managers = [w for w in ipywidgets.widgets.widget._instances.values() if type(w).__name__ == "_CanvasManager"]
canvas.fill_rect(0, 0, 5, 5)
print(manager is module._CANVAS_MANAGER, type(manager.comm).__module__, len(managers), manager.comm.comm_id)
"""


def test_ipycanvas_preloaded_a_forked_kernel_draws_through_a_canvas_manager_of_its_own(template, monkeypatch):
    async def scenario():
        template.stop()
        monkeypatch.setattr(KernelTemplate, "_shared", None)
        monkeypatch.setenv("MT_KERNEL_TEMPLATE_PRELOAD", "numpy,ipywidgets,mt_widgets.widgets")
        manager, client = await _started()
        assert manager.provisioner.forked
        iopub = []
        reply = await client.execute_interactive(CANVAS_PROBE, timeout=60, output_hook=iopub.append)
        assert reply["content"]["status"] == "ok"
        out = "".join(m["content"].get("text", "") for m in iopub if m["msg_type"] == "stream").split()
        # The manager the canvas draws through is the module's, made in this kernel: a real comm
        # (ipykernel's, not the template's mute one), and the only one left.
        assert out[:3] == ["True", "ipykernel.comm.comm", "1"], out
        # The drawing reached the front end (this client) on that comm (opened when the kernel started).
        assert any(m["msg_type"] == "comm_msg" and m["content"]["comm_id"] == out[3] and m["buffers"]
                   for m in iopub)
        client.stop_channels()
        await manager.shutdown_kernel()
        KernelTemplate._shared.stop()

    asyncio.run(scenario())


def test_a_kernel_the_template_cannot_fork_starts_the_usual_way(template):
    assert not template.serves(["/usr/bin/other-python", "-m", "ipykernel_launcher", "-f", "x.json"])
    assert not template.serves([os.sys.executable, "-m", "some_other_kernel", "-f", "x.json"])
    assert template.serves([os.sys.executable, "-m", "ipykernel_launcher", "-f", "x.json"])
