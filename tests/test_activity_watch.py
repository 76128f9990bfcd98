"""mt_widgets/kernels/activity.py's watcher against jupyter_server's own, message by message.

Both watchers are fed the same IOPub messages (signed by the kernel's session, as a kernel sends
them); after each, the kernel's execution state and whether its idle clock moved must agree.
"""

from __future__ import annotations

import importlib.util
import time
from types import SimpleNamespace

import pytest
from jupyter_client.session import Session
from jupyter_server.services.kernels.kernelmanager import AsyncMappingKernelManager

from browser_support import REPO
from mt_widgets.kernels.activity import HeaderActivityKernelManager


def _kiosk_manager_class():
    # Loaded from its file: deploy/voila on sys.path would make its voila.py shadow the voila package.
    spec = importlib.util.spec_from_file_location("kiosk_kernels", REPO / "deploy" / "voila" / "kiosk_kernels.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.KioskKernelManager


class _Stream:
    def __init__(self):
        self.callback = None

    def on_recv(self, callback):
        self.callback = callback


def _watched(manager_class, session: Session):
    """A manager watching one stub kernel; returns (manager, kernel, feed(frames))."""
    manager = manager_class()
    stream = _Stream()
    kernel = SimpleNamespace(reason="x", last_activity=None, execution_state="starting", session=session,
                             connect_iopub=lambda: stream)
    manager._kernels["k"] = kernel
    manager.start_watching_activity("k")
    return manager, kernel, stream.callback


def _frames(session: Session, msg_type: str, content: dict, parent_type: str | None) -> list[bytes]:
    parent = session.msg(parent_type, {}) if parent_type else {}
    message = session.msg(msg_type, content, parent=parent)
    return [b"kernel.abc.iopub", *session.serialize(message)]


#: What a kernel sends: its start, an execution with output and widget messages, a comm_info
#: exchange (not activity), a widget update while idle (activity), untracked output while busy
#: (activity), and a bare status.
SEQUENCE = [
    ("status", {"execution_state": "starting"}, None),
    ("status", {"execution_state": "idle"}, "kernel_info_request"),
    ("status", {"execution_state": "busy"}, "execute_request"),
    ("execute_input", {"code": "1", "execution_count": 1}, "execute_request"),
    ("comm_open", {"comm_id": "c", "target_name": "jupyter.widget", "data": {}}, "execute_request"),
    ("stream", {"name": "stdout", "text": "hi"}, "execute_request"),
    ("status", {"execution_state": "idle"}, "execute_request"),
    ("status", {"execution_state": "busy"}, "comm_info_request"),
    ("status", {"execution_state": "idle"}, "comm_info_request"),
    ("comm_msg", {"comm_id": "c", "data": {"method": "update"}}, "comm_msg"),
    ("stream", {"name": "stdout", "text": "late"}, "comm_info_request"),
    ("status", {"execution_state": "busy"}, "execute_request"),
    ("stream", {"name": "stdout", "text": "while busy"}, "kernel_info_request"),  # activity: it is busy
    ("status", {"execution_state": "idle"}, "execute_request"),
    ("status", {"execution_state": "busy"}, None),
]


@pytest.mark.parametrize("manager_class", [HeaderActivityKernelManager, _kiosk_manager_class()],
                         ids=["header", "kiosk"])
def test_the_header_watcher_keeps_jupyter_servers_activity_and_execution_state_for_every_message(manager_class):
    session = Session(key=b"secret")
    reference, reference_kernel, feed_reference = _watched(AsyncMappingKernelManager, session)
    kiosk, kiosk_kernel, feed_kiosk = _watched(manager_class, session)
    assert kiosk_kernel.reason == "" and kiosk_kernel.last_activity is not None
    moved_somewhere = set()
    for msg_type, content, parent in SEQUENCE:
        frames = _frames(session, msg_type, content, parent)
        before = (reference_kernel.last_activity, kiosk_kernel.last_activity)
        time.sleep(0.002)  # the clocks tick between messages
        feed_reference(list(frames))
        feed_kiosk(list(frames))
        step = f"{msg_type} (parent {parent})"
        assert kiosk_kernel.execution_state == reference_kernel.execution_state, step
        moved = (reference_kernel.last_activity != before[0], kiosk_kernel.last_activity != before[1])
        assert moved[0] == moved[1], step
        moved_somewhere.add(moved[0])
        assert (kiosk.last_kernel_activity == kiosk_kernel.last_activity) == (
            reference.last_kernel_activity == reference_kernel.last_activity), step
    assert moved_somewhere == {True, False}  # the sequence has both kinds of message
    assert reference_kernel.execution_state == "busy"


def test_a_frame_list_that_is_not_a_jupyter_message_is_logged_and_changes_nothing(caplog):
    _, kernel, feed = _watched(HeaderActivityKernelManager, Session(key=b"secret"))
    state, clock = kernel.execution_state, kernel.last_activity
    with caplog.at_level("WARNING"):
        feed([b"kernel.abc.iopub", b"no delimiter here"])
    assert (kernel.execution_state, kernel.last_activity) == (state, clock)
    assert "not a Jupyter message" in caplog.text


@pytest.mark.parametrize("as_frames", [False, True])
def test_zmq_frames_are_read_as_bytes_are(as_frames):
    zmq = pytest.importorskip("zmq")
    session = Session(key=b"secret")
    _, kernel, feed = _watched(HeaderActivityKernelManager, session)
    frames = _frames(session, "status", {"execution_state": "busy"}, "execute_request")
    feed([zmq.Frame(frame) for frame in frames] if as_frames else frames)
    assert kernel.execution_state == "busy"
