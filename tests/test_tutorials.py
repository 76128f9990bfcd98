"""Promises the tutorials make to a reader (issue 13): each one says what it teaches and how long it
takes, asks the reader to predict before it shows, ends with a summary and its references, and
asserts the numbers it teaches. The notebooks themselves run under nbval (``--nbval-lax``); these
checks read them without a kernel, so a tutorial that loses its objectives or its assertions fails
here even when it still runs.
"""

import json
import re
from pathlib import Path

import pytest

TUTORIALS = Path(__file__).resolve().parents[1] / "tutorials"
NOTEBOOKS = sorted(TUTORIALS.glob("[0-9][0-9]_*.ipynb")) + sorted(TUTORIALS.glob("appendix_*.ipynb"))

#: The theory path the course's graded exercises follow, in order (tutorials 02-05).
THEORY_PATH = ["02_ridge_regression", "03_machine_teaching", "04_the_teaching_bound",
               "05_query_states_and_conditioning"]

REFERENCES = ["arXiv:2409.15563", "Liu, J., Zhu, X. (2016)", "Zhu, X., Singla, A., Zilles, S., Rafferty, A. N. (2018)",
              "Sena, A., Howard, M. (2020)", "Khan, F., Zhu, X., Mutlu, B. (2011)"]


def cells(path: Path, kind: str | None = None) -> list[str]:
    notebook = json.loads(path.read_text())
    return ["".join(c["source"]) for c in notebook["cells"] if kind is None or c["cell_type"] == kind]


def test_there_are_tutorials_and_appendices():
    names = [p.stem for p in NOTEBOOKS]
    assert len(names) >= 14, names
    assert any(n.startswith("appendix_") for n in names)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_tutorial_opens_with_objectives_and_a_time(path):
    first = cells(path)[0]
    assert first.startswith("# "), f"{path.name}: the first cell should be the title"
    assert re.search(r"\*\*Time:\*\* about \d+ minutes", first), f"{path.name}: no time estimate at the top"
    assert "**By the end you can**" in first, f"{path.name}: no learning objectives at the top"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_tutorial_asks_to_predict_then_checks(path):
    markdown = cells(path, "markdown")
    predicts = [i for i, text in enumerate(markdown) if "**Predict" in text]
    assert predicts, f"{path.name}: no predict-then-check question"
    assert any("**Check.**" in text for text in markdown[predicts[0]:]), f"{path.name}: a prediction is never checked"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_tutorial_ends_with_what_you_learnt_and_references(path):
    markdown = cells(path, "markdown")
    assert any(text.startswith("## What you learnt") for text in markdown[-3:]), f"{path.name}: no summary at the end"
    references = next((text for text in markdown[-2:] if text.startswith("## References")), "")
    missing = [r for r in REFERENCES if r not in references]
    assert not missing, f"{path.name}: references missing {missing}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_tutorial_asserts_what_it_teaches(path):
    asserts = sum(len(re.findall(r"^\s*assert ", text, flags=re.M)) for text in cells(path, "code"))
    assert asserts >= 1, f"{path.name}: asserts nothing, so a wrong number would pass"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_plots_end_without_an_object_repr(path):
    for text in cells(path, "code"):
        if "plt.subplots" in text:
            last = text.rstrip().splitlines()[-1]
            shown = "plt.show()" in text or last.rstrip().endswith(";")
            assert shown, f"{path.name}: a plot cell ends with {last!r}: end it with plt.show() or ';'"


def test_theory_path_in_order_with_live_sliders():
    names = [p.stem for p in NOTEBOOKS]
    assert names[2:6] == THEORY_PATH, names
    for stem in ("02_ridge_regression", "05_query_states_and_conditioning"):
        code = cells(TUTORIALS / f"{stem}.ipynb", "code")
        interactive = [text for text in code if "interact(" in text]
        assert interactive, f"{stem}: no slider"
        redraw = re.search(r"interact\((\w+)", interactive[0]).group(1)
        # The redraw function is also called from code, so that nbval runs it.
        assert any(re.search(rf"\b{redraw}\(", text) for text in code if "interact(" not in text), stem


def test_the_teaching_dimension_warning_is_shown():
    code = "\n".join(cells(TUTORIALS / "03_machine_teaching.ipynb", "code"))
    assert "UnderdeterminedTeachingWarning" in code and "caught[0].message" in code


def test_the_capstone_replaces_the_phase_notebooks():
    names = [p.stem for p in NOTEBOOKS]
    assert "10_protocol_capstone" in names
    assert not [n for n in names if re.match(r"\d\d_p[1-5]_", n)], names
    capstone = "\n".join(cells(TUTORIALS / "10_protocol_capstone.ipynb", "code"))
    # The student's own run is logged in a study folder that tutorial 11 reads.
    assert "start_participant" in capstone and "read_study(folder)" in capstone
    assert "read_study(folder)" in "\n".join(cells(TUTORIALS / "11_reading_the_results.ipynb", "code"))


@pytest.mark.parametrize("path", [p for p in NOTEBOOKS if p.stem[:2].isdigit() and p.stem[:2] != "00"],
                         ids=lambda p: p.stem)
def test_tutorial_records_the_students_progress_for_the_class_view(path):
    # Issue 12: a student's lessons feed the instructor's class view (when a class folder is set).
    code = "\n".join(cells(path, "code"))
    assert f'progress.lesson("{path.stem}")' in code, f"{path.name}: does not record that the lesson was opened"
    # The episode a student teaches is named ``episode``; other widgets are code-driven checks.
    if re.search(r"^episode = EpisodeWidget\(", code, flags=re.M):
        assert f'progress.attach(episode, "{path.stem}")' in code, \
            f"{path.name}: the student's episode is not followed by the class progress recorder"


def test_a_tutorials_episode_reaches_the_class_folder(tmp_path, monkeypatch):
    # Run tutorial 08's first code cells as a student would, with the instructor's class folder set.
    from mt_widgets.classroom import read_class

    monkeypatch.setenv("MT_WIDGETS_CLASS_FOLDER", str(tmp_path))
    monkeypatch.setenv("MT_WIDGETS_STUDENT", "ada")
    namespace: dict = {}
    for source in cells(TUTORIALS / "08_one_full_episode.ipynb", "code")[:2]:
        exec(compile(source, "08_one_full_episode", "exec"), namespace)
    # The student teaches the episode the tutorial shows them (here through the widget's own
    # demonstrate, as the canvas does for a drawn arrow): that episode is the one recorded.
    episode = namespace["episode"]
    for action in episode.optimal:
        episode.demonstrate(1.3 * action)
    (student,) = read_class(tmp_path).students.values()
    kinds = [event["kind"] for event in student.events]
    assert kinds[0] == "lesson" and kinds.count("demonstration") == 5 and kinds[-1] == "episode"
    assert student.events[-1]["theta_error"] == pytest.approx(episode.result.theta_error)
