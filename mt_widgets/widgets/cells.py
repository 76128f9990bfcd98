"""The views a notebook cell made or showed, retired once the cell's output is gone and nothing can show them again.

ipywidgets keeps every widget open (its registry and its comm hold it) until ``close()``: a cell that
makes an ``EpisodeWidget`` and is run again leaves the last one open, with its rollouts, its sixty
widget models in the kernel and their models in the page. A class's kernel grew by about 1.5 MiB an
episode that way over a lesson (``benchmarks/bench_long_day.py``).

JupyterLab sends each execute request with the id of the cell it runs (``cellId``) and the ids of
cells deleted since the last one (``deletedCells``); a cell run again has its outputs cleared on every
page first (two tabs of one notebook share its model), and a deleted cell's are gone. So this module
records, for each view it is given (``own``), the cells it was made in and shown in (``shown``, from
the view's ``_repr_mimebundle_``), and retires the view (``animation.retire``: closed once every page
has drawn what was sent to it) when

1. every one of those cells has been run again or deleted, and
2. after the cell that ran, nothing of the user's reaches it: no name of the user's namespace, nor
   anything reachable from one (lists, dicts, objects' attributes, functions' closures), nor a widget
   still open (a box of the user's that holds it, a button whose callback names it). The search is
   bounded (``SEARCH_LIMIT`` objects): beyond it, the view is kept. A view found kept is searched for
   again after 1, 2, 4, ... cell runs (at most ``MAX_SEARCH_EVERY``): a search costs tens of
   milliseconds, and a notebook that keeps a list of its episodes should not pay it at every cell.

What IPython's output cache holds (``Out``, ``_5``, ``_``) does not count, since it would hold every
episode shown as a cell's last expression for a thousand cells: a retired view leaves the cache too.
A view made or shown without a cell id (Voila, the classic notebook, a callback of another view) is
never retired here: nothing says where it is shown.
"""

from __future__ import annotations

import gc
import re
import sys
import types
import weakref

from IPython import get_ipython
from ipywidgets import Widget
from ipywidgets.widgets.widget import _instances  # the registry of open widgets (no public name in 8.x)

from .animation import retire
from .tree import widget_tree

#: Objects the reachability search visits at most; beyond it every view in question is kept.
SEARCH_LIMIT = 200_000
#: At most how many cell runs apart a view the user keeps is searched for again.
MAX_SEARCH_EVERY = 32
#: The output cache's numbered names (``_5``); IPython's other names are found by their hidden value.
_CACHED_RESULT = re.compile(r"_\d+")
#: Objects never looked into: they hold nothing of the user's and reach everything (a module's names).
_LEAVES = (str, bytes, bytearray, int, float, complex, bool, type(None), types.ModuleType, types.CodeType,
           types.BuiltinFunctionType, range)
#: Packages whose objects a view's widgets hold that reach the kernel, never a view of the user's: comms
#: (each reaches its own widget only, through its callback), the kernel's, ZeroMQ's, loggers, threads.
_NOT_THE_USERS = frozenset({"comm", "ipykernel", "zmq", "logging", "threading", "asyncio", "tornado"})


class _Views:
    """The kernel's record: view -> the cells it was made or shown in (weakly: a view closed by its
    owner drops out), and the hooks that retire views once those cells are gone."""

    def __init__(self):
        self._cells: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
        self._shell = None
        self._running: str | None = None
        #: Views whose cells are all gone, waiting for nothing of the user's to reach them.
        self._waiting: weakref.WeakSet = weakref.WeakSet()
        # A view the user keeps is searched for again after 1, 2, 4, ... 32 cell runs, not after every
        # one: the search costs tens of milliseconds with a few episodes open.
        self._search_every, self._runs_to_search = 1, 0

    # -- what the views say ----------------------------------------------------------------------
    def own(self, view: Widget) -> None:
        """Records ``view`` as made by the cell running now (nothing outside a cell with an id)."""
        if self._hooked() and self._running is not None:
            self._cells.setdefault(view, set()).add(self._running)

    def shown(self, view: Widget) -> None:
        """Records that ``view`` is shown in the output of the cell running now."""
        if self._hooked() and self._running is not None:
            self._cells.setdefault(view, set()).add(self._running)
            self._waiting.discard(view)

    def cells(self, view: Widget) -> frozenset[str]:
        """The cells ``view`` was made or shown in that still show it (for tests and the curious)."""
        return frozenset(self._cells.get(view, ()))

    # -- the kernel's cells ----------------------------------------------------------------------
    def _hooked(self) -> bool:
        """Whether this runs in a kernel whose cells are followed (hooks registered on first use)."""
        shell = get_ipython()
        if shell is None or getattr(shell, "kernel", None) is None:
            return False
        if self._shell is not shell:
            shell.events.register("pre_run_cell", self._pre_run_cell)
            shell.events.register("post_run_cell", self._post_run_cell)
            self._shell = shell
            # The cell running now made the first view: its id is in the request being answered.
            self._running = _cell_id(shell)
        return True

    def _pre_run_cell(self, info) -> None:
        cell = getattr(info, "cell_id", None) or _cell_id(self._shell)
        self._running = cell
        gone = set(_deleted_cells(self._shell))
        if cell is not None:
            gone.add(cell)  # its outputs are cleared on every page before it runs again
        if not gone:
            return
        for view, cells in list(self._cells.items()):
            if cells & gone:
                cells -= gone
                if not cells:
                    self._waiting.add(view)
                    self._search_every, self._runs_to_search = 1, 0

    def _post_run_cell(self, _result) -> None:
        self._running = None
        waiting = [view for view in self._waiting if not self._cells.get(view) and view.comm is not None]
        if not waiting:
            return
        if self._runs_to_search > 0:
            self._runs_to_search -= 1
            return
        reached = _reached(self._shell, waiting)
        if reached is None or reached:  # still kept (or too much to search): look again later
            self._search_every = min(2 * self._search_every, MAX_SEARCH_EVERY)
            self._runs_to_search = self._search_every - 1
        if reached is None:
            return
        for view in waiting:
            if id(view) not in reached:
                self._waiting.discard(view)
                self._cells.pop(view, None)
                _forget_cached(self._shell, view)
                retire(view)


