"""Makes the short instruction video the shipped protocols show (protocols/media/instructions.webm).

Not the paper's video. The paper links its instruction video online (its footnote:
https://youtu.be/Ir2DLJAYytY); it is not ours to redistribute, so the package cannot ship it.
This makes a stand-in: an 8-second animation, drawn on a canvas in Chromium and recorded with
its MediaRecorder (VP8 WebM, which Chromium and Firefox play), of what the paper's
instructions say: drag from the tip to draw an arrow, confirm, watch the robot play back what
it learnt. Run: ``.venv/bin/python scripts/make_instruction_video.py``.

A researcher who has the paper's video (or makes their own) names the file in the protocol's
video step, relative to the protocol file (``file = "media/my_video.mp4"``,
mt_widgets/study/steps.py): its sha256 becomes part of the protocol's data and hash, so every
participant's log says exactly which video they saw; or names its address (``url = ...``).
"""

from __future__ import annotations

import base64
from pathlib import Path

from playwright.sync_api import sync_playwright

OUT = Path(__file__).resolve().parents[1] / "mt_widgets" / "study" / "protocols" / "media" / "instructions.webm"

PAGE = """
<canvas id="c" width="480" height="320"></canvas>
<script>
const c = document.getElementById('c'), g = c.getContext('2d');
const captions = [[0, 'How to teach the robot'], [2, 'Drag from the tip to draw an arrow'],
                  [4.5, 'Press Confirm for each situation'], [6, 'The robot learns and plays it back']];
function frame(t) {
  g.fillStyle = '#ffffff'; g.fillRect(0, 0, 480, 320);
  const base = [240, 250], q1 = 0.9 + 0.15 * Math.sin(t), q2 = 0.8;
  const elbow = [base[0] + 90 * Math.cos(q1), base[1] - 90 * Math.sin(q1)];
  const tip = [elbow[0] + 80 * Math.cos(q1 + q2), elbow[1] - 80 * Math.sin(q1 + q2)];
  g.strokeStyle = '#444'; g.lineWidth = 8; g.beginPath(); g.moveTo(...base); g.lineTo(...elbow); g.lineTo(...tip);
  g.stroke(); g.fillStyle = '#000'; g.beginPath(); g.arc(tip[0], tip[1], 7, 0, 7); g.fill();
  if (t > 2 && t < 6) {
    const k = Math.min(1, (t - 2) / 1.5), end = [tip[0] + 90 * k, tip[1] + 30 * k];
    g.strokeStyle = '#0072B2'; g.lineWidth = 4; g.beginPath(); g.moveTo(...tip); g.lineTo(...end); g.stroke();
  }
  if (t >= 4.5 && t < 6) { g.fillStyle = '#0072B2'; g.fillRect(360, 270, 100, 34);
    g.fillStyle = '#fff'; g.font = '18px sans-serif'; g.fillText('Confirm', 378, 293); }
  let caption = ''; for (const [start, text] of captions) if (t >= start) caption = text;
  g.fillStyle = '#111'; g.font = '22px sans-serif'; g.fillText(caption, 20, 36);
}
window.record = async (seconds) => {
  const stream = c.captureStream(15), chunks = [];
  const recorder = new MediaRecorder(stream, {mimeType: 'video/webm;codecs=vp8', videoBitsPerSecond: 200000});
  recorder.ondataavailable = e => chunks.push(e.data);
  const done = new Promise(r => recorder.onstop = r);
  const start = performance.now(); recorder.start();
  await new Promise(resolve => { (function tick() { const t = (performance.now() - start) / 1000; frame(t);
    if (t < seconds) requestAnimationFrame(tick); else resolve(); })(); });
  recorder.stop(); await done;
  const buffer = await new Blob(chunks, {type: 'video/webm'}).arrayBuffer();
  let s = ''; new Uint8Array(buffer).forEach(b => s += String.fromCharCode(b)); return btoa(s);
};
</script>
"""


def main() -> None:
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium")
        page = browser.new_page()
        page.set_content(PAGE)
        data = page.evaluate("record(8)")
        browser.close()
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_bytes(base64.b64decode(data))
    print(OUT, OUT.stat().st_size, "bytes")


if __name__ == "__main__":
    main()
