# Voila configuration for the demo and study pages (scripts/serve-demo.sh, scripts/serve-study.sh).
# Voila 0.5 reads it as its "voila" config file: pass --Voila.config_file_paths=<this folder>.
# tests/browser/test_kiosk.py checks these values and what they do; benchmarks/bench_kiosk.py
# measures memory and time to interactive with and without them.
import os
import sys
import tempfile
from pathlib import Path

c = get_config()  # noqa: F821 (traitlets' config loader provides it)

# The kernel manager below lives beside this file; the server imports it by name.
sys.path.insert(0, str(Path(__file__).resolve().parent))

# --- Kernels leave when their page leaves ------------------------------------------------------
# Voila's page asks for its kernel's shutdown on `beforeunload` (a sendBeacon POST to
# /voila/api/shutdown/<kernel>), but the page never receives an _xsrf cookie, so the server
# refuses every such POST with 403 "'_xsrf' argument missing from POST" (voila-dashboards/voila
# issue 1458) and each visit keeps its ~200 MB kernel for good. Voila serves these pages without
# authentication, so the XSRF check guards nothing here: every endpoint it would protect needs
# a kernel's random id, which only that kernel's page knows.
#
# --- Extensions' scripts come from the browser's cache -----------------------------------------
# Voila serves the widget extensions' scripts (/voila/labextensions/) with "no-cache", so every
# visit of a warm kiosk asks the server again for each of them (a 304 each, 20-30 requests in
# three rounds: entry points, their chunks, the widgets' chunks once the states arrived) before
# the widget manager can start. Every file a page asks for there has its content's hash in its
# name (remoteEntry.<hash>.js, <n>.<hash>.js?v=<hash>; an upgraded extension gets new names in
# the page's config), so jupyter_server's immutable cache for that prefix is exact. (A server run
# under another --Voila.base_url keeps Voila's revalidation: the prefix no longer matches.)
c.Voila.tornado_settings = {"disable_check_xsrf": True, "static_immutable_cache": ["/voila/labextensions/"]}

# --- Kernels over IPC sockets, not TCP ports ---------------------------------------------------
# jupyter_client picks a kernel's five ports by binding port 0 and closing it again; the preheated
# pools below start their kernels at the same moment, and any process can take such a port before
# the kernel binds it. That kernel dies at start, and Voila 0.5 then keeps the visitor's page
# loading for ever (the renderer's task fails and never ends the streamed page). IPC sockets have
# no ports to collide on; they live in Voila's private (0700) connection folder, a fresh
# voila_<random> in connection_dir_root, and a socket's path may have at most 107 bytes.
_connection_root = tempfile.gettempdir()
if len(f"{_connection_root}/voila_xxxxxxxx/kernel-{'0' * 36}-ipc-5") > 107:
    _connection_root = "/tmp"
c.Voila.connection_dir_root = _connection_root
c.KernelManager.transport = "ipc"

# --- Online arrivals turned away before a kernel starts ----------------------------------------
# A link to the online study page that names no usable participant, or a new participant while
# the server is at capacity ($MT_WIDGETS_STUDY_MAX_PARTICIPANTS, $MT_WIDGETS_STUDY_MIN_FREE_MIB),
# gets a plain page in words from the server itself: no kernel starts for them (the preheated
# spare stays for the next participant) and nothing is recorded (deploy/voila/arrival_gate.py).
import arrival_gate  # noqa: E402 (beside this file, found through the path set above)

arrival_gate.install()

# --- Kernels forked from a template, not started -----------------------------------------------
# Every page's kernel is forked from one template process this server starts now, which has
# imported numpy, numba, ipywidgets, ipycanvas and the widgets (mt_widgets/kernels/): a kernel
# is there in milliseconds instead of importing them for about 2 s of CPU, and shares their
# memory copy-on-write with the template and the other pages' kernels. What a page may do is
# unchanged: Voila's server still relays no code from the page, and each kernel is its own
# process with its own connection file and key. The template starts with the first kernel, which
# the preheated pools below ask for at the server's start. MT_KERNEL_TEMPLATE=off in the server's
# environment starts kernels the usual way.
c.MultiKernelManager.kernel_manager_class = "mt_widgets.kernels.provisioner.ForkingKernelManager"
# The template also imports voila.utils, whose get_query_string every page's first cell imports:
# it imports Voila's server side (jupyter_server, jupyter_events, jsonschema and its format
# checkers' rfc3987_syntax, which builds about forty parsers), 7-10 s of CPU per kernel on this
# 2-core machine, by far the largest part of a page's start (benchmarks/bench_online.py --burst).
os.environ.setdefault("MT_KERNEL_TEMPLATE_PRELOAD", "numpy,numba,ipywidgets,mt_widgets,mt_widgets.study,"
                      "mt_widgets.widgets,mt_widgets.apps.study,voila.utils")

# --- Idle-kernel culling: what the beacon cannot catch -----------------------------------------
# A tab that vanishes without `beforeunload` (a crashed or killed browser, a phone that
# discards a background tab, a lost network) leaves a kernel with no page. jupyter_server's
# culler (Voila 0.5 uses jupyter_server's AsyncMappingKernelManager, and its own subclass never
# culls kernels still waiting in the preheated pool) shuts a kernel down once it has been idle
# for cull_idle_timeout seconds, checking every cull_interval seconds.
# - 600 s: a visitor who steps away for a few minutes and whose phone drops the websocket comes
#   back to a live page (the page reconnects to its kernel); an abandoned kernel is gone within
#   cull_idle_timeout + cull_interval = 11 minutes.
# - cull_connected = False: a kernel whose page is still open is somebody's page (the kiosk's
#   own screen, a participant reading consent text); culling it would leave that page with dead
#   buttons. Open pages are the legitimate load; the culler removes what no page uses.
# - cull_busy = False: a busy kernel is computing for its page (a reproduction).
c.MappingKernelManager.cull_idle_timeout = 600
c.MappingKernelManager.cull_interval = 60
c.MappingKernelManager.cull_connected = False
c.MappingKernelManager.cull_busy = False
# Voila's preheating keeps spares out of the culler only while they wait in the pool; this
# manager also spares a kernel in the second between a visitor taking it and the page
# connecting (deploy/voila/kiosk_kernels.py says why).
c.VoilaConfiguration.multi_kernel_manager_class = "kiosk_kernels.KioskKernelManager"

