"""What the pages' server leaves out of its log (deploy/voila/voila.py's logging_config)."""

import logging

#: jupyter_server's contents manager's message at every load of an unsigned notebook.
UNTRUSTED = "Notebook %s is not trusted"


class NotebookTrustNoise(logging.Filter):
    """Drops "Notebook ... is not trusted", logged at every visit.

    jupyter_server's contents manager checks a notebook's signature whenever it loads it; in
    JupyterLab the answer decides whether the notebook's stored outputs (HTML, scripts) are shown.
    Voila shows none of the stored outputs: it runs the notebook and shows what that run makes. The
    line only said, on every visit, that the shipped notebooks carry no signature, which they cannot:
    a signature is made with each user's own secret. Every other record passes.
    """

    def filter(self, record: logging.LogRecord) -> bool:
        return record.msg != UNTRUSTED
