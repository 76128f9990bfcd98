"""The browser pages that show this kernel's widgets, told apart by their kernel session.

One kernel's widgets can be shown by several pages at once: one notebook open in two JupyterLab tabs,
a second window, a page reloaded (the old one gone, the new one there). Each page's connection to the
kernel has a session of its own, named in the header of every message the page sends; the kernel
handles one message at a time, so the session of the message being handled says which page spoke.

A page makes itself known when its models of this kernel's canvases appear (ipycanvas' ``client_ready``,
heard by ``redraw.repaint_on_new_view`` and by the receipt canvas). A page that goes (a tab closed, or
reloaded) sends nothing to say so: whoever waits on pages drops the ones that stay silent past a
fallback (``receipt.Receipts.give_up``).
"""

from __future__ import annotations

from IPython import get_ipython


def current_page() -> str | None:
    """The page whose message the kernel is handling now: the kernel session in the message's header,
    or None outside a kernel (scripts, kernel-free tests: one page at most)."""
    kernel = getattr(get_ipython(), "kernel", None)
    if kernel is None:
        return None
    parent = kernel.get_parent("shell") or {}
    return parent.get("header", {}).get("session") or None


class Pages:
    """The pages known to show this kernel's widgets (a kernel has one: ``PAGES``)."""

    def __init__(self):
        # A dict as an ordered set: pages in the order they were first heard of.
        self._live: dict[str | None, None] = {}

    def seen(self, page: str | None) -> None:
        """``page`` shows this kernel's widgets (again, if it had been taken as gone)."""
        self._live[page] = None

    def gone(self, page: str | None) -> None:
        """``page`` is taken as gone: nothing waits for it any more."""
        self._live.pop(page, None)

    @property
    def live(self) -> tuple[str | None, ...]:
        return tuple(self._live)


#: The kernel's pages.
PAGES = Pages()
