"""A cell run again, or deleted, retires the episodes it made once nothing of the user's reaches them
(``mt_widgets/widgets/cells.py``): a real ipykernel, sent execute requests with the cell ids JupyterLab
sends (``cellId``, ``deletedCells``)."""

from __future__ import annotations

import json
import queue
import time

import pytest
from jupyter_client.manager import start_new_kernel

from mt_widgets.widgets.cells import MAX_SEARCH_EVERY

pytestmark = pytest.mark.slow

SETUP = """
import gc, json
import mt_widgets.widgets.animation as _animation
# No page answers receipts here: close at the kernel's own estimate of playback, with a short margin.
_animation.CLOSE_FALLBACK_S, _animation.CLOSE_MARGIN_S = 0.0, 0.2
from ipywidgets.widgets.widget import _instances
from mt_widgets.widgets import EpisodeWidget
from mt_widgets.widgets.cells import VIEWS

def _state(*names):
    gc.collect()
    return json.dumps({"open": len(_instances),
                       "episodes": sorted(w.model_id for w in _instances.values() if isinstance(w, EpisodeWidget)),
                       **{name: globals()[name].model_id for name in names}})
"""


class Kernel:
    def __init__(self):
        self.manager, self.client = start_new_kernel(kernel_name="python3")

    def run(self, code: str, cell: str | None = None, deleted: tuple[str, ...] = ()) -> str:
        metadata = {}
        if cell is not None:
            metadata["cellId"] = cell
        if deleted:
            metadata["deletedCells"] = list(deleted)
        content = {"code": code, "silent": False, "store_history": True, "user_expressions": {},
                   "allow_stdin": False, "stop_on_error": True}
        message = self.client.session.msg("execute_request", content, metadata=metadata)
        self.client.shell_channel.send(message)
        msg_id, printed, deadline = message["header"]["msg_id"], [], time.monotonic() + 120
        while True:
            try:
                reply = self.client.get_iopub_msg(timeout=max(0.1, deadline - time.monotonic()))
            except queue.Empty:
                raise AssertionError(f"no answer to {code!r} within 120 s") from None
            if reply["parent_header"].get("msg_id") != msg_id:
                continue
            kind = reply["msg_type"]
            if kind == "stream":
                printed.append(reply["content"]["text"])
            elif kind == "error":
                raise AssertionError("\n".join(reply["content"]["traceback"]))
            elif kind == "status" and reply["content"]["execution_state"] == "idle":
                return "".join(printed)

    def state(self, *names: str, cell: str = "probe") -> dict:
        # A probe cell of its own: running it retires nothing of the cells under test.
        return json.loads(self.run(f"print(_state{names!r})", cell=cell).strip().splitlines()[-1])

    def settle(self) -> dict:
        """The state once retired views had their close (the kernel's estimate of playback, plus its margin)."""
        self.run("import time; time.sleep(_animation.CLOSE_MARGIN_S + 0.5)")
        return self.state()

    def stop(self):
        self.client.stop_channels()
        self.manager.shutdown_kernel(now=True)


@pytest.fixture(scope="module")
def kernel():
    kernel = Kernel()
    kernel.run(SETUP)
    yield kernel
    kernel.stop()


def test_a_cell_run_again_retires_the_episode_it_made_and_frees_its_widgets(kernel):
    cell = "cell-again"
    kernel.run("episode = EpisodeWidget('sim-point', seed=1)", cell=cell)
    first = kernel.state("episode")
    kernel.run("episode = EpisodeWidget('sim-point', seed=2)", cell=cell)
    second = kernel.state("episode")
    after = kernel.settle()
    assert first["episode"] not in after["episodes"], "the replaced episode is still open"
    assert second["episode"] in after["episodes"], "the episode the cell made now was closed"
    # Every widget of the old episode went with it (and runs again cost nothing more).
    for seed in (3, 4, 5):
        kernel.run(f"episode = EpisodeWidget('sim-point', seed={seed})", cell=cell)
    assert kernel.settle()["open"] == after["open"]


