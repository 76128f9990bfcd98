"""Audio cues of teaching effort: a tone in the browser and the same tone on the arm's buzzer.

The paper's physical set-up gives "auditory guidance for teaching effort progress ... via a
speaker" (Fig. 2b). Here each confirmed demonstration sounds a short tone whose pitch
rises with the demonstrations done in the episode (:func:`effort_tone_hz`), and the end of
an episode a longer, higher one; the tone is played by the browser (an ipywidgets
``Audio`` holding WAV bytes made with numpy, no files) and by the arm's buzzer (M2210).
The cue is the same for every group: it tells effort, never the quality of a demonstration.
"""

from __future__ import annotations

import io
import math
import wave

import numpy as np
from ipywidgets import Audio, HBox, Layout

from mt_widgets.core.validation import as_bool, as_count, as_positive

#: Pitch of the first and of the last demonstration's cue (Hz): an octave, A4 to A5.
LOW_HZ, HIGH_HZ = 440.0, 880.0
#: The episode's end: higher than any demonstration's cue.
EPISODE_END_HZ = 1175.0
DEMONSTRATION_CUE_S = 0.15
EPISODE_END_CUE_S = 0.4


def tone_wav(frequency_hz: float, duration_s: float, sample_rate: int = 22050, volume: float = 0.5,
             fade_s: float = 0.01) -> bytes:
    """A sine tone as the bytes of a 16-bit mono PCM WAV file.

    Args:
        frequency_hz: pitch, 20 Hz .. sample_rate / 2.
        duration_s: length in seconds, 0.01 .. 10.
        sample_rate: samples per second.
        volume: peak amplitude as a fraction of full scale, (0, 1].
        fade_s: linear fade in and out, seconds (a hard start clicks).
    """
    # as_count / as_positive refuse booleans (True is an int to Python, never a rate to us).
    if not 8000 <= as_count("sample_rate", sample_rate) <= 192000:
        raise ValueError(f"sample_rate: expected an int in 8000..192000 Hz, got {sample_rate!r}")
    if not 20 <= as_positive("frequency_hz", frequency_hz) <= sample_rate / 2:
        raise ValueError(f"frequency_hz: expected 20..{sample_rate / 2:g} Hz, got {frequency_hz!r}")
    if not 0.01 <= as_positive("duration_s", duration_s) <= 10:
        raise ValueError(f"duration_s: expected 0.01..10 s, got {duration_s!r}")
    if not as_positive("volume", volume) <= 1:
        raise ValueError(f"volume: expected a fraction in (0, 1], got {volume!r}")
    if not as_positive("fade_s", fade_s, allow_zero=True) <= duration_s / 2:
        raise ValueError(f"fade_s: expected 0..duration_s / 2 = {duration_s / 2:g} s, got {fade_s!r}")
    n = int(round(duration_s * sample_rate))
    t = np.arange(n) / sample_rate
    signal = np.sin(2 * np.pi * frequency_hz * t)
    ramp = int(round(fade_s * sample_rate))
    if ramp > 0:
        envelope = np.ones(n)
        envelope[:ramp] = np.linspace(0.0, 1.0, ramp)
        envelope[n - ramp:] = np.linspace(1.0, 0.0, ramp)
        signal *= envelope
    samples = np.round(signal * volume * 32767).astype("<i2")
    buffer = io.BytesIO()
    with wave.open(buffer, "wb") as out:
        out.setnchannels(1)
        out.setsampwidth(2)
        out.setframerate(sample_rate)
        out.writeframes(samples.tobytes())
    return buffer.getvalue()


def effort_tone_hz(done: int, total: int) -> float:
    """The cue's pitch after ``done`` of ``total`` demonstrations: 440 Hz for the first, rising
    in equal musical steps to 880 Hz for the last."""
    total = as_count("total", total)
    if not as_count("done", done) <= total:
        raise ValueError(f"done: expected 1..total = {total}, got {done!r}")
    if total == 1:
        return HIGH_HZ
    return LOW_HZ * (HIGH_HZ / LOW_HZ) ** ((done - 1) / (total - 1))


class AudioCues(HBox):
    """Plays tones in the browser; each cue is a fresh ``Audio`` widget set to autoplay once.

    A fresh widget per cue, because an ``Audio`` whose value does not change is not played
    again, and ``loop`` (True by default in ipywidgets) would repeat the tone for ever.
    Browsers play sound only after the user interacted with the page (a click or a drag
    does), which the participant has always done before a cue.

    Args:
        arm_beep: optional ``callback(frequency_hz, duration_ms)`` sounding the arm's buzzer.
        enabled: whether the browser plays the tones.
    """

    def __init__(self, arm_beep=None, enabled: bool = True):
        super().__init__([], layout=Layout(width="0px", height="0px", overflow="hidden"))
        self.arm_beep = arm_beep
        self.enabled = as_bool("enabled", enabled)
        self.played: list[tuple[float, float]] = []

    def play(self, frequency_hz: float, duration_s: float) -> None:
        """Sound one tone in the browser and on the arm."""
        self.played.append((float(frequency_hz), float(duration_s)))
        if self.enabled:
            self.children = [Audio(value=tone_wav(frequency_hz, duration_s), format="wav", autoplay=True,
                                   loop=False, controls=False)]
        if self.arm_beep is not None:
            self.arm_beep(frequency_hz, max(1.0, math.floor(duration_s * 1000.0)))

    def demonstration(self, done: int, total: int) -> None:
        """The cue after the ``done``-th of ``total`` demonstrations."""
        self.play(effort_tone_hz(done, total), DEMONSTRATION_CUE_S)

    def episode_end(self) -> None:
        """The cue at the end of an episode."""
        self.play(EPISODE_END_HZ, EPISODE_END_CUE_S)


__all__ = ["AudioCues", "EPISODE_END_HZ", "HIGH_HZ", "LOW_HZ", "effort_tone_hz", "tone_wav"]
