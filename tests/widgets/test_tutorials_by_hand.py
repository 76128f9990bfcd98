"""Tutorials 06, 08 and 13 run whether the student drew by hand first (none, some or every arrow) or not.

Each tutorial's code cells run in order, as Shift+Enter runs them; after the cell that shows the
widget, a "student" confirms arrows on it as the pointer does. The cells that follow must pass
their own assertions and leave the student's arrows as they were.
"""

import json
from pathlib import Path

import pytest

TUTORIALS = Path(__file__).resolve().parents[2] / "tutorials"


def code_cells(name: str) -> list[str]:
    cells = json.loads((TUTORIALS / name).read_text())["cells"]
    return ["".join(cell["source"]) for cell in cells if cell["cell_type"] == "code"]


def run_drawing_by_hand(name: str, widget_name: str, draw) -> dict:
    namespace: dict = {}
    drawn = False
    for source in code_cells(name):
        exec(compile(source, name, "exec"), namespace)
        if not drawn and widget_name in namespace:
            draw(namespace[widget_name])
            drawn = True
    assert drawn
    return namespace


def confirm_by_pointer(teach, count: int) -> None:
    for _ in range(count):
        teach.set_action([0.4, 0.2], method="pointer")
        teach.confirm()


@pytest.mark.parametrize("count", [0, 2, 5])
def test_tutorial_06_after_drawing_by_hand(recorder, count, monkeypatch):
    monkeypatch.delenv("MT_WIDGETS_CLASS_FOLDER", raising=False)
    namespace = run_drawing_by_hand("06_drawing_a_demonstration.ipynb", "teach",
                                    lambda teach: confirm_by_pointer(teach, count))
    teach = namespace["teach"]
    assert teach.state_index == count and teach.demonstrations == [[0.4, 0.2]] * count


@pytest.mark.parametrize("count", [0, 2, 5])
def test_tutorial_08_after_drawing_by_hand(recorder, count, monkeypatch):
    monkeypatch.delenv("MT_WIDGETS_CLASS_FOLDER", raising=False)

    def draw(episode):
        for _ in range(count):
            episode.teaching.set_action([0.4, 0.2], method="pointer")
            episode.teaching.confirm()

    namespace = run_drawing_by_hand("08_one_full_episode.ipynb", "episode", draw)
    episode = namespace["episode"]
    assert len(episode.demonstrations) == count
    assert episode.phase == ("finished" if count == 5 else "teaching")


@pytest.mark.slow   # the whole tutorial 13 (UR5 query states, reproductions, a URDF arm): about 5-10 s each
@pytest.mark.parametrize("count", [0, 2, 4])
def test_tutorial_13_after_drawing_a_3d_demonstration_by_hand(recorder, count, monkeypatch):
    monkeypatch.delenv("MT_WIDGETS_CLASS_FOLDER", raising=False)

    def draw(episode):
        for _ in range(count):   # an arrow dragged in the top view, confirmed, then past machine teaching's arrow
            episode.teaching.set_action([0.05, -0.04, -0.03], method="pointer")
            episode.teaching.confirm()
            episode.next()

    namespace = run_drawing_by_hand("13_teaching_an_industrial_arm.ipynb", "teach_ur5", draw)
    teach = namespace["teach_ur5"]
    assert teach.demonstrations == [[0.05, -0.04, -0.03]] * count
    assert teach.phase == ("finished" if count == 4 else "teaching")
    assert (teach.result is not None) == (count == 4)
    assert namespace["by_code"].result.theta_error < 1e-12
