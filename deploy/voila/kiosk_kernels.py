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

It also watches a kernel's activity from the messages' headers, a fraction of jupyter_server's
work per message (``mt_widgets/kernels/activity.py`` says why that is safe).
"""

from __future__ import annotations

from jupyter_server._tz import utcnow

from mt_widgets.kernels.activity import HeaderActivityKernelManager


class KioskKernelManager(HeaderActivityKernelManager):
    """Watches activity from the headers; its culler counts a spare's departure from the pool as activity."""

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
