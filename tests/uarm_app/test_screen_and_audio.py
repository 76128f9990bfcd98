"""The true-scale screen view and the audio cues, without a kernel."""

from __future__ import annotations

import io
import math
import wave

import numpy as np
import pytest
from ipywidgets import Audio

from mt_widgets.apps.uarm_audio import EPISODE_END_HZ, HIGH_HZ, LOW_HZ, AudioCues, effort_tone_hz, tone_wav
from mt_widgets.apps.uarm_screen import SCREEN_CLASS, ScreenGeometry, fit_episode
from mt_widgets.hardware.bridge import UArmBridge
from mt_widgets.widgets import EpisodeWidget

from .helpers import device_of


# ----------------------------------------------------------------------------- true scale
def test_the_papers_screen_gives_its_pixels_per_millimetre():
    geometry = ScreenGeometry(screen_mm=(518, 325), resolution_px=(1920, 1200))
    assert geometry.pixels_per_mm_xy == pytest.approx((1920 / 518, 1200 / 325))
    assert geometry.pixels_per_mm == pytest.approx((1920 / 518 + 1200 / 325) / 2)
    assert 3.69 < geometry.pixels_per_mm < 3.71
    t = geometry.transform("cm")
    assert t.pixels_per_unit == pytest.approx(10 * geometry.pixels_per_mm)
    # 10 cm in the plant is 100 mm on the screen, whichever way it points.
    for direction in ([1, 0], [0, 1], [0.6, -0.8]):
        a, b = t.to_pixel([[20.0, 0.0], np.add([20.0, 0.0], 10 * np.asarray(direction))])
        assert np.linalg.norm(b - a) / geometry.pixels_per_mm == pytest.approx(100.0)
    assert geometry.transform("mm").pixels_per_unit == pytest.approx(geometry.pixels_per_mm)


def test_the_world_frame_is_aligned_with_the_arms_base_on_the_screen():
    geometry = ScreenGeometry(screen_mm=(518, 325), resolution_px=(1920, 1200), canvas_px=(1920, 900),
                              base_px=(960, 1100), heading_deg=90)
    t = geometry.transform("cm")
    np.testing.assert_allclose(t.to_pixel([0.0, 0.0]), [960, 1100])
    ppcm = t.pixels_per_unit
    # heading 90: the arm's +X (forward) points up the screen, +Y (left) to the left.
    np.testing.assert_allclose(t.to_pixel([20.0, 0.0]), [960, 1100 - 20 * ppcm])
    np.testing.assert_allclose(t.to_pixel([20.0, 5.0]), [960 - 5 * ppcm, 1100 - 20 * ppcm])
    turned = ScreenGeometry(screen_mm=(518, 325), resolution_px=(1920, 1200), base_px=(0, 450), heading_deg=0)
    np.testing.assert_allclose(turned.transform().to_pixel([20.0, 5.0]), [20 * ppcm, 450 - 5 * ppcm])
    points = np.random.default_rng(1).uniform(-30, 30, (20, 2))
    np.testing.assert_allclose(t.to_world(t.to_pixel(points)), points, atol=1e-9)
    tip = t.action_tip([22.0, 3.0], [1.5, -2.0])
    np.testing.assert_allclose(t.action_from_drag([22.0, 3.0], tip), [1.5, -2.0], atol=1e-9)
    # True-scale arrows: the tip of an action is drawn where the tool would go.
    np.testing.assert_allclose(tip, t.to_pixel([23.5, 1.0]))


def test_the_default_canvas_holds_the_whole_workspace_of_the_papers_screen():
    geometry = ScreenGeometry()
    t = geometry.transform("cm")
    width, height = geometry.canvas_px
    assert (width, height) == (1920, 1200 - 260)
    yaw = np.deg2rad(np.linspace(-50, 50, 21))
    for r in (14.0, 30.0):
        px = t.to_pixel(np.stack([r * np.cos(yaw), r * np.sin(yaw)], axis=-1))
        assert np.all((px >= 0) & (px <= [width, height]))


def test_screen_geometry_errors_name_the_argument():
    with pytest.raises(ValueError, match=r"screen_mm, resolution_px: expected square pixels"):
        ScreenGeometry(screen_mm=(518, 325), resolution_px=(1200, 1920))
    with pytest.raises(ValueError, match="screen_mm: expected two positive"):
        ScreenGeometry(screen_mm=(0, 325))
    with pytest.raises(ValueError, match="canvas_px: expected at most"):
        ScreenGeometry(canvas_px=(4000, 100))
    with pytest.raises(ValueError, match="units"):
        ScreenGeometry().transform("m")


