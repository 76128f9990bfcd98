"""The shipped paper-sim protocol, end to end in Voila in real Chromium, through the steps around the task.

Three scripted participants take part at once, each in its own Chromium (Playwright's sync API
wants one instance per thread), so the two-minute practice and the reproductions run side by
side: one of each group goes through the instruction video (watched to the end, once replayed),
the information sheet, consent, the eligibility question, age and sex, the neutral practice, P1
to P5 with real mouse drags and the closing questionnaire; a third withdraws in the middle of P1.
The target group's guidance shows the two arrows and no words. The study then exports as a BIDS
dataset the validator accepts, and its status report counts what happened.
"""

from __future__ import annotations

import re
import threading
import time
import traceback

import numpy as np
import pytest
from bids_validator import BIDSValidator

from browser_support import CHROMIUM, CHROMIUM_ARGS, artifact_path, local_page
from mt_widgets.study import StudyFolder, export_bids, load_protocol, read_events, read_study
from mt_widgets.study.practice import PRACTICE_SKILLS
from mt_widgets.study.pseudonyms import code_of
from mt_widgets.widgets import ArmView
from mt_widgets.widgets.theme import DEFAULT_THEME

from .support import assert_one_drag, button, drag_and_wait, unlock, wait_for_marker

pytestmark = [pytest.mark.browser, pytest.mark.slow]

PAGE = "/voila/render/study_sim.ipynb"
PROTOCOL = load_protocol("paper-sim")
# The words of guidance (how the arrow differs from the optimal one); the legend naming the dashed
# arrow is a label of what is drawn, not guidance in words.
GUIDANCE_WORDS = re.compile(r"off by|too long|too short|Direction:|Size:|° off", re.IGNORECASE)


def log_events(logs, participant):
    path = logs / f"{participant}.jsonl"
    return read_events(path)[0] if path.exists() else []


