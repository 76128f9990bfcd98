"""The timeline and the query states, derived in one place: reproduction after each episode or each
phase as protocol data, step kinds as a type, and query states of matched difficulty."""

import numpy as np
import pytest

from mt_widgets.in_silico.plan import episode_plan, query_states_for
from mt_widgets.study import ProtocolError, Session, StudyFolder, load_protocol, parse_protocol, read_events
from mt_widgets.study.timeline import StepKind, episode_query_states, learner_sensitivity, timeline

from .scripted import SHORT_PROTOCOL, run


def by_phase(text: str) -> str:
    return text.replace('seed = 11\n', 'seed = 11\nreproduce_after = "phase"\n', 1)


def test_reproduction_after_each_phase_shows_the_phases_last_episode_only(tmp_path):
    protocol = parse_protocol(by_phase(SHORT_PROTOCOL))
    assert protocol.reproduce_after == "phase" and parse_protocol(SHORT_PROTOCOL).reproduce_after == "episode"
    slots = timeline(protocol)
    reproductions = [(s.phase_index, s.episode) for s in slots if s.kind == StepKind.REPRODUCTION]
    assert reproductions == [(0, 1), (1, 3), (2, 1)]  # B has three episodes: one reproduction, after the third
    every = [(s.phase_index, s.episode) for s in timeline(parse_protocol(SHORT_PROTOCOL))
             if s.kind == StepKind.REPRODUCTION]
    assert every == [(0, 1), (1, 1), (1, 2), (1, 3), (2, 1)]
    study = StudyFolder.create(tmp_path / "study", protocol)
    with Session.start(study, "P01") as session:
        run(session)
        assert session.completed
    events, _ = read_events(study.log_path("P01"))
    shown = [(e["phase_index"], e["episode"]) for e in events if e.get("screen") == "reproduction"]
    assert shown == reproductions
    assert sum(e["type"] == "episode_finished" for e in events) == 5  # every episode is still learnt and logged
    plan = episode_plan(protocol)
    assert [step["reproduced"] for step in plan] == [True, False, False, True, True]
    with pytest.raises(ProtocolError, match="reproduce_after: expected one of"):
        parse_protocol(SHORT_PROTOCOL.replace('seed = 11\n', 'seed = 11\nreproduce_after = "session"\n', 1))


def test_step_kinds_are_a_type_equal_to_their_text():
    kinds = [slot.kind for slot in timeline(parse_protocol(SHORT_PROTOCOL))]
    assert all(isinstance(kind, StepKind) for kind in kinds)
    assert kinds[0] == "welcome" and f"{kinds[0]}" == "welcome" and str(kinds[-1]) == "thank_you"


def test_the_session_and_the_in_silico_plan_draw_the_same_states(tmp_path):
    protocol = parse_protocol(SHORT_PROTOCOL.replace('seed = 11\n', 'seed = 11\nquery_states = "per-participant"\n'))
    study = StudyFolder.create(tmp_path / "study", protocol)
    for participant in range(2):
        with Session.start(study, f"P0{participant}") as session:
            run(session)
        events, _ = read_events(study.log_path(f"P0{participant}"))
        logged = [np.asarray(e["query_states"]) for e in events if e["type"] == "episode_started"]
        planned = [query_states_for(protocol, step, participant) for step in episode_plan(protocol)]
        assert len(logged) == len(planned) == 5
        assert all(np.array_equal(a, b) for a, b in zip(logged, planned))


def test_the_paper_protocols_do_not_match_difficulty_and_their_sensitivity_differs_across_phases():
    protocol = load_protocol("paper-sim")
    assert protocol.matched_difficulty is None
    plan = {step["phase"]: step for step in episode_plan(protocol)}
    sensitivity = {phase: learner_sensitivity(protocol.skill(plan[phase]["skill"]),
                                              query_states_for(protocol, plan[phase]), protocol.lam)
                   for phase in ("P1", "P4")}
    # The numbers: the same slip costs 2.5 times more at P4 than at P1.
    assert sensitivity["P1"] == pytest.approx(1.82, abs=0.01) and sensitivity["P4"] == pytest.approx(4.60, abs=0.01)


def test_matched_difficulty_draws_every_episode_within_the_band_reproducibly():
    base = load_protocol("paper-sim").source_text
    protocol = parse_protocol(base + '\n[matched_difficulty]\nsensitivity = [1.5, 2.5]\n', "matched.toml")
    assert protocol.matched_difficulty == (1.5, 2.5)
    values = []
    for step in episode_plan(protocol):
        states = query_states_for(protocol, step)
        values.append(learner_sensitivity(protocol.skill(step["skill"]), states, protocol.lam))
        again, _ = episode_query_states(protocol, step["states_index"], step["episode"], step["demonstrations"],
                                        step["skill"])
        assert np.array_equal(states, again)
    assert all(1.5 <= v <= 2.5 for v in values) and len(values) == 12
    with pytest.raises(ProtocolError, match="expected 0 < low < high"):
        parse_protocol(base + '\n[matched_difficulty]\nsensitivity = [3, 2]\n')
    with pytest.raises(ProtocolError, match="two numbers"):
        parse_protocol(base + '\n[matched_difficulty]\nsensitivity = "narrow"\n')
    narrow = parse_protocol(base + '\n[matched_difficulty]\nsensitivity = [100.0, 100.001]\n')
    with pytest.raises(ValueError, match="widen the band"):
        query_states_for(narrow, episode_plan(narrow)[0])


def test_a_protocol_names_the_researchers_own_video_file_and_its_hash_is_in_the_log(tmp_path):
    import hashlib
    video = tmp_path / "media" / "our_instructions.webm"
    video.parent.mkdir()
    video.write_bytes(b"\x1aE\xdf\xa3 a researcher's own recording")
    text = SHORT_PROTOCOL + '\n[[before]]\nid = "video"\nkind = "video"\nfile = "media/our_instructions.webm"\n'
    (tmp_path / "study.toml").write_text(text)
    protocol = load_protocol(tmp_path / "study.toml")
    sha = hashlib.sha256(video.read_bytes()).hexdigest()
    assert protocol.step("video").video_sha256 == sha and protocol.data["before"][0]["sha256"] == sha
    study = StudyFolder.create(tmp_path / "study", protocol)
    Session.start(study, "P01").close()
    first = read_events(study.log_path("P01"))[0][0]
    assert first["protocol_hash"] == protocol.hash == StudyFolder(study.folder).protocol.hash
    video.write_bytes(b"another video")  # a changed file no longer matches the protocol's hash
    (tmp_path / "pinned.toml").write_text(text.replace('file = "media', f'sha256 = "{sha}"\nfile = "media'))
    with pytest.raises(ProtocolError, match="not the protocol's"):
        load_protocol(tmp_path / "pinned.toml")
