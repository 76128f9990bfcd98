"""A server's watch on its kernels' activity, with a fraction of jupyter_server's work per message.

A Jupyter server watches every IOPub message of every kernel to keep each kernel's idle clock
(``last_activity``, what the idle culler and JupyterHub's activity report read) and its execution
state. jupyter_server's watcher checks each message's signature and parses its header with date
conversion: about a third of the server's CPU per relayed message (py-spy on the kiosk's skill
click, which relays about 180 widget messages), and a tenth of a class hub student's server during
a lecture's first minute (py-spy over the thirty servers of ``benchmarks/bench_hub.py``).

``HeaderActivityKernelManager`` reads only the header's and the parent header's JSON, and the
content of status messages, and keeps the same rules (what counts as activity, the execution
state; ``tests/test_activity_watch.py`` feeds both watchers the same messages). The signature
protects nothing here: the stream comes from the server's own kernel over a socket in its private
(0700) runtime folder, which only the server's own user can reach, and what a message there can
change is bookkeeping (the idle clock, the execution state the culler reads), which the kernel's
code could move anyway by printing; the websocket that relays the messages to the page is
unchanged. It assumes the session's default JSON packer (no deployment here sets another).

Used by the kiosk's Voila (``deploy/voila/kiosk_kernels.py``) and the class hub's servers
(``deploy/jupyterhub/student-config/jupyter_server_config.py``).
"""

from __future__ import annotations

import json

from jupyter_server._tz import utcnow
from jupyter_server.services.kernels.kernelmanager import AsyncMappingKernelManager

#: The frame that separates a ZeroMQ message's routing identities from the Jupyter message.
_DELIMITER = b"<IDS|MSG>"


class HeaderActivityKernelManager(AsyncMappingKernelManager):
    """jupyter_server's kernel manager, with the same activity watch done from the messages' headers."""

    def start_watching_activity(self, kernel_id):
        """jupyter_server's activity watch (the same last_activity and execution_state), cheaper."""
        kernel = self._kernels[kernel_id]
        kernel.reason = ""
        kernel.last_activity = utcnow()
        kernel._activity_stream = kernel.connect_iopub()

        def record_activity(msg_list):
            # [identities..., <IDS|MSG>, signature, header, parent_header, metadata, content, buffers...]
            frames = msg_list if isinstance(msg_list[0], bytes) else [bytes(frame) for frame in msg_list]
            try:
                start = frames.index(_DELIMITER) + 2
                header = json.loads(frames[start])
                parent = json.loads(frames[start + 1]) or {}
            except (ValueError, IndexError):
                self.log.warning("kernel %s sent an IOPub message that is not a Jupyter message", kernel_id)
                return
            msg_type, parent_type = header.get("msg_type"), parent.get("msg_type")
            tracked_parent = self.track_message_type(parent_type)
            if self.track_message_type(msg_type) or tracked_parent or kernel.execution_state == "busy":
                self.last_kernel_activity = kernel.last_activity = utcnow()
            if msg_type == "status":
                execution_state = json.loads(frames[start + 3])["execution_state"]
                if tracked_parent:
                    kernel.execution_state = execution_state
                elif kernel.execution_state == "starting" and execution_state != "starting":
                    # jupyter_server's rule: after starting, "idle" unless a tracked message says otherwise.
                    kernel.execution_state = "idle"

        kernel._activity_stream.on_recv(record_activity)
