"""The demo page served as the kiosk serves it (deploy/voila/voila.py) needs nothing from the internet.

Voila's lab template links Font Awesome from a CDN (cdn.jsdelivr.net): a classroom or a kiosk without
internet waited for it, and the buttons' icons came only from Voila's own bundle. The shipped
configuration renders the pages with the template in deploy/voila/templates/ (the lab template
without the CDN links; Voila's bundle carries Font Awesome 5 and its fonts, served by the server).
Every request the page makes is recorded and every one that is not the server's is refused.
"""

from __future__ import annotations

from browser_support import LOCAL_PREFIXES

from .helpers import OKABE, ee_pixel, wait_for_color
from .kiosk import DEMO_URL_PATH, reference_episodes, start_page_server

#: An icon the demo's buttons show (Voila's bundle styles ipywidgets' "fa fa-<name>" icons).
ICON = "button i.fa"


def test_the_demo_page_asks_nothing_outside_the_server_and_its_icons_render(browser, tmp_path, artifacts):
    server = start_page_server(tmp_path)
    context = browser.new_context(viewport={"width": 1280, "height": 1100})
    outside = []

    def only_the_server(route):
        if route.request.url.startswith(LOCAL_PREFIXES):
            route.continue_()
        else:
            outside.append(route.request.url)
            route.abort()

    context.route("**/*", only_the_server)
    try:
        page = context.new_page()
        first, _ = reference_episodes()
        page.goto(server.url(DEMO_URL_PATH), wait_until="commit", timeout=60_000)
        wait_for_color(page, 0, *ee_pixel(first), OKABE["yellow"], timeout=120_000)
        page.wait_for_selector(ICON, state="attached", timeout=30_000)
        page.wait_for_load_state("networkidle", timeout=60_000)
        page.evaluate("document.fonts.ready")
        icon = page.evaluate(f"""() => {{
            const icons = [...document.querySelectorAll('{ICON}')];
            const icon = icons.find(i => i.getBoundingClientRect().width > 0) || icons[0];
            const glyph = getComputedStyle(icon, '::before');
            return {{name: icon.className, family: glyph.fontFamily, content: glyph.content,
                     width: icon.getBoundingClientRect().width,
                     loaded: [...document.fonts].filter(f => /Font Awesome/.test(f.family) && f.status === 'loaded')
                             .map(f => f.family)}}; }}""")
        page.screenshot(path=artifacts("demo-offline"))
        assert outside == [], f"the page asked outside the server: {outside}"
        # The icon is a Font Awesome glyph, drawn with a Font Awesome font the server sent.
        assert "Font Awesome" in icon["family"] and icon["content"] not in ("none", "normal", ""), icon
        assert icon["width"] > 4 and icon["loaded"], icon
    finally:
        context.close()
        server.stop()
