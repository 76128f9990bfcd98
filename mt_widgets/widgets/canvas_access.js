// The teaching canvas for fingers, the keyboard and screen readers: the front end of
// CanvasDescription (canvas_access.py says what ipycanvas' own front end does and why this is needed).
// It names no study word: a blinded participant's page is checked for them (tests/study/test_app.py).

// One set of document listeners per page, shared by every description on it (each description's
// module is imported afresh by anywidget, so the page-wide part lives on globalThis). They listen in
// the capture phase on the document, before ipycanvas' listeners on the canvas element.
const PAGE_KEY = "mtWidgetsCanvasAccess";

function pageAccess() {
  if (globalThis[PAGE_KEY]) return globalThis[PAGE_KEY];
  // models: a canvas element's class (CANVAS_CLASS_PREFIX + token) -> its description's model, with
  // how many views of that description are on the page.
  const access = { models: new Map(), passing: false };
  globalThis[PAGE_KEY] = access;

  function modelOf(canvas) {
    for (const name of canvas.classList) {
      const entry = access.models.get(name);
      if (entry) return entry.model;
    }
    return null;
  }
  // The described canvas an event happened on, and its description's model.
  function ours(event) {
    const node = event.composedPath()[0];
    const canvas = node && node.closest ? node.closest("canvas") : null;
    const model = canvas ? modelOf(canvas) : null;
    return model ? { canvas, model } : null;
  }
  function onGrabZone({ canvas, model }, touch) {
    const box = canvas.getBoundingClientRect();
    const zones = model.get("grab_zones") || [];
    if (!zones.length || !box.width) return false;
    const scale = canvas.width / box.width; // canvas pixels per CSS pixel
    const x = (touch.clientX - box.left) * scale;
    const y = (touch.clientY - box.top) * scale;
    const finger = model.get("finger_radius_css_px") * scale;
    // A finger gets at least its own size, at most the zone's touch radius.
    return zones.some(([zx, zy, mouseRadius, touchRadius]) =>
      Math.hypot(x - zx, y - zy) <= Math.min(touchRadius, Math.max(mouseRadius, finger)));
  }
  // Whether a touch reaches ipycanvas (and so the kernel) is decided when the first finger lands:
  // within a grab zone it draws; anywhere else, or a second finger, the browser scrolls or zooms.
  document.addEventListener("touchstart", (event) => {
    const found = ours(event);
    if (!found) return;
    if (event.touches.length === 1) access.passing = onGrabZone(found, event.touches[0]);
    if (!access.passing) event.stopImmediatePropagation();
  }, { capture: true, passive: true });
  for (const type of ["touchmove", "touchend", "touchcancel"]) {
    document.addEventListener(type, (event) => {
      if (!ours(event)) return;
      const passing = access.passing;
      if (event.touches.length === 0) access.passing = false;
      if (!passing) event.stopImmediatePropagation();
    }, { capture: true, passive: true });
  }
  // Tab and Shift+Tab move focus on, as anywhere else (ipycanvas would keep it on the canvas).
  document.addEventListener("keydown", (event) => {
    if (event.key === "Tab" && ours(event)) event.stopImmediatePropagation();
  }, true);

  // The canvas element's role and name: set when a description is shown, when its words change,
  // and when a canvas element of a shown description appears later (ipycanvas renders its own).
  access.label = (canvasClass, model) => {
    const text = model.get("text");
    for (const canvas of document.querySelectorAll(`canvas.${CSS.escape(canvasClass)}`)) {
      if (canvas.getAttribute("aria-label") === text) continue;
      canvas.setAttribute("role", "application");
      canvas.setAttribute("aria-roledescription", "teaching canvas");
      canvas.setAttribute("aria-label", text);
    }
  };
  new MutationObserver((mutations) => {
    const added = mutations.some((m) => Array.from(m.addedNodes).some((n) =>
      n.nodeType === 1 && (n.tagName === "CANVAS" || n.querySelector("canvas"))));
    if (added) access.models.forEach(({ model }, canvasClass) => access.label(canvasClass, model));
  }).observe(document.body, { childList: true, subtree: true });
  return access;
}

function render({ model, el }) {
  const access = pageAccess();
  const canvasClass = model.get("canvas_class");
  const entry = access.models.get(canvasClass) || { model, views: 0 };
  entry.views += 1;
  access.models.set(canvasClass, entry);

  // The words, in a polite live region: a change (a new state, an arrow, the guidance) is read out.
  el.setAttribute("aria-live", "polite");
  const words = document.createElement("div");
  el.replaceChildren(words);
  const show = () => {
    words.textContent = model.get("text");
    access.label(canvasClass, model);
  };
  show();
  model.on("change:text", show);
  return () => {
    model.off("change:text", show);
    entry.views -= 1;
    if (entry.views === 0 && access.models.get(canvasClass) === entry) access.models.delete(canvasClass);
  };
}

export default { render };
