"""Flat over a long session: the paper's whole protocol and its follow-up session, driven through the
study app's widgets, leave the kernel with as many open widgets, comms and as much memory after
episode 2k as after episode k (a study screen used to leave widgets open, and every finished
episode kept its 1 kHz reproduction: about 0.8 MB an episode)."""

import datetime as dt
import gc
import tracemalloc
import weakref

import comm
import pytest
from ipywidgets import Button
from ipywidgets.widgets.widget import _instances

from mt_widgets import SKILLS
from mt_widgets.apps import StudyApp
from mt_widgets.apps.study.participant import ParticipantView
from mt_widgets.study import Session, StudyFolder, load_protocol, read_events
from mt_widgets.widgets import EpisodeWidget, retire

pytestmark = pytest.mark.slow  # the paper's 12 episodes and the follow-up's 2, with reproductions: about 15 s


def _answer(item) -> str:
    """An answer that keeps the participant in the study."""
    if item.kind in ("likert", "choice"):
        return (list(item.eligible) if item.eligible else list(item.choices))[0]
    if item.kind == "number":
        low = item.eligible_minimum if item.eligible_minimum is not None else item.minimum
        return str(int(30 if low is None else low) + 1)
    return "Nothing to add."


def _primary(view) -> Button:
    found, pending = [], [view.body]
    while pending:
        node = pending.pop()
        if isinstance(node, Button) and node.button_style == "primary" and node.layout.display != "none":
            found.append(node)
        pending += list(getattr(node, "children", ()))
    assert len(found) == 1, found
    return found[0]


def _act(view: ParticipantView) -> None:
    """One participant action through the page's widgets."""
    step = view.session.current_step()
    if step.kind == "video":
        view.video.ended_button.click()
        view.video.continue_button.click()
    elif step.kind in ("eligibility", "demographics", "questionnaire"):
        for item in step.study_step.items:
            view.form.fields[item.id].value = _answer(item)
        view.form.continue_button.click()
    elif step.kind == "practice":
        view.practice.done_button.disabled = False  # the practice's two minutes, not waited for
        view.practice.done_button.click()
    elif step.kind in ("demonstration", "episode_end"):
        if view.episode.phase == "guidance":
            view.episode.next()
        else:
            view.episode.demonstrate(SKILLS[step.skill].target_actions(step.state[None])[0] + 0.3)
    elif step.kind == "reproduction":
        view._episode_step.continue_button.click()
    else:
        _primary(view).click()
    assert view.stopped_by is None, view.stopped_by


def _open_comms() -> int:
    return len(comm.get_comm_manager().comms)


def _drive(view: ParticipantView) -> list[tuple[int, int, int]]:
    """Runs the page's session to its end; (open widgets, open comms, traced bytes) each time a
    study episode appears (its widgets built, the one before it gone)."""
    last, counts = None, []  # a weak reference: the test must not keep an episode alive itself
    while not view.session.finished:
        _act(view)
        episode = view.episode
        in_study = not view.session.finished and view.session.current_step().kind in ("demonstration",
                                                                                       "episode_end")
        if isinstance(episode, EpisodeWidget) and in_study and (last is None or episode is not last()):
            last = weakref.ref(episode)
            del episode
            gc.collect()
            counts.append((len(_instances), _open_comms(), tracemalloc.get_traced_memory()[0]))
    return counts


def test_widgets_comms_and_memory_stay_flat_through_the_paper_protocol_and_its_follow_up(tmp_path):
    tracemalloc.start(1)
    try:
        gc.collect()
        before = len(_instances)  # other tests' widgets, in a whole run
        app = StudyApp(protocol="paper-sim-followup", log_folder=tmp_path / "logs")
        app.start_participant("P01", group="target")
        main = _drive(app.participant_view)
        assert app.session.completed and len(main) == 12   # the paper's 12 episodes (practice apart)
        # After episode k and after episode 2k (k = 4: both in P3's eight episodes): the same widgets
        # and comms, and no more than 1 MB more memory (one kept reproduction is 0.8 MB).
        for k in (4,):
            widgets_k, comms_k, bytes_k = main[k - 1]
            widgets_2k, comms_2k, bytes_2k = main[2 * k - 1]
            assert widgets_2k <= widgets_k and comms_2k <= comms_k, main
            assert bytes_2k - bytes_k < 1_000_000, [(b - bytes_k) / 1e6 for _, _, b in main]
        # Bounded to the end: what remains is a few widgets per phase screen (P4, P5), not per episode.
        assert main[-1][0] - main[3][0] < 40, (before, main)

        # The follow-up, four weeks later, in a new page of the same kernel: the first page leaves
        # (its widgets close), and the second one ends no higher than the first one's episodes.
        ended = dt.datetime.fromisoformat(read_events(tmp_path / "logs" / "P01.jsonl")[0][-1]["time"]
                                          .replace("Z", "+00:00"))
        retire(app)
        study = StudyFolder(tmp_path / "logs")
        view = ParticipantView()
        view.begin(Session.arrive(study, "P01", now=ended + dt.timedelta(days=29)))
        followup = _drive(view)
        assert view.session.completed and len(followup) == 2
        assert max(w for w, _, _ in followup) <= max(w for w, _, _ in main)
        assert max(c for _, c, _ in followup) <= max(c for _, c, _ in main)
        assert followup[-1][2] - main[-1][2] < 2_000_000, (followup, main[-1])
    finally:
        tracemalloc.stop()
    assert load_protocol("paper-sim-followup").sessions[1].id == "followup"
