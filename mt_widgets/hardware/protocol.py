"""Text of the uArm Swift Pro serial protocol: building request lines, sorting received lines.

Pure functions, no I/O; the facts come from ``docs/uarm-protocol.md`` (sections "Link",
"Framing", "Errors and events").
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

#: Longest line firmware 4.x accepts (characters, newline excluded).
MAX_LINE_CHARS = 80
#: Numbers 1..9999, wrapping, as in the official uArm-Python-SDK.
MAX_REQUEST_NUMBER = 9999
#: Characters the 4.x (grbl) serial interrupt swallows as real-time commands: never send them.
FORBIDDEN_CHARS = frozenset("?!~@\x18")

_FIXED_DECIMAL = re.compile(r"^[-+]?(\d+(\.\d*)?|\.\d+)$")
_REPLY = re.compile(r"^\$(\d+)(?:\s+(.*))?$")
_ERROR_TOKEN = re.compile(r"(?:^|\s)E(\d+)(?=\s|$)")
_BARE_ERROR = re.compile(r"^E(\d+)(?:\s.*)?$")
_EVENT = re.compile(r"^@(\d+)(?:\s+(.*))?$")
_VALUE = re.compile(r"^([A-Z])([-+]?(?:\d+(?:\.\d*)?|\.\d+))$")
_VERSION = re.compile(r"V?(\d+)\.(\d+)(?:\.(\d+))?")


def format_number(value: float, *, name: str = "value", decimals: int = 4) -> str:
    """Format a number in fixed-decimal form, the only form firmware 4.x accepts.

    ``repr(0.00001)`` is ``1e-05``, which 4.x rejects with E21; this never writes an
    exponent. Trailing zeros are dropped and ``-0`` is written ``0``.

    Args:
        value: the number (any unit; the caller knows which).
        name: the parameter's name, for the error message.
        decimals: digits after the point (4, as the SDK sends on 4.x).

    Returns:
        The number as text, e.g. ``"180"``, ``"-12.5"``, ``"0.0001"``.

    Raises:
        ValueError: if ``value`` is not a finite real number below 1e6 in magnitude.
    """
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name}: expected a real number, got {value!r}") from exc
    if not math.isfinite(v) or abs(v) >= 1e6:
        raise ValueError(f"{name}: expected a finite number below 1e6 in magnitude, got {value!r}")
    text = f"{v:.{decimals}f}"
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    if text in ("-0", "+0", ""):
        text = "0"
    return text


def is_fixed_decimal(text: str) -> bool:
    """Whether ``text`` is a number in the fixed-decimal form the firmware parses."""
    return bool(_FIXED_DECIMAL.match(text))


def check_line(line: str) -> str:
    """Check a line before it goes on the wire.

    Args:
        line: the full line without its newline, e.g. ``"#12 P2220"``.

    Returns:
        The line, unchanged.

    Raises:
        ValueError: if it holds a newline, a non-printable or non-ASCII character, a grbl
            real-time character (``? ! ~ @`` or 0x18), or is longer than 80 characters.
    """
    if len(line) > MAX_LINE_CHARS:
        raise ValueError(f"line: expected at most {MAX_LINE_CHARS} characters, got {len(line)}: {line!r}")
    bad = sorted({c for c in line if c in FORBIDDEN_CHARS or not (" " <= c <= "~")})
    if bad:
        raise ValueError(
            f"line: expected printable ASCII without the real-time characters ? ! ~ @, got {bad!r} in {line!r}"
        )
    return line


def build_request(number: int | None, command: str, *params: tuple[str, float | int]) -> str:
    """Build one request line (without newline).

    Args:
        number: the request number 1..9999, or None for an unnumbered line.
        command: the command word, e.g. ``"G1"`` or ``"P2220"``.
        *params: ``(letter, value)`` pairs, written in the given order (4.x parses some
            commands with a fixed pattern: order matters).

    Returns:
        e.g. ``"#7 G1 X200 Y0 Z80 F50"``.
    """
    if not re.fullmatch(r"[GMPS]\d{1,4}", command):
        raise ValueError(f"command: expected a letter G/M/P/S and 1-4 digits, got {command!r}")
    parts = [] if number is None else [f"#{int(number)}"]
    parts.append(command)
    for letter, value in params:
        if not re.fullmatch(r"[A-Z]", letter):
            raise ValueError(f"parameter letter: expected one capital letter, got {letter!r}")
        parts.append(letter + format_number(value, name=f"{command} {letter}"))
    return check_line(" ".join(parts))


@dataclass(frozen=True)
class Reply:
    """A numbered reply ``$n ...``.

    Attributes:
        number: the request number it answers.
        ok: True if the reply says ``ok`` and carries no error code.
        error_code: the ``E<code>`` number if any (3.x writes ``ok E22 unreachable``).
        payload: the text after ``ok`` (e.g. ``"X200.0000 Y0.0000 Z80.0000"``).
        line: the raw line.
    """

    number: int
    ok: bool
    error_code: int | None
    payload: str
    line: str


@dataclass(frozen=True)
class Event:
    """An unsolicited line: ``@n`` reports, ``echo:`` lines, bare errors, banners.

    Attributes:
        kind: ``"@1"``, ``"@3"``, ... for reports; ``"echo"``; ``"error"`` for a bare
            ``E<code>``; ``"info"`` for anything else (banners, ``start``).
        line: the raw line.
        values: letter -> number for ``@n`` reports (``@3 X.. Y.. Z.. R..``).
        error_code: the code of a bare error line (``E23 buffer full``), else None.
    """

    kind: str
    line: str
    values: dict[str, float] = field(default_factory=dict)
    error_code: int | None = None


def parse_values(payload: str) -> dict[str, float]:
    """Read ``X200.0000 Y0.0000 ...`` into ``{"X": 200.0, "Y": 0.0}``; other tokens are skipped."""
    out: dict[str, float] = {}
    for token in payload.split():
        m = _VALUE.match(token)
        if m:
            out[m.group(1)] = float(m.group(2))
    return out


def parse_version(text: str) -> tuple[int, int, int] | None:
    """Read ``V4.10.0`` / ``4.10`` into ``(4, 10, 0)``; None if there is no version."""
    m = _VERSION.search(text)
    if not m:
        return None
    return int(m.group(1)), int(m.group(2)), int(m.group(3) or 0)


def classify_line(raw: str) -> Reply | Event | None:
    """Sort one received line into a reply or an event.

    Args:
        raw: a line as read, with or without ``\\r`` (3.x ends lines with ``\\r\\n``).

    Returns:
        A :class:`Reply` for ``$n ...``, an :class:`Event` for anything else, None for a
        blank line (3.x sometimes sends them).
    """
    line = raw.strip()
    if not line:
        return None
    m = _REPLY.match(line)
    if m:
        rest = (m.group(2) or "").strip()
        err = _ERROR_TOKEN.search(rest)
        code = int(err.group(1)) if err else None
        words = rest.split(maxsplit=1)
        is_ok = bool(words) and words[0].lower() == "ok"
        payload = words[1] if is_ok and len(words) > 1 else ("" if is_ok else rest)
        return Reply(int(m.group(1)), is_ok and code is None, code, payload, line)
    m = _EVENT.match(line)
    if m:
        return Event("@" + m.group(1), line, parse_values(m.group(2) or ""))
    m = _BARE_ERROR.match(line)
    if m:
        return Event("error", line, error_code=int(m.group(1)))
    if line.lower().startswith("echo:"):
        return Event("echo", line)
    return Event("info", line)
