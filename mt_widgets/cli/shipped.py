"""Where the notebooks, the tutorials and the Voila settings are, installed or in a clone.

A wheel carries them inside the package, under ``mt_widgets/_data/`` (setup.py's build step
copies ``tutorials/``, ``notebooks/`` and ``deploy/voila/`` there), so the repository keeps one
copy of each notebook. An editable install or a clone has no ``_data``: the folders are read
where they are, at the repository's root beside the package.
"""

from __future__ import annotations

import shutil
from pathlib import Path

PACKAGE_ROOT = Path(__file__).resolve().parents[1]
#: What the wheel ships, as (folder inside the repository, file patterns).
#: deploy/voila's template (the lab template without its CDN links) keeps its folders: Voila finds it
#: as jupyter/voila/templates/mt-widgets/ under a Jupyter data folder (deploy/voila/voila.py).
SHIPPED = {"tutorials": ("*.ipynb", "*.toml"), "notebooks": ("*.ipynb", "*.toml"),
           "deploy/voila": ("*.py", "jupyter/voila/templates/*/*")}
START_HERE = "tutorials/00_start_here.ipynb"


def shipped_folder(name: str) -> Path:
    """The folder ``name`` (a key of ``SHIPPED``) of this installation.

    Raises:
        FileNotFoundError: neither the package's ``_data`` nor a repository beside it holds it.
    """
    if name not in SHIPPED:
        raise ValueError(f"name: expected one of {sorted(SHIPPED)}, got {name!r}")
    for root in (PACKAGE_ROOT / "_data", PACKAGE_ROOT.parent):
        if (root / name).is_dir() and any((root / name).glob(SHIPPED[name][0])):
            return root / name
    raise FileNotFoundError(f"{name}: not in this installation of mt-widgets ({PACKAGE_ROOT / '_data'} "
                            f"nor {PACKAGE_ROOT.parent}); reinstall it from a wheel or a clone")


def shipped_files(name: str) -> list[Path]:
    """The files of the shipped folder ``name``, sorted."""
    folder = shipped_folder(name)
    return sorted({path for pattern in SHIPPED[name] for path in folder.glob(pattern) if path.is_file()})


def copy_notebooks(folder) -> tuple[list[Path], list[Path]]:
    """Copies the tutorials and the notebooks into ``folder``/tutorials and ``folder``/notebooks
    (the tutorials link to ``../notebooks``). A file already there is kept, never overwritten: it
    may hold the user's work. Returns (copied, kept)."""
    folder = Path(folder).expanduser()
    if folder.exists() and not folder.is_dir():
        raise NotADirectoryError(f"folder: expected a folder for the tutorials, got the file {folder}")
    copied, kept = [], []
    for name in ("tutorials", "notebooks"):
        target = folder / name
        target.mkdir(parents=True, exist_ok=True)
        for source in shipped_files(name):
            destination = target / source.name
            if destination.exists():
                kept.append(destination)
            else:
                shutil.copyfile(source, destination)
                copied.append(destination)
    return copied, kept


def copy_report(folder, copied: list, kept: list) -> str:
    """What ``copy_notebooks`` did, in words: "FOLDER: 1 file copied, 23 already there (kept as they are)"."""
    def files(n: int) -> str:
        return f"{n} file" if n == 1 else f"{n} files"

    return f"{folder}: {files(len(copied))} copied, {len(kept)} already there (kept as they are)"
