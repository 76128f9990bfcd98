"""What the study-page browser tests share: the page, its buttons, the experimenter's code, the
participant's log, real drags and the wait for a drawn marker (tests import this, never each other)."""

import re
import time

import numpy as np

from browser_support import artifact_path
from mt_widgets import SKILLS
from mt_widgets.study import read_events
from mt_widgets.widgets import ArmView
from protocols import BROWSER_TEXTS, phase, protocol_toml

#: The experimenter's code the test servers are given ($MT_WIDGETS_EXPERIMENTER_CODE).
EXPERIMENTER_CODE = "lab-code-4711"

PAGE = "/voila/render/study_sim.ipynb"


def two_part_protocol(second: str = "P3", guided: bool = True, seed: int = 5, practice_s: float = 10,
                      practice_text: str = "Practice freely.", reproduction_s: float = 2.0) -> str:
    """A short study named "browser" (``open_and_fill`` waits for that name): skill 1 taught in
    two parts of one 3-state episode each, the second (``second``) guided for the target group
    when ``guided``."""
    return protocol_toml("browser", [
        phase("P1", "sim-point", demonstrations=3, instructions="First part: teach skill 1."),
        phase(second, "sim-point", demonstrations=3, **({"guidance": ["target"]} if guided else {}),
              instructions="Second part: teach skill 1 again.")],
        seed=seed, practice_s=practice_s, practice_text=practice_text, texts=BROWSER_TEXTS,
        top={"reproduction_duration_s": reproduction_s})


#: The short study the study-page tests take part in (test_study_page.py, test_touch_drawing.py).
PROTOCOL = two_part_protocol()


def button(page, name):
    # Icons add to a button's accessible name: match the words, nothing else.
    return page.get_by_role("button", name=re.compile(rf"^\W*{re.escape(name)}\s*$"))


def unlock(page, server):
    """Opens the lab page and the experimenter panel with the experimenter's code."""
    # The kernel runs the page's notebook while the page loads: wait for the field, not for "load".
    page.goto(server.url(PAGE), wait_until="commit", timeout=120_000)
    page.get_by_placeholder("the experimenter's code").fill(EXPERIMENTER_CODE, timeout=120_000)
    button(page, "Open the experimenter panel").click()
    page.get_by_text("Experimenter", exact=True).wait_for(timeout=60_000)


def open_and_fill(page, server, protocol_path, participant):
    unlock(page, server)
    protocol = page.get_by_placeholder("paper-sim, paper-uarm or a .toml/.json file")
    protocol.fill(str(protocol_path))
    protocol.press("Enter")
    page.get_by_text("Protocol 'browser'").wait_for(timeout=10_000)
    page.get_by_placeholder("pseudonymous code, e.g. P07").fill(participant)


def log_events(server, participant):
    path = server.logs / f"{participant}.jsonl"
    return read_events(path)[0] if path.exists() else []


