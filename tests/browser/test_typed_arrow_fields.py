"""Typed arrows in a real browser: at the next state the fields are empty, so "Set arrow" never
re-applies the previous state's numbers (they used to stay, and Set arrow drew the old arrow)."""

import pytest

from .helpers import OKABE, ee_pixel, reference_episode, wait_for_color, wait_for_status

pytestmark = pytest.mark.browser


def test_the_typed_fields_are_empty_at_the_next_state(page, voila_server, artifacts):
    reference = reference_episode()
    page.goto(voila_server.url("/voila/render/episode_sim.ipynb"), timeout=60_000)
    page.wait_for_selector("canvas", timeout=60_000)
    wait_for_color(page, 0, *ee_pixel(reference), OKABE["yellow"])
    fields = page.locator(".widget-text input[type=number]")
    fields.nth(0).fill("1.25")
    fields.nth(1).fill("-0.5")
    fields.nth(1).press("Tab")
    page.get_by_role("button", name="Set arrow").click()
    wait_for_status(page, "s.pending !== null && Math.abs(s.pending[0] - 1.25) < 1e-9")
    page.get_by_role("button", name="Confirm").click()
    page.get_by_role("button", name="Next state").click()
    wait_for_status(page, "s.index === 1 && s.pending === null")
    page.wait_for_function("() => [...document.querySelectorAll('.widget-text input[type=number]')]"
                           ".every(f => Number(f.value) === 0)", timeout=5_000)
    page.screenshot(path=artifacts("next-state"))
    page.get_by_role("button", name="Set arrow").click()
    status = wait_for_status(page, "s.pending !== null")
    assert status["pending"] == [0.0, 0.0], f"Set arrow re-applied an old arrow: {status['pending']}"
