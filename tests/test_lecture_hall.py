"""A lecture hall starting at once (issue 46): every spawn reaches the server template, and the student
beyond the class server's capacity is told so in a page.

A class of a hundred spawned at once lost a quarter of its spawns ("Connection lost" in
``ask_template``): the template's socket held 64 waiting connections, asyncio took the refused
connect for one in progress, and the first write failed. Here a template-like listener that holds
one waiting connection and answers slowly is asked by many at once: every request must be answered.
The hub's side (the backlog equal to its spawn limit) is checked in tests/course/test_hub_config.py.
"""

from __future__ import annotations

import asyncio
import shutil
import socket
import sys
import threading
from pathlib import Path
from types import SimpleNamespace

import jinja2
import pytest
from jupyterhub._data import DATA_FILES_PATH

from mt_widgets.kernels import template
from mt_widgets.kernels.provisioner import ask_template
from mt_widgets.kernels.server_template import ServerTemplate

REPO = Path(__file__).resolve().parents[1]


class _SlowTemplate:
    """A template's socket that holds ``backlog`` waiting connections and answers one request at a
    time, each after ``pause_s``, with a pid of its own count (no fork)."""

    def __init__(self, path: Path, backlog: int, pause_s: float):
        self.socket = str(path)
        self.process = SimpleNamespace(poll=lambda: None, returncode=None)
        self.started_at = 0.0
        self.listener = template.listen(self.socket, backlog)
        self.pause = threading.Event()
        self.pause_s = pause_s
        self.requests: list[dict] = []
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self.listener.accept()
            except OSError:
                return  # closed: the test is over
            with conn:
                self.requests.append(template.read_line(conn))
                self.pause.wait(self.pause_s)  # a fork of a large process is not instant either
                conn.sendall(b'{"pid": %d}\n' % (1000 + len(self.requests)))

    def close(self) -> None:
        self.listener.shutdown(socket.SHUT_RDWR)  # wakes the thread's accept (a close alone would not)
        self.thread.join(5)
        self.listener.close()


def test_a_class_asking_at_once_beyond_the_templates_backlog_is_answered_every_one(tmp_path):
    class_size = 24
    slow = _SlowTemplate(tmp_path / "s", backlog=1, pause_s=0.001)

    async def lecture():
        answers = await asyncio.gather(*(ask_template("test template", slow, {"student": n}, wait_s=30)
                                         for n in range(class_size)))
        for answer in answers:
            if answer is not None:
                answer[2].close()
        return answers

    try:
        answers = asyncio.run(lecture())
    finally:
        slow.close()
    assert all(answer is not None for answer in answers), "a spawn was lost (started the usual way)"
    pids = [answer[0] for answer in answers]
    assert sorted(pids) == list(range(1001, 1001 + class_size))
    # Each request arrived whole and exactly once.
    assert sorted(request["student"] for request in slow.requests) == list(range(class_size))


def test_a_template_that_has_ended_is_not_waited_for(tmp_path, caplog):
    """A socket file nobody listens on (its template died): the asker gives up at once, logged, and the
    caller starts the usual way, instead of retrying until its deadline."""
    path = tmp_path / "s"
    orphan = socket.socket(socket.AF_UNIX)
    orphan.bind(str(path))
    orphan.close()
    dead = SimpleNamespace(socket=str(path), process=SimpleNamespace(poll=lambda: -9, returncode=-9), started_at=0.0)
    assert asyncio.run(ask_template("test template", dead, {}, wait_s=30)) is None
    assert "test template unreachable (test template ended (-9))" in caplog.text


def test_the_backlog_is_a_positive_count_and_reaches_the_server_templates_command(tmp_path):
    with pytest.raises(ValueError, match="backlog: expected a positive integer, got 0"):
        template.listen(str(tmp_path / "s"), 0)
    with pytest.raises(ValueError, match=r"backlog: expected a positive integer \(the hub's concurrent spawn limit\), "
                                         r"got '100'"):
        ServerTemplate(sys.executable, ["jupyterhub.singleuser"], [], [], {}, backlog="100")
    hall = ServerTemplate(sys.executable, ["jupyterhub.singleuser"], [], [], {}, backlog=250)
    try:
        argv, _, _ = hall.command()
        assert argv[-1] == "250"
    finally:
        shutil.rmtree(hall.folder)


def _refusal_page(message: str) -> str:
    templates = Path(DATA_FILES_PATH) / "templates"  # where JupyterHub itself finds its pages
    loader = jinja2.FileSystemLoader([str(REPO / "deploy" / "jupyterhub" / "templates"), str(templates)])
    page = jinja2.Environment(loader=loader, autoescape=True).get_template("429.html")
    return page.render(status_code=429, status_message="Too Many Requests", message=message,
                       static_url=lambda *args, **kwargs: "/static", base_url="/hub/", prefix="/", user=None)


def test_the_student_beyond_the_class_servers_capacity_is_told_so_in_words():
    # JupyterHub's own messages for its two refusals (jupyterhub/handlers/base.py, spawn_single_user).
    full = _refusal_page("Active user limit exceeded. Try again in a few minutes.")
    assert 'data-reason="full"' in full and "The class server is full" in full
    assert "Nothing of yours is lost" in full and "Try again" in full
    assert "429 : Too Many Requests" not in full
    starting = _refusal_page("Too many users trying to log in right now. Try again in 30 seconds.")
    assert 'data-reason="starting"' in starting and "Try again in 30 seconds." in starting