#: The kernel's one record (a forked kernel starts with an empty one: no view is made before a fork).
VIEWS = _Views()


def _parent_metadata(shell) -> dict:
    kernel = getattr(shell, "kernel", None)
    parent = kernel.get_parent("shell") if kernel is not None else {}  # as pages.current_page reads it
    return (parent or {}).get("metadata") or {}


def _cell_id(shell) -> str | None:
    cell = _parent_metadata(shell).get("cellId")
    return cell if isinstance(cell, str) and cell else None


def _deleted_cells(shell) -> list[str]:
    deleted = _parent_metadata(shell).get("deletedCells") or []
    return [cell for cell in deleted if isinstance(cell, str)] if isinstance(deleted, list) else []


def _user_roots(shell) -> list:
    """The user's names' values, but what IPython put there itself (``In``, ``Out``, ``_``, ``_5``, ...,
    each found as the value IPython recorded as hidden)."""
    hidden = shell.user_ns_hidden
    return [value for name, value in shell.user_ns.items()
            if not (name in hidden and hidden[name] is value) and not _CACHED_RESULT.fullmatch(name)]


def _reached(shell, views: list[Widget]) -> set[int] | None:
    """The ids of those of ``views`` that the user's names or an open widget outside them reach (any of
    their widgets: a part the user kept keeps its view), or None when the search passed ``SEARCH_LIMIT``."""
    owner = {id(node): id(view) for view in views for node in widget_tree(view)}
    stack = _user_roots(shell) + [widget for widget in list(_instances.values()) if id(widget) not in owner]
    # Never walked into: the kernel and shell (they reach everything), comms (a comm reaches only its own
    # widget, through its callback), loggers, every module's names,
    # and the registry itself (a user who imported it holds every widget through it).
    skipped = {id(shell), id(getattr(shell, "kernel", None)), id(shell.user_ns), id(shell.user_ns_hidden),
               id(_instances)}
    skipped.update(id(vars(module)) for module in list(sys.modules.values()) if isinstance(module, types.ModuleType))
    seen: set[int] = set()
    reached: set[int] = set()
    while stack:
        item = stack.pop()
        key = id(item)
        if key in seen or key in skipped or isinstance(item, _LEAVES):
            continue
        seen.add(key)
        if len(seen) > SEARCH_LIMIT:
            return None
        if key in owner:
            reached.add(owner[key])
            if len(reached) == len(views):
                return reached
        if isinstance(item, type):
            if item.__module__ != "__main__":
                continue  # a library's class: its class-wide values are the library's, not the user's
        elif type(item).__module__.split(".", 1)[0] in _NOT_THE_USERS:
            continue
        stack.extend(gc.get_referents(item))
    return reached


def _forget_cached(shell, view: Widget) -> None:
    """Takes ``view`` out of IPython's output cache (``Out[5]``, ``_5``, ``_``, ``__``, ``___``)."""
    user_ns, hidden = shell.user_ns, shell.user_ns_hidden
    output = user_ns.get("_oh")
    if isinstance(output, dict):
        for number in [number for number, value in output.items() if value is view]:
            del output[number]
            for namespace in (user_ns, hidden):
                if namespace.get(f"_{number}") is view:
                    del namespace[f"_{number}"]
    hook = getattr(shell, "displayhook", None)
    for name in ("_", "__", "___"):
        if user_ns.get(name) is view and hidden.get(name) is view:
            user_ns[name] = hidden[name] = ""  # IPython's own empty value: it goes on updating them
        if hook is not None and getattr(hook, name, None) is view:
            setattr(hook, name, "")
