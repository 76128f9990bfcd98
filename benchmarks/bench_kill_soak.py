"""Kill soak (issue 46): the study's kill loop (tests/study/test_crash_safety.py) run for many random
SIGKILLs across the paper's protocols, checking that nothing acknowledged is lost or duplicated.

Each participant gets a fresh study folder of one protocol, taken in turn from ``--protocols``
(by default every built-in protocol: paper-sim, paper-uarm, paper-sim-followup, industrial-sim,
reward-sim). A forked child (everything already imported, so an attempt costs milliseconds)
resumes or starts the participant and drives them with deterministic scripted answers and actions.
The child is SIGKILL-ed in one of two ways:

- by itself inside a log write (``jsonl.write_all``), at a random write of the attempt: before the
  write ("before"), after half of the line ("torn"), or after all of its bytes but before the
  fsync ("unsynced");
- by the parent, after a random delay of 0 to 30 ms ("timed").

After every ``ParticipantLog.append`` that returned (the event is acknowledged: a page would have
moved on), the child reports the event's sequence number and a digest of its content through a
pipe. Once a participant's session reaches its end, the checks are:

- **nothing acknowledged lost**: every reported event is in the final log, at its sequence
  number, with the same content;
- **nothing duplicated**: the log's sequence numbers are consecutive, every demonstration
  (phase, episode, index) appears once, and there is exactly one ``session_finished``;
- **nothing changed**: the demonstrations and the episodes' learnt skills are those of an
  uninterrupted run of the same participant.

Run: ``.venv/bin/python benchmarks/bench_kill_soak.py --kills 1000`` (``--seed``, ``--protocols``).
It prints the kills by kind, participants, checks and wall time. It exits with 1 on any violation.
Not a CI test: the suite's own kill test (tests/study/test_crash_safety.py) kills about a dozen times.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import signal
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout's package, not an installed one
from mt_widgets import SKILLS  # noqa: E402
from mt_widgets.study import (  # noqa: E402
    BUILTIN_PROTOCOLS,
    ParticipantLog,
    Session,
    StudyFolder,
    load_protocol,
    read_events,
)
from mt_widgets.study import jsonl as jsonl_module  # noqa: E402

WRITE_MODES = ("before", "torn", "unsynced")
PARTICIPANT = "P01"


def digest(event: dict) -> str:
    return hashlib.sha256(json.dumps(event, sort_keys=True, separators=(",", ":")).encode()).hexdigest()[:16]


def answers_for(step) -> dict:
    """Answers every item of a form so that the participant stays in the study."""
    answers = {}
    for item in step.study_step.items:
        if item.choices:
            answers[item.id] = next((c for c in item.choices if item.is_eligible(c)), item.choices[0])
        elif item.kind == "number":
            low = max(v for v in (item.minimum, item.eligible_minimum, 0) if v is not None)
            answers[item.id] = int(np.ceil(low)) if item.integer else float(low)
        else:
            answers[item.id] = "soak" if item.required else None
    return answers


def scripted_action(step) -> np.ndarray:
    """The skill's own action plus noise seeded by where the step is: the same step, the same action."""
    target = SKILLS[step.skill].target_actions(step.state[None])[0]
    rng = np.random.default_rng([step.phase_index, step.episode, step.index])
    return target + rng.normal(0.0, 0.2 * (1 + np.abs(target)), size=target.shape)


def drive(session) -> None:
    """Drives ``session`` to the end of its (first) session."""
    while not session.finished:
        step = session.current_step()
        if step.kind == "video":
            session.finish_video(True, 1)
        elif step.kind in ("eligibility", "demographics", "questionnaire"):
            session.submit_answers(answers_for(step))
        elif step.kind == "practice":
            session.finish_practice(duration_s=1.0)
        elif step.kind == "demonstration":
            session.submit_demonstration(scripted_action(step), {"time_to_first_input_s": 0.5,
                                                                 "drawing_duration_s": 0.25}, index=step.index)
        elif step.kind == "episode_end":
            session.finish_episode()
        else:
            session.advance()
    if session.ended is not None:
        raise RuntimeError(f"the scripted participant's session ended early ({session.ended})")