def wait_for_log(server, participant, predicate, timeout=15.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        events = log_events(server, participant)
        if predicate(events):
            return events
        time.sleep(0.05)
    raise AssertionError(f"{participant}: the log never satisfied the condition; last event: "
                         f"{log_events(server, participant)[-1:]}")


def drag(page, ee_pixel, offset):
    """A real drag from the end-effector, through the CSS-scaled canvas box."""
    element = page.locator("canvas").first
    box = element.bounding_box()
    width, height = element.evaluate("c => [c.width, c.height]")

    def to_page(x, y):
        return box["x"] + x * box["width"] / width, box["y"] + y * box["height"] / height

    start = to_page(*ee_pixel)
    end = to_page(ee_pixel[0] + offset[0], ee_pixel[1] + offset[1])
    page.mouse.move(*start)
    page.mouse.down()
    for fraction in np.linspace(0.25, 1.0, 4):
        page.mouse.move(start[0] + fraction * (end[0] - start[0]), start[1] + fraction * (end[1] - start[1]))
    page.mouse.up()


#: How long the kernel may take to answer a drag's release (Confirm enabled). Measured on a
#: 2-core machine over every drag of these tests: at most 0.4 s of 136 at load average 3, 0.9 s
#: of 136 at load average 20-45 (three busy loops beside the tests); each press reached the
#: kernel on the current state's hand and started the drag. A kernel shared with other pages can
#: be busy for longer: wait for the answer, never drag again.
CONFIRM_WITHIN_MS = 30_000


def drag_and_wait(page, ee_pixel, offset):
    """Drags once from the hand and waits until the kernel took the arrow (Confirm enabled).

    Never drags again: a person's first drag after the state is drawn must count (each drag is
    one pending arrow; a second would replace it, hiding a canvas that ignored the first)."""
    confirm = button(page, "Confirm")
    # A new state's marker is drawn before its disabled Confirm reaches the page (the kernel sends
    # the drawing first): wait for that, or the previous arrow's Confirm would be taken as this one's.
    page.wait_for_function("b => b.disabled", arg=confirm.element_handle(), timeout=CONFIRM_WITHIN_MS)
    drag(page, ee_pixel, offset)
    try:
        page.wait_for_function("b => !b.disabled", arg=confirm.element_handle(), timeout=CONFIRM_WITHIN_MS)
    except Exception:
        page.screenshot(path=artifact_path("study-page-drag-not-taken", f"{round(ee_pixel[0])}-{round(ee_pixel[1])}"))
        raise AssertionError(f"a drag from the hand at canvas pixel {tuple(round(v) for v in ee_pixel)} was not "
                             f"taken within {CONFIRM_WITHIN_MS} ms; the page says: "
                             f"{page.inner_text('body')[:1500]}") from None
    return confirm


YELLOW = (240, 228, 66)  # the end-effector marker (Okabe-Ito yellow)


def wait_for_marker(page, ee_pixel, timeout=15_000, canvases=2):
    """Waits until the page holds ``canvases`` canvases (an episode: teaching, reproduction; a
    practice round: teaching only) and the teaching canvas shows the end-effector marker at
    ``ee_pixel``: drawn, not just present."""
    page.wait_for_function(
        """([x, y, rgb, n]) => {
            const all = document.querySelectorAll('canvas');
            if (all.length !== n) return false;
            const d = all[0].getContext('2d').getImageData(Math.round(x) - 2, Math.round(y) - 2, 5, 5).data;
            for (let i = 0; i < d.length; i += 4) {
                if (Math.abs(d[i] - rgb[0]) < 40 && Math.abs(d[i + 1] - rgb[1]) < 40
                    && Math.abs(d[i + 2] - rgb[2]) < 40 && d[i + 3] > 200) return true;
            }
            return false;
        }""", arg=[float(ee_pixel[0]), float(ee_pixel[1]), list(YELLOW), int(canvases)], timeout=timeout)


def current_episode(server, participant):
    started = [e for e in log_events(server, participant) if e["type"] == "episode_started"]
    return started[-1]


def demonstrate(page, server, participant, phase, index, offset):
    """Draws and confirms the arrow at query state ``index`` of ``phase``; waits until it is on disk."""
    # The episode's query states are logged when the kernel enters it: wait for that first.
    wait_for_log(server, participant, lambda events: any(
        e["type"] == "episode_started" and e["phase"] == phase for e in events))
    episode = current_episode(server, participant)
    view = ArmView(SKILLS[episode["skill"]])
    ee = view.end_effector_pixel(np.asarray(episode["query_states"][index]))
    try:
        wait_for_marker(page, ee)
    except Exception:
        page.screenshot(path=artifact_path("study-page-no-marker", f"{episode['phase']}-{index}"))
        raise
    confirm = drag_and_wait(page, ee, offset)
    confirm.click()
    key = (episode["phase"], episode["episode"], index)
    events = wait_for_log(server, participant, lambda events: any(
        (e["phase"], e["episode"], e["index"]) == key for e in events if e["type"] == "demonstration"))
    assert_one_drag([e for e in events if e["type"] == "demonstration"
                     and (e["phase"], e["episode"], e["index"]) == key][-1])
    return events


def assert_one_drag(demonstration):
    """The logged demonstration was drawn by the one drag made: one press taken, by the pointer."""
    given = demonstration["input"]
    assert given["method"] == "pointer" and given["redraws"] == 1, given
