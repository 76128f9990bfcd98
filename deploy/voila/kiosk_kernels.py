"""The kernel manager of the kiosk's Voila server (deploy/voila/voila.py selects it).

Voila 0.5 keeps preheated kernels out of the idle culler while they wait in the pool, but a
spare's idle clock keeps running from the moment it finished running the page. When a visitor
takes a spare that waited longer than ``cull_idle_timeout`` (the first visitor after a quiet
spell), the kernel has no page connected yet for the second or so the page takes to load its
scripts and open the websocket; a culler pass in that window shuts the kernel down and the
visitor gets a page whose widgets never appear (seen in tests/browser/test_kiosk.py with a 5 s
timeout: the first visit's kernel was culled before its page connected).

``KioskKernelManager`` counts leaving the pool as activity: every culler pass first notes the
kernels still in a pool, and a kernel's idle time starts no earlier than the last pass that saw it
there. A spare taken between two passes therefore has at most ``cull_interval`` seconds of
idleness at the next pass (the config keeps that well below ``cull_idle_timeout``), and its page
connects long before the following one.

It also watches a kernel's activity with less work per message. jupyter_server's watcher checks
each IOPub message's signature and parses its header with date conversion, about a third of
the server's CPU per message (py-spy on a skill click, which relays about 180 widget messages).
This watcher reads only the header's and the parent header's JSON and the content of status
messages, and keeps the same rules (what counts as activity, the execution state). The
signature protects nothing here: the stream comes from the server's own kernel over a socket
in Voila's private (0700) connection folder, which only the server's own user can reach, and
what a message there can change is bookkeeping (the idle clock, the execution state the culler
reads); the websocket that relays the messages to the page is unchanged. It assumes the
session's default JSON packer (the kiosk's config sets no other).
"""

from __future__ import annotations

import json

from jupyter_server._tz import utcnow
from jupyter_server.services.kernels.kernelmanager import AsyncMappingKernelManager

#: The frame that separates a ZeroMQ message's routing identities from the Jupyter message.
_DELIMITER = b"<IDS|MSG>"


class KioskKernelManager(AsyncMappingKernelManager):
    """jupyter_server's kernel manager whose culler counts a spare's departure from the pool as activity."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._last_seen_spare: dict = {}

    def _spare_kernel_ids(self) -> set[str]:
        # ``_pools`` is Voila's preheated pool (notebook -> tasks whose result names the kernel),
        # a private name of Voila 0.5 (pinned below 0.6 in pyproject.toml); it exists only when
        # Voila wraps this class for preheating.
        spares = set()
        for pool in getattr(self, "_pools", {}).values():
            for task in pool:
                if task.done() and not task.cancelled() and task.exception() is None:
                    spares.add(task.result()["kernel_id"])
        return spares

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

    async def cull_kernels(self):
        now = utcnow()
        for kernel_id in self._spare_kernel_ids():
            self._last_seen_spare[kernel_id] = now
        for kernel_id in list(self._last_seen_spare):
            if kernel_id not in self._kernels:
                del self._last_seen_spare[kernel_id]
        await super().cull_kernels()

    async def cull_kernel_if_idle(self, kernel_id):
        kernel = self._kernels.get(kernel_id)
        if kernel is None:
            # Shut down (by its page's beacon) while the culler was awaiting another kernel's
            # shutdown: jupyter_server would raise KeyError here and log it as an error.
            return None
        seen = self._last_seen_spare.get(kernel_id)
        if seen is not None and getattr(kernel, "last_activity", seen) < seen:
            kernel.last_activity = seen
        return await super().cull_kernel_if_idle(kernel_id)