def test_an_episode_shown_as_the_cells_result_leaves_the_output_cache_when_retired(kernel):
    cell = "cell-shown"
    kernel.run("shown = EpisodeWidget('sim-point', seed=1)\nshown", cell=cell)
    old = kernel.state("shown")["shown"]
    kernel.run("shown = EpisodeWidget('sim-point', seed=2)\nshown", cell=cell)
    assert old not in kernel.settle()["episodes"]
    cached = kernel.run("print([v.model_id for v in Out.values() if isinstance(v, EpisodeWidget)], "
                        "isinstance(_, EpisodeWidget) and _.model_id)")
    assert old not in cached, cached
    # IPython goes on caching results: the next result is ``_``.
    assert kernel.run("41 + 1\n", cell="cell-answer") == ""
    assert kernel.run("print(_)") .strip() == "42"


def test_an_episode_the_user_still_names_or_holds_is_kept(kernel):
    cell = "cell-kept"
    kernel.run("kept = EpisodeWidget('sim-point', seed=1)\nlater = kept", cell=cell)
    named = kernel.state("kept")["kept"]
    kernel.run("kept = EpisodeWidget('sim-point', seed=2)", cell=cell)
    assert named in kernel.settle()["episodes"], "an episode named by `later` was closed"
    # In a list, then in a closure: still reached.
    kernel.run("held = [later]; del later", cell="cell-other")
    kernel.run("kept = EpisodeWidget('sim-point', seed=3)", cell=cell)
    assert named in kernel.settle()["episodes"], "an episode held in a list was closed"
    kernel.run("def _make(e):\n    return lambda: e\nrecall = _make(held[0]); del held", cell="cell-other")
    kernel.run("kept = EpisodeWidget('sim-point', seed=4)", cell=cell)
    assert named in kernel.settle()["episodes"], "an episode held in a closure was closed"
    # Once nothing holds it, a later run of any cell retires it: a view the user keeps is searched for
    # again after 1, 2, 4, ... cell runs, at most MAX_SEARCH_EVERY apart.
    kernel.run("del recall", cell="cell-other")
    for _ in range(MAX_SEARCH_EVERY):
        kernel.run("pass", cell="cell-other")
    assert named not in kernel.settle()["episodes"]


def test_an_episode_shown_in_another_cell_stays_until_that_cell_goes_too(kernel):
    kernel.run("made = EpisodeWidget('sim-point', seed=1)", cell="cell-made")
    kernel.run("display(made)", cell="cell-display")
    old = kernel.state("made")["made"]
    kernel.run("made = EpisodeWidget('sim-point', seed=2)", cell="cell-made")
    assert old in kernel.settle()["episodes"], "an episode another cell still shows was closed"
    # That cell deleted (JupyterLab says so with the next execute request): now it goes.
    kernel.run("pass", cell="cell-next", deleted=("cell-display",))
    assert old not in kernel.settle()["episodes"]


def test_without_cell_ids_nothing_is_retired(kernel):
    kernel.run("plain = EpisodeWidget('sim-point', seed=1)")
    old = kernel.state("plain")["plain"]
    kernel.run("plain = EpisodeWidget('sim-point', seed=2)")
    assert old in kernel.settle()["episodes"], "a Voila-like kernel (no cell ids) had an episode closed"


def test_a_retired_episode_is_freed_at_its_close_without_waiting_for_pythons_collector(kernel):
    """A closed view is garbage in reference cycles. In a kernel forked from a frozen template, Python's
    own full collections came about every thirty episodes (animation.py, ``_collect_soon``); here they
    never come, and the episode must still be gone once it is closed."""
    cell = "cell-freed"
    # After a full collection every survivor (the first episode) is in the oldest generation, which
    # only a full collection visits; with its threshold out of reach, only an explicit one frees it.
    kernel.run("import weakref\nepisode = EpisodeWidget('sim-point', seed=1)\n_first = weakref.ref(episode)\n"
               "gc.collect(); gc.set_threshold(700, 10, 10**9)", cell=cell)
    try:
        kernel.run("episode = EpisodeWidget('sim-point', seed=2)", cell=cell)
        # The close comes CLOSE_MARGIN_S after the retire; its collection then, or once the kernel has
        # had COLLECTION_SHARE's due since the last one (a few seconds at most under load).
        deadline, freed = time.monotonic() + 30, "False"
        while freed.startswith("False") and time.monotonic() < deadline:
            time.sleep(0.2)
            freed = kernel.run("print(_first() is None, gc.get_threshold())").strip()
        assert freed == "True (700, 10, 1000000000)", freed
    finally:
        kernel.run("gc.set_threshold(700, 10, 10)")
