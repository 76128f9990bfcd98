"""The build step that ships the notebooks in the wheel; everything else is in pyproject.toml.

The repository keeps one copy of each notebook, at the top (tutorials/, notebooks/) where the
tests, Binder and the lab use them. A wheel copies them, with deploy/voila's server settings,
into mt_widgets/_data/ (mt_widgets/cli/shipped.py reads them there), so ``mt-widgets lab`` and
``mt-widgets demo`` work without a clone. An editable install reads them in place.
"""

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent
# The same as mt_widgets/cli/shipped.py's SHIPPED (tests/install/test_shapes.py checks the wheel).
SHIPPED = {"tutorials": ("*.ipynb", "*.toml"), "notebooks": ("*.ipynb", "*.toml"),
           "deploy/voila": ("*.py", "jupyter/voila/templates/*/*")}


class BuildWithNotebooks(build_py):
    def run(self):
        super().run()
        if getattr(self, "editable_mode", False):
            return
        for folder, patterns in SHIPPED.items():
            target = Path(self.build_lib) / "mt_widgets" / "_data" / folder
            for pattern in patterns:
                for source in sorted((HERE / folder).glob(pattern)):
                    copy = target / source.relative_to(HERE / folder)   # a template keeps its folders
                    copy.parent.mkdir(parents=True, exist_ok=True)
                    self.copy_file(str(source), str(copy))


setup(cmdclass={"build_py": BuildWithNotebooks})
