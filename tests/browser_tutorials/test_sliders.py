"""The theory tutorials' sliders redraw their figure live in a browser (Voila, real Chromium)."""

import pytest

pytestmark = pytest.mark.browser


def figure_sources(page) -> list[str]:
    return page.eval_on_selector_all(".widget-interact img", "imgs => imgs.map(i => i.src)")


def readout(page, index: int) -> str:
    return page.locator(".widget-interact .widget-readout").nth(index).inner_text()


@pytest.mark.parametrize("name, slider, presses, expected, printed", [
    ("05_query_states_and_conditioning", 1, 4, "0.80", "spread 0.80: kappa"),   # spread 1.00 -> 0.80
    ("02_ridge_regression", 0, 2, "0.00316", "lambda 0.00316: E ="),            # lambda 10^-2 -> 10^-2.5
])
def test_moving_a_slider_redraws_the_figure(page, tutorial_server, artifacts, name, slider, presses, expected, printed):
    # Voila runs the whole tutorial before the page loads: generous limits for a loaded machine.
    page.goto(tutorial_server.url(f"/voila/render/{name}.ipynb"), timeout=240_000)
    # The first drawing settles into exactly one figure (waited for, not sampled at one instant).
    page.wait_for_function("() => document.querySelectorAll('.widget-interact img').length == 1",
                           timeout=120_000)
    before = figure_sources(page)
    assert len(before) == 1
    page.locator(".widget-interact").first.scroll_into_view_if_needed()
    page.screenshot(path=artifacts(f"{name}-before"), full_page=False)

    handle = page.locator(".widget-interact .noUi-handle").nth(slider)
    handle.focus()
    for _ in range(presses):
        handle.press("ArrowLeft")
    page.wait_for_function(
        f"() => document.querySelectorAll('.widget-interact .widget-readout')[{slider}]"
        f".innerText.trim() == '{expected}'",
        timeout=30_000)
    page.wait_for_function(
        f"() => {{ const i = document.querySelector('.widget-interact img'); return i && i.src !== {before[0]!r}; }}",
        timeout=60_000)
    # The redraw for the last position prints its numbers above its figure: wait for it, then the figure is final.
    page.wait_for_function(
        f"() => {{ const out = document.querySelector('.widget-interact .widget-output');"
        f" const i = out.querySelector('img');"
        f" return out.innerText.includes({printed!r}) && i && i.src !== {before[0]!r}; }}",
        timeout=60_000)
    after = figure_sources(page)
    assert len(after) == 1 and after[0] != before[0]
    assert readout(page, slider).strip() == expected
    page.screenshot(path=artifacts(f"{name}-after"), full_page=False)
