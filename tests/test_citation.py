"""CITATION.cff: the paper mt-widgets implements, with its authors right, and the software's version."""

from pathlib import Path

import pytest

yaml = pytest.importorskip("yaml")  # PyYAML comes with the lab's Jupyter stack

ROOT = Path(__file__).resolve().parents[1]
PAPER = "Using Machine Teaching to Boost Novices' Robot Teaching Skill"
AUTHORS = [("Zhu", "Yuqing"), ("Sun", "Endong"), ("Howard", "Matthew")]


def _names(entry):
    return [(a["family-names"], a["given-names"]) for a in entry["authors"]]


def test_the_citation_names_the_paper_its_authors_and_both_versions():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software"
    paper = cff["preferred-citation"]
    assert paper["title"] == PAPER and _names(paper) == AUTHORS
    assert "ICRA" in paper["collection-title"] and paper["year"] == 2026
    (preprint,) = [r for r in cff["references"] if r["title"] == PAPER]
    assert _names(preprint) == AUTHORS and preprint["url"].endswith("2409.15563")


def test_the_citation_gives_the_packages_version():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    version = [line for line in (ROOT / "pyproject.toml").read_text(encoding="utf-8").splitlines()
               if line.startswith("version = ")]
    assert version == [f'version = "{cff["version"]}"']