# --- Preheated kernels: only for the pages that need them --------------------------------------
# Preheating runs a page's notebook in a spare kernel before anyone asks for it, so a visitor
# gets an executed page instead of waiting for a kernel to start and import numpy, numba and
# ipycanvas (benchmarks/bench_kiosk.py, times taken in the page: the demo page's warm time to
# interactive is about 1.2-1.4 s without the spare and 0.8-1.0 s with it). One spare kernel per
# page: visitors arrive one at a time at a kiosk, and the pool refills within a few seconds; every
# spare costs a kernel's memory all day. The other
# notebooks of notebooks/ get no spare (analysis.ipynb does heavy work on open, study_uarm.ipynb
# talks to hardware), which matters when the whole folder is served.
c.VoilaConfiguration.preheat_kernel = True
c.VoilaKernelManager.kernel_pools_config = {
    "default": {"pool_size": 0},
    "demo.ipynb": {"pool_size": 1},
    "study_sim.ipynb": {"pool_size": 1},
    "study_online.ipynb": {"pool_size": 1},
}
# Refill the pool 3 s after a visitor takes the spare, once the visitor's page is interactive. A
# refill (a kernel starting, importing numpy, numba and ipycanvas, running the page) takes about
# 2.5 s of CPU; started at once (fill_delay = 0) it competed with the visitor's own page, server
# and browser for the 2 cores during the very seconds the page becomes interactive.
# benchmarks/bench_kiosk.py, one run, 8 warm visits each, load average 3.1-3.5 from the benchmark
# itself: refill at once p50 2.52 s / p95 2.96 s, after 3 s p50 1.91 s / p95 2.37 s, stock Voila
# 4.44 s (the ratio to stock goes from 0.57 to 0.43); a warm visit's p95 stays under the 3 s. The
# price: a second visitor within 3 s of the first waits for the delay and the spare's start (about
# 3 s more than now, like a page without preheating); a kiosk's visitors come one at a time.
# (An earlier 5 s delay, priced at load average 10 and 25 on a shared machine, was inconclusive.)
c.VoilaKernelManager.fill_delay = 3.0

# --- Only the extensions a page uses ----------------------------------------------------------
# Voila loads every JupyterLab extension installed beside it before it starts the widget
# manager: three of them have nothing to do on these pages (nbgrader's and Jupyter Notebook's
# Lab extensions, the pygments theme for code, which Voila strips), about 12 requests and
# 0.2 MB of scripts to fetch and run before the first widget. The widgets' own
# (@jupyter-widgets/jupyterlab-manager, ipycanvas, anywidget: the canvas's accessibility layer and
# the study pages' navigation, Voila's widgets manager) stay.
c.VoilaConfiguration.extension_denylist = ["@jupyter/nbgrader", "@jupyter-notebook/lab-extension",
                                           "jupyterlab_pygments"]

# --- The server's log at INFO, its logger too -------------------------------------------------
# traitlets sets an application's logger to DEBUG and filters at its handler (INFO by default),
# so each of the many debug calls on a message's way through the server (the websocket relay,
# the kernel manager) still builds a log record that the handler then drops: about a tenth of
# the server's CPU per relayed widget message (py-spy on a skill click). INFO at the logger
# skips them. To see debug lines, run with --Voila.logging_config='{}' --Voila.log_level=DEBUG.
# "Notebook ... is not trusted", logged at every visit, is left out: Voila shows no stored output,
# which is all a notebook's trust decides (deploy/voila/log_filters.py).
c.Voila.logging_config = {"filters": {"notebook_trust": {"()": "log_filters.NotebookTrustNoise"}},
                          "loggers": {"Voila": {"level": "INFO", "filters": ["notebook_trust"]}}}

# No tracebacks on a public page: errors go to the server's log.
c.VoilaConfiguration.show_tracebacks = False

# --- Nothing from the internet ------------------------------------------------------------------
# Voila's lab template links Font Awesome from a CDN (cdn.jsdelivr.net), so every page waited on
# the internet, and without it (a classroom offline, a kiosk on a closed network) the request
# failed. The "mt-widgets" template beside this file (jupyter/voila/templates/mt-widgets/) is the
# lab template without those links: Voila's own bundle, which the server sends, already carries
# Font Awesome 5 (with the v4 names ipywidgets' icons use) and its fonts. Voila finds templates
# in the Jupyter data folders; this folder joins them (JUPYTER_PATH, read when the server collects
# the template's folders, after this file). tests/browser/test_demo_offline.py records the requests.
_templates_root = str(Path(__file__).resolve().parent / "jupyter")
if _templates_root not in os.environ.get("JUPYTER_PATH", "").split(os.pathsep):
    os.environ["JUPYTER_PATH"] = os.pathsep.join(p for p in (_templates_root, os.environ.get("JUPYTER_PATH")) if p)
c.VoilaConfiguration.template = "mt-widgets"
