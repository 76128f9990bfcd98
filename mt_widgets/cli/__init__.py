"""The ``mt-widgets`` command: what ``scripts/*.sh`` do from a clone, after a plain ``pip install``.

``mt-widgets lab [FOLDER]`` copies the tutorials and notebooks into a folder and opens JupyterLab
there; ``mt-widgets demo`` serves the visitors' demo with Voila;
``mt-widgets study serve|status|export|withdraw`` serves and looks after a study;
``mt-widgets course check`` and ``mt-widgets hub check`` read a class folder and a class roster. One module per concern:
``shipped`` (where the notebooks and server settings are), ``servers`` (lab, demo, study pages),
``study`` (a study folder's status, export and withdrawal), ``classroom`` (course and hub checks).
"""

from .main import build_parser, main

__all__ = ["build_parser", "main"]