def _child(folder: Path, participant: str, kill_at: int | None, mode: str | None, acks: int) -> None:
    """In the forked child: resume or start, report every acknowledged event, drive; never returns."""
    status = 1
    try:
        if kill_at is not None:
            real_write, count = jsonl_module.write_all, [0]

            def dying_write(fd, data):
                count[0] += 1
                if count[0] == kill_at:
                    if mode == "torn":
                        real_write(fd, data[: max(1, len(data) // 2)])
                    elif mode == "unsynced":
                        real_write(fd, data)
                    os.kill(os.getpid(), signal.SIGKILL)
                real_write(fd, data)

            jsonl_module.write_all = dying_write
        real_append = ParticipantLog.append

        def reporting_append(log, event_type, **fields):
            event = real_append(log, event_type, **fields)
            os.write(acks, f"{event['seq']} {digest(event)}\n".encode())  # one small write: atomic on a pipe
            return event

        ParticipantLog.append = reporting_append
        study = StudyFolder(folder)
        if participant in study.participant_ids():
            session = Session.resume(study, participant, lock_timeout_s=5.0)
        else:
            session = Session.start(study, participant, group="target")
        drive(session)
        session.close()
        status = 0
    except BaseException:
        import traceback

        traceback.print_exc()
    finally:
        os._exit(status)


def attempt(folder: Path, participant: str, acknowledged: dict, rng) -> str | None:
    """One forked attempt; the kind of kill, or None when it ran to the end."""
    read_end, write_end = os.pipe()
    timed = rng.random() >= 0.7
    kill_at, mode = (None, None) if timed else (int(rng.integers(1, 8)), WRITE_MODES[int(rng.integers(3))])
    pid = os.fork()
    if pid == 0:
        os.close(read_end)
        _child(folder, participant, kill_at, mode, write_end)
    os.close(write_end)
    if timed:
        time.sleep(float(rng.uniform(0.0, 0.03)))
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    reports = b""
    while chunk := os.read(read_end, 65536):
        reports += chunk
    os.close(read_end)
    _, status = os.waitpid(pid, 0)
    for line in reports.decode().splitlines():
        seq, event_digest = line.split()
        if acknowledged.setdefault(int(seq), event_digest) != event_digest:
            raise AssertionError(f"{participant}: seq {seq} was acknowledged twice with different content")
    if os.WIFSIGNALED(status):
        assert os.WTERMSIG(status) == signal.SIGKILL
        return "timed" if timed else mode
    if os.WEXITSTATUS(status) != 0:
        raise RuntimeError(f"{participant}: the scripted session failed (not killed) in the child")
    return None


def summary(events) -> tuple:
    demonstrations = [(e["phase"], e["episode"], e["index"], tuple(e["state"]), tuple(e["action"]))
                      for e in events if e["type"] == "demonstration"]
    finished = [(e["phase"], e["episode"], tuple(np.ravel(e["theta_hat"]))) for e in events
                if e["type"] == "episode_finished"]
    return demonstrations, finished


def check(log_path: Path, acknowledged: dict, reference: tuple) -> list[str]:
    """The violations in a finished participant's log (empty: none)."""
    events, info = read_events(log_path)  # raises on a damaged or out-of-sequence log
    problems = []
    by_seq = {event["seq"]: event for event in events}
    lost = [seq for seq, event_digest in acknowledged.items()
            if seq not in by_seq or digest(by_seq[seq]) != event_digest]
    if lost:
        problems.append(f"{len(lost)} acknowledged events lost or changed (seq {lost[:5]})")
    if [e["seq"] for e in events] != list(range(len(events))):
        problems.append("sequence numbers not consecutive")
    demonstrations, finished = summary(events)
    keys = [d[:3] for d in demonstrations]
    if len(keys) != len(set(keys)):
        problems.append("a demonstration is duplicated")
    if [e["type"] for e in events].count("session_finished") != 1:
        problems.append("not exactly one session_finished")
    if (demonstrations, finished) != reference:
        problems.append("demonstrations or learnt skills differ from the uninterrupted run")
    return problems


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kills", type=int, default=1000, help="stop after this many kills (default 1000)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--protocols", default=",".join(BUILTIN_PROTOCOLS),
                        help="comma-separated built-in protocols, taken in turn")
    args = parser.parse_args()
    protocols = [name for name in args.protocols.split(",") if name]
    rng = np.random.default_rng(args.seed)
    kinds = {kind: 0 for kind in (*WRITE_MODES, "timed")}
    participants, acknowledged_total, violations = 0, 0, []
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="mt-kill-soak-") as root:
        references = {}
        while sum(kinds.values()) < args.kills:
            protocol = protocols[participants % len(protocols)]
            # Every participant is "P01" of a study folder of their own, as is the uninterrupted
            # reference: the same ID, group and enrolment index, so the same query states.
            if protocol not in references:
                reference_study = StudyFolder.create(Path(root, f"reference-{protocol}"), load_protocol(protocol))
                session = Session.start(reference_study, PARTICIPANT, group="target")
                drive(session)
                session.close()
                references[protocol] = summary(session.events)
            folder = Path(root, f"{protocol}-{participants:04d}")
            study = StudyFolder.create(folder, load_protocol(protocol))
            acknowledged: dict[int, str] = {}
            for _ in range(100_000):
                kind = attempt(folder, PARTICIPANT, acknowledged, rng)
                if kind is None:
                    break
                kinds[kind] += 1
            problems = check(study.log_path(PARTICIPANT), acknowledged, references[protocol])
            acknowledged_total += len(acknowledged)
            if problems:
                violations.append(f"{protocol} participant {participants + 1}: " + "; ".join(problems))
            participants += 1
            print(f"{protocol:<19} participant {participants:>3}: {sum(kinds.values()):>5} kills so far, "
                  f"{len(acknowledged)} events acknowledged, {'OK' if not problems else problems}", flush=True)
    wall = time.perf_counter() - started
    print(f"\n{sum(kinds.values())} SIGKILLs ({', '.join(f'{k} {v}' for k, v in kinds.items())}) across "
          f"{participants} participants of {len(protocols)} protocols in {wall:.0f} s; "
          f"{acknowledged_total} acknowledged events checked: "
          f"{'nothing lost, nothing duplicated' if not violations else f'{len(violations)} VIOLATIONS'}")
    for violation in violations:
        print("  " + violation)
    return 1 if violations else 0


if __name__ == "__main__":
    sys.exit(main())