def wait_for_log(logs, participant, predicate, timeout=60.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        events = log_events(logs, participant)
        if predicate(events):
            return events
        time.sleep(0.1)
    last = log_events(logs, participant)[-1:]
    raise AssertionError(f"{participant}: the log never satisfied the condition; last: {last}")


def hex_rgb(colour: str) -> list[int]:
    colour = colour.lstrip("#")
    return [int(colour[i:i + 2], 16) for i in (0, 2, 4)]


def count_colour(page, rgb, canvas_index=0) -> int:
    """Pixels of the given colour on a canvas (the teaching canvas is the first)."""
    return page.evaluate("""([i, rgb]) => {
        const c = document.querySelectorAll('canvas')[i];
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        let n = 0;
        for (let k = 0; k < d.length; k += 4)
            if (Math.abs(d[k] - rgb[0]) < 30 && Math.abs(d[k + 1] - rgb[1]) < 30 && Math.abs(d[k + 2] - rgb[2]) < 30
                && d[k + 3] > 200) n++;
        return n;
    }""", [canvas_index, rgb])


OFFSETS = ((50, -40), (-50, -30), (40, 45), (-45, 40), (55, 10))


def drag_and_confirm(page, pixel, offset):
    drag_and_wait(page, pixel, offset).click()


def wait_enabled(page, name, timeout=60_000):
    page.wait_for_function("b => !b.disabled", arg=button(page, name).element_handle(timeout=timeout),
                           timeout=timeout)


def steps_before_the_task(page, participant, replay: bool, shot):
    page.get_by_text("Welcome, and thank you for taking part.").wait_for(timeout=30_000)
    button(page, "Continue").click()
    # The instruction video: Continue only once it has played to the end.
    page.get_by_text("Instruction video").wait_for()
    video = page.locator("video")
    video.wait_for()
    assert button(page, "Continue").is_disabled()
    if shot:
        page.screenshot(path=shot("video"))
    video.evaluate("v => { v.muted = true; v.playbackRate = 4; return v.play(); }")
    wait_enabled(page, "Continue", timeout=60_000)
    if replay:
        page.get_by_role("button", name="Play again from the start").click()
        page.wait_for_function("v => v.currentTime > 0 && !v.paused", arg=video.element_handle(), timeout=10_000)
        video.evaluate("v => { v.playbackRate = 4; }")
        page.wait_for_function("v => v.ended", arg=video.element_handle(), timeout=30_000)
        time.sleep(0.5)  # the "ended" click travels to the kernel
    button(page, "Continue").click()
    page.get_by_text("Information sheet").wait_for()
    if shot:
        page.screenshot(path=shot("information"))
    button(page, "Continue").click()
    button(page, "I do not agree").wait_for()   # both answers are offered
    page.get_by_text("By pressing \"I agree\"").wait_for()
    button(page, "I agree").click()
    page.get_by_text("Have you studied robotics or worked with robots before?").wait_for()
    page.get_by_role("radio", name="no").check()
    button(page, "Continue").click()
    page.get_by_text("Your age, in years").wait_for()
    page.get_by_placeholder("a number (years)").fill("27")
    page.get_by_role("radio", name="female").check()
    button(page, "Continue").click()
    page.get_by_text("You will first have two minutes to try drawing freely.").wait_for()
    button(page, "Start the practice").click()


def practice(page, shot):
    page.get_by_text("Practice: for two minutes").wait_for()
    skill = PRACTICE_SKILLS["sim-practice"]
    state = skill.query_states(seed=np.random.SeedSequence(12345).spawn(1)[0])[0]
    pixel = ArmView(skill).end_effector_pixel(state)
    wait_for_marker(page, pixel, timeout=30_000, canvases=1)   # drawing only: no reproduction canvas
    drag_and_confirm(page, pixel, (50, -30))
    if shot:
        page.screenshot(path=shot("practice"))
    page.get_by_text("Practice time is over.").wait_for(timeout=180_000)
    button(page, "Continue to the study").click()


def phases(page, logs, participant, group, shot, withdraw_in_p1=False):
    """P1 to P5; returns True if the participant withdrew."""
    user, optimal = hex_rgb(DEFAULT_THEME.user_arrow.color), hex_rgb(DEFAULT_THEME.optimal_arrow.color)
    for phase in PROTOCOL.phases:
        page.get_by_text(f"Part {phase.index + 1} of {len(PROTOCOL.phases)}").first.wait_for(timeout=60_000)
        button(page, "Start").click()
        for episode in range(1, phase.episodes + 1):
            key = (phase.id, episode)
            events = wait_for_log(logs, participant, lambda ev, key=key: any(
                e["type"] == "episode_started" and (e["phase"], e["episode"]) == key for e in ev))
            started = [e for e in events if e["type"] == "episode_started"][-1]
            assert started["guidance_modality"] == "arrows"
            view = ArmView(PROTOCOL.skill(phase.skill))
            guided = group in phase.guidance
            for index in range(phase.demonstrations):
                pixel = view.end_effector_pixel(np.asarray(started["query_states"][index]))
                wait_for_marker(page, pixel, timeout=30_000)
                # Arrows long enough to see (and to count on the canvas), in varied directions.
                drag_and_confirm(page, pixel, OFFSETS[index % len(OFFSETS)])
                wait_for_log(logs, participant, lambda ev, key=key + (index,): any(
                    e["type"] == "demonstration" and (e["phase"], e["episode"], e["index"]) == key for e in ev))
                if withdraw_in_p1 and index == 1:
                    button(page, "Withdraw from the study").click()
                    page.get_by_text("Do you want to withdraw from the study?").wait_for()
                    if shot:
                        page.screenshot(path=shot("withdraw-confirm"))
                    button(page, "Yes, withdraw").click()
                    page.get_by_text("You have withdrawn from the study.").wait_for(timeout=30_000)
                    if shot:
                        page.screenshot(path=shot("withdrawn"))
                    return True
                if guided:
                    last = index + 1 == phase.demonstrations
                    name = "Finish and watch" if last else "Next state"
                    button(page, name).wait_for(timeout=30_000)
                    # Both arrows are drawn: the participant's and the optimal one; no words.
                    deadline = time.monotonic() + 10
                    while count_colour(page, optimal) < 20 and time.monotonic() < deadline:
                        time.sleep(0.1)
                    assert count_colour(page, optimal) >= 20 and count_colour(page, user) >= 20
                    assert not GUIDANCE_WORDS.search(page.inner_text("body"))
                    if shot and episode == 1 and index == 0:
                        page.screenshot(path=shot("guidance-arrows-only"))
                    button(page, name).click()
            wait_for_log(logs, participant, lambda ev, key=key: any(
                e["type"] == "episode_finished" and (e["phase"], e["episode"]) == key for e in ev))
            page.get_by_text("This is what the robot learnt").wait_for(timeout=30_000)
            if shot and phase.id == "P1":
                page.screenshot(path=shot("reproduction"))
            wait_enabled(page, "Continue", timeout=60_000)
            button(page, "Continue").click()
    return False


def questionnaire(page, shot):
    page.get_by_text("How difficult was it to teach the robot?").wait_for(timeout=60_000)
    page.get_by_role("radio", name="easy", exact=True).check()
    if shot:
        page.screenshot(path=shot("questionnaire"))
    button(page, "Continue").click()
    page.get_by_text("That is the end of the study.").wait_for(timeout=30_000)


def take_part(server, participant, group, withdraw=False, replay=False, shot=None):
    from playwright.sync_api import sync_playwright
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        context, page = local_page(browser, 1280, 1300)
        page.set_default_timeout(60_000)
        try:
            unlock(page, server)
            page.get_by_placeholder("pseudonymous code, e.g. P07").fill(participant)
            page.get_by_label("Group").select_option(label=group)
            button(page, "Start new participant").click()
            steps_before_the_task(page, participant, replay, shot)
            practice(page, shot)
            if phases(page, server.logs, participant, group, shot, withdraw_in_p1=withdraw):
                return
            questionnaire(page, shot)
            if shot:
                page.screenshot(path=shot("thank-you"))
        except BaseException:
            page.screenshot(path=artifact_path("paper-sim-failed", participant))
            raise
        finally:
            context.close()
            browser.close()


def test_paper_sim_end_to_end_with_the_steps_around_the_task_and_a_withdrawal(voila_study, artifacts, tmp_path):
    people = [("T01", "target", False, True), ("C01", "control", False, False), ("W01", "control", True, False)]
    errors = {}

    def run(pid, group, withdraw, replay):
        try:
            take_part(voila_study, pid, group, withdraw, replay,
                      shot=(lambda step, pid=pid: artifacts(f"{pid}-{step}")))
        except BaseException:
            errors[pid] = traceback.format_exc()

    threads = [threading.Thread(target=run, args=person) for person in people]
    for thread in threads:
        thread.start()
        time.sleep(2.0)  # the page's kernel starts before the next page asks for one
    for thread in threads:
        thread.join(timeout=1500)
    assert not errors, "\n".join(f"{pid}:\n{text}" for pid, text in errors.items())

    logs = voila_study.logs
    for pid in ("T01", "C01"):
        events = log_events(logs, pid)
        assert events[-1]["type"] == "session_finished"
        done = {e["step"]: e for e in events if e["type"] == "step_done"}
        assert done["video"]["watched_to_end"] is True
        assert done["demographics"]["answers"] == {"age": 27, "sex": "female"}
        assert done["eligibility"]["eligible"] is True and done["questionnaire"]["answers"]["difficulty"] == "easy"
        demos = [e for e in events if e["type"] == "demonstration"]
        assert len(demos) == sum(p.episodes * p.demonstrations for p in PROTOCOL.phases)
        for demonstration in demos:
            assert_one_drag(demonstration)
        practice_event = [e for e in events if e["type"] == "practice_started"][0]
        assert practice_event["skill"] == "sim-practice"
    assert {e["step"]: e for e in log_events(logs, "T01") if e["type"] == "step_done"}["video"]["plays"] >= 2
    guided = [d["guidance_shown"] for d in log_events(logs, "T01") if d["type"] == "demonstration"]
    assert sum(guided) == 8 * 5 and not any(d["guidance_shown"] for d in log_events(logs, "C01")
                                            if d["type"] == "demonstration")
    withdrawn = log_events(logs, "W01")
    assert withdrawn[-1]["type"] == "withdrawn" and withdrawn[-1]["data"] == "exclude"

    study = StudyFolder(logs)
    counts = study.group_status()
    assert counts["target"]["completed"] == 1 and counts["control"]["completed"] == 1
    assert counts["control"]["withdrawn"] == 1 and counts["control"]["enrolled"] == 2
    episodes, _ = read_study(logs)
    assert {e["participant"] for e in episodes} == {"T01", "C01"}
    out = export_bids(logs, tmp_path / "bids")
    files = sorted("/" + str(p.relative_to(out)) for p in out.rglob("*") if p.is_file())
    validator = BIDSValidator()
    assert [f for f in files if not validator.is_bids(f)] == []
    t01 = code_of(logs, "T01")
    assert f"/sub-{t01}/beh/sub-{t01}_task-papersim_beh.tsv" in files and code_of(logs, "W01") is None
    (tmp_path / "status.txt").write_text(study.status_report())
    print(study.status_report())
    print("\n".join(files))
