"""A study server at the widget-state level: the online page's Python objects behind HTTP, one per open page.

For tests/study_shards/test_several_servers.py. A Voila server runs each participant's page in a
kernel of its own, built by notebooks/study_online.ipynb as ``OnlineStudyPage(protocol, folder,
query)``, and the page's buttons reach it over the kernel's websocket. This server does the same
with the same object, without the kernels and the browser (so thirty participants fit in a test
of the slow tier): a page's render URL builds the page and answers with a kernel id; a kernel's
URL acts on that page (``act`` of tests/study_pages/support.py: what the buttons do);
deleting a kernel ends its page, as Voila's shutdown of a page's kernel does on unload. Like
Voila's, its kernels die with the server: a participant whose server was restarted reloads their
page, and the page resumes them from the study folder.

Run: ``python page_server.py --port P --name N --protocol FILE --folder STUDY_FOLDER``.
"""

from __future__ import annotations

import argparse
import json
import secrets
import sys
import traceback
from http.server import BaseHTTPRequestHandler, HTTPServer
from pathlib import Path
from urllib.parse import urlsplit

sys.path[:0] = [str(Path(__file__).resolve().parents[1]), str(Path(__file__).resolve().parents[2])]

from blinding_support import participant_texts  # noqa: E402
from mt_widgets.apps.study import OnlineStudyPage  # noqa: E402
from study_pages.support import act  # noqa: E402

RENDER = "/voila/render/study_online.ipynb"


def describe(page) -> dict:
    """What the test reads of a page: the participant, their step, the words shown."""
    session = page.session
    state = {"participant": None, "step": None, "finished": None,
             "text": " ".join(participant_texts(page))[:4000]}
    if session is not None:
        state["participant"] = session.participant
        state["finished"] = session.finished
        if not session.finished:
            step = session.current_step()
            state["step"] = [step.kind, step.phase, step.index]
    return state


def serve(port: int, name: str, protocol: str, folder: str) -> None:
    kernels: dict[str, OnlineStudyPage] = {}

    class Handler(BaseHTTPRequestHandler):
        def reply(self, status: int, body: dict) -> None:
            data = json.dumps({"server": name, **body}).encode()
            self.send_response(status)
            self.send_header("Content-Type", "application/json")
            self.send_header("Content-Length", str(len(data)))
            self.send_header("X-Study-Server", name)
            self.end_headers()
            self.wfile.write(data)

        def do_GET(self):  # noqa: N802 (http.server's name)
            url = urlsplit(self.path)
            if url.path == "/health":
                return self.reply(200, {"kernels": len(kernels)})
            if url.path != RENDER:
                return self.reply(404, {"error": f"no page {url.path}"})
            page = OnlineStudyPage(protocol, folder, url.query, redirect_delay_s=0)
            kernel = secrets.token_hex(8)
            kernels[kernel] = page
            self.reply(200, {"kernel": kernel, **describe(page)})

        def do_POST(self):  # noqa: N802
            parts = urlsplit(self.path).path.strip("/").split("/")
            if len(parts) != 4 or parts[:2] != ["api", "kernels"] or parts[3] != "act":
                return self.reply(404, {"error": "no such endpoint"})
            page = kernels.get(parts[2])
            if page is None:  # as Voila's websocket to a kernel this server does not have
                return self.reply(404, {"error": "no such kernel"})
            try:
                act(page.view)
            except Exception as error:  # noqa: BLE001
                # A kernel logs an exception raised by a widget's message handler and lives on; the
                # page shows what its view made of it (a stale page: "open in another tab").
                traceback.print_exc()
                return self.reply(200, {**describe(page), "error": f"{type(error).__name__}: {error}"})
            self.reply(200, describe(page))

        def do_DELETE(self):  # noqa: N802
            parts = urlsplit(self.path).path.strip("/").split("/")
            page = kernels.pop(parts[2], None) if len(parts) == 3 and parts[:2] == ["api", "kernels"] else None
            if page is None:
                return self.reply(404, {"error": "no such kernel"})
            if page.session is not None:
                page.session.close()
            self.reply(200, {})

        def log_message(self, *args):  # the test reads the replies, not a log
            pass

    # One request at a time, as one kernel's messages are handled one at a time.
    HTTPServer(("127.0.0.1", port), Handler).serve_forever()


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--name", required=True)
    parser.add_argument("--protocol", required=True)
    parser.add_argument("--folder", required=True)
    args = parser.parse_args()
    serve(args.port, args.name, args.protocol, args.folder)