def test_an_episode_fitted_to_the_screen_is_drawn_at_true_scale(recorder):
    geometry = ScreenGeometry(screen_mm=(300, 200), resolution_px=(1200, 800), canvas_px=(1200, 700),
                              base_px=(600, 760))
    episode = EpisodeWidget("uarm-point", seed=0, guidance=True, theme="paper-uarm")
    recorder.clear()
    fit_episode(episode, geometry)
    view = episode.teaching.view
    assert (view.canvas.width, view.canvas.height) == (1200, 700)
    assert SCREEN_CLASS in view.canvas._dom_classes and view.canvas.layout.width == "1200px"
    state = episode.query_states[0]
    expected = np.array([600 - state[1] * 40.0, 760 - state[0] * 40.0])  # 4 px/mm = 40 px/cm
    np.testing.assert_allclose(view.end_effector_pixel(state), expected)
    # The black dot is drawn there, the red target at (23, 11) cm.
    robot = recorder.on(view.layer("robot"))
    dots = [args for name, args in robot if name == "fillCircle"]
    assert any(np.allclose(args[:2], expected) for args in dots)
    background = recorder.on(view.layer("background"))
    target = np.array([600 - 11 * 40.0, 760 - 23 * 40.0])
    assert any(name == "fillCircle" and np.allclose(args[:2], target) for name, args in background)
    # A real drag of 40 px up the screen from the dot is a step of +1 cm in r1.
    canvas = view.canvas
    x, y = expected
    for event, px, py in (("mouse_down", x, y), ("mouse_move", x, y - 40), ("mouse_up", x, y - 40)):
        canvas[-1]._handle_frontend_event(None, {"event": event, "x": px, "y": py}, [])
    np.testing.assert_allclose(episode.teaching.pending_action, [1.0, 0.0], atol=1e-9)
    assert episode.player.layout.display == "none"


# ----------------------------------------------------------------------------- audio
def _read(wav_bytes):
    with wave.open(io.BytesIO(wav_bytes)) as w:
        params = w.getnchannels(), w.getsampwidth(), w.getframerate(), w.getnframes()
        samples = np.frombuffer(w.readframes(w.getnframes()), dtype="<i2")
    return params, samples


@pytest.mark.parametrize("frequency, duration", [(440.0, 0.15), (1175.0, 0.4), (659.25, 1.0)])
def test_the_tone_is_a_valid_wav_of_the_right_duration_and_pitch(frequency, duration):
    data = tone_wav(frequency, duration)
    assert data[:4] == b"RIFF" and data[8:12] == b"WAVE"
    (channels, width, rate, frames), samples = _read(data)
    assert (channels, width, rate) == (1, 2, 22050)
    assert frames / rate == pytest.approx(duration, abs=1 / rate)
    spectrum = np.abs(np.fft.rfft(samples * np.hanning(len(samples))))
    peak_hz = np.fft.rfftfreq(len(samples), 1 / rate)[np.argmax(spectrum)]
    assert abs(peak_hz - frequency) <= rate / len(samples)  # within one FFT bin
    assert 0.45 * 32767 < np.abs(samples).max() <= 0.5 * 32767 + 1
    assert samples[0] == 0 and abs(int(samples[-1])) < 200  # faded: no click


def test_tone_arguments_are_checked():
    with pytest.raises(ValueError, match="frequency_hz"):
        tone_wav(20000.0, 0.1)
    with pytest.raises(ValueError, match="duration_s"):
        tone_wav(440.0, 0.0)


def test_the_effort_cue_rises_an_octave_over_an_episode():
    pitches = [effort_tone_hz(k, 3) for k in (1, 2, 3)]
    assert pitches[0] == LOW_HZ and pitches[-1] == pytest.approx(HIGH_HZ)
    assert pitches[0] < pitches[1] < pitches[2] < EPISODE_END_HZ
    assert pitches[1] == pytest.approx(math.sqrt(LOW_HZ * HIGH_HZ))
    with pytest.raises(ValueError, match="done"):
        effort_tone_hz(4, 3)


def test_cues_play_in_the_browser_once_and_on_the_arms_buzzer(arm):
    bridge = UArmBridge(arm)
    cues = AudioCues(arm_beep=bridge.beep)
    cues.demonstration(2, 3)
    (audio,) = cues.children
    assert isinstance(audio, Audio) and audio.format == "wav" and audio.autoplay and not audio.loop
    assert _read(audio.value)[0][3] == round(0.15 * 22050)
    cues.episode_end()
    assert cues.children[0] is not audio
    assert device_of(arm).beeps == [(pytest.approx(effort_tone_hz(2, 3), abs=1e-3), 150.0), (EPISODE_END_HZ, 400.0)]
