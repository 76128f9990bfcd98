"""The public names the API reference documents: every name in the ``__all__`` of ``mt_widgets`` and
of each of its subpackages, each documented once, on its own page.

A name that several packages export (``mt_widgets.SKILLS`` is ``mt_widgets.core.SKILLS``) is
documented where it is defined and listed, with a link, on the other packages' pages: two pages
for one object would make Sphinx warn of a duplicate description. docs/conf.py writes the
packages' pages from this at every build; tests/docs/test_docs_build.py checks the built site
holds a page for every name.
"""

from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass

#: The packages in the order their names are claimed: the science first, the top-level package,
#: which re-exports the science's most used names, last.
ORDER = ("core", "arms", "study", "in_silico", "analysis", "widgets", "hardware", "classroom", "apps")


@dataclass(frozen=True)
class PublicName:
    """One name of one package's ``__all__`` and where it is documented."""

    package: str  #: the package that exports it, e.g. ``mt_widgets``
    name: str  #: its name there, e.g. ``SKILLS``
    documented_as: str  #: the full name of its one API page, e.g. ``mt_widgets.core.SKILLS``

    @property
    def full_name(self) -> str:
        return f"{self.package}.{self.name}"

    @property
    def is_reexport(self) -> bool:
        return self.full_name != self.documented_as


def packages() -> list[str]:
    """``mt_widgets`` and its subpackages, the ones of ``ORDER`` first."""
    import mt_widgets

    found = [info.name for info in pkgutil.iter_modules(mt_widgets.__path__) if info.ispkg]
    ordered = [name for name in ORDER if name in found] + sorted(set(found) - set(ORDER))
    return [f"mt_widgets.{name}" for name in ordered] + ["mt_widgets"]


def public_names() -> list[PublicName]:
    """Every package's ``__all__``, in the order of ``packages()``, each name with its one page."""
    claimed: list[tuple[object, str]] = []   # (object, the full name documenting it)
    names = []
    for package in packages():
        module = importlib.import_module(package)
        if not hasattr(module, "__all__"):
            raise RuntimeError(f"{package} has no __all__: the API reference documents the names a package lists "
                               f"there, so every package of mt_widgets lists its public names")
        for name in module.__all__:
            value = getattr(module, name)
            documented_as = next((full for obj, full in claimed
                                  if obj is value and full.rsplit(".", 1)[1] == name), None)
            if documented_as is None:
                documented_as = f"{package}.{name}"
                claimed.append((value, documented_as))
            names.append(PublicName(package, name, documented_as))
    return names
