"""The simulated uArm Swift Pro's number grammars: how each firmware reads its arguments.

The 4.x firmware (grbl-based) reads numbers with grbl's ``read_float`` and its fixed
patterns with ``sscanf``; the 3.x firmware (Marlin-based) with ``strtod``/``strtol`` after
Marlin's ``code_seen``. Each reader here reproduces one of them, quirks included
(docs/uarm-protocol.md "The command table"), so the simulated arm accepts and refuses what
the real one does. Pure functions of text.
"""

from __future__ import annotations

import re

_GRBL_FLOAT = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)")
_STRTOD = re.compile(r"\s*([-+]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|inf(?:inity)?|nan))", re.IGNORECASE)
_STRTOL = re.compile(r"\s*([-+]?\d+)")


def grbl_read_float(text: str) -> float | None:
    """grbl's ``read_float``: sign, digits and one point, no exponent; None without a digit.
    What follows the number is left alone (the caller sees it)."""
    m = _GRBL_FLOAT.match(text)
    return float(m.group(0)) if m else None


def marlin_float(text: str) -> float:
    """Marlin's ``code_value_float``: ``strtod`` on the text, cut at the first ``E`` (Marlin's
    extruder letter), so ``1e-05`` is 1e-05 and ``1E-05`` is 1; no number reads as 0."""
    cut = text.split("E", 1)[0]
    m = _STRTOD.match(cut)
    return float(m.group(1)) if m else 0.0


def marlin_int(text: str) -> int:
    """Marlin's ``code_value_int``/``_byte``/``_ushort``: ``strtol`` base 10, 0 without a number."""
    m = _STRTOL.match(text)
    return int(m.group(1)) if m else 0


# sscanf conversions of the 4.x parsers: "f" is %[0-9-+.], "u" is %[0-9.], "d" is %d,
# "s" is %s, "h" is %[0-F.] (the serial number's characters).
_SCAN_SETS = {"f": r"[-+.0-9]+", "u": r"[.0-9]+", "d": r"[-+]?\d+", "s": r"\S+", "h": r"[0-9:;<=>?@A-F.]+"}


def scan4(pattern: list[tuple[str, str]], text: str) -> list[str]:
    """The fields ``sscanf`` fills for a 4.x pattern such as ``X%[0-9-+.]Y...``: it stops
    at the first literal or conversion that does not match, so the count says how far it got."""
    out, pos = [], 0
    for literal, kind in pattern:
        if not text.startswith(literal, pos):
            break
        pos += len(literal)
        m = re.compile(_SCAN_SETS[kind]).match(text, pos)
        if not m:
            break
        out.append(m.group(0))
        pos = m.end()
    return out


def scan_pattern(spec: str) -> list[tuple[str, str]]:
    """``"X f Y f Z f"`` -> ``[("X", "f"), ("Y", "f"), ("Z", "f")]``."""
    parts = spec.split()
    return list(zip(parts[0::2], parts[1::2]))


def grbl_words(args: str) -> dict[str, float] | int | None:
    """grbl's word parser for G0/G1: letter, number, ... -> words, or a status: None for
    the silent ones (a missing letter or number, a negative F), 20 for an unsupported or
    repeated word."""
    words: dict[str, float] = {}
    pos = 0
    while pos < len(args):
        letter = args[pos]
        if not "A" <= letter <= "Z":
            return None
        m = _GRBL_FLOAT.match(args, pos + 1)
        if not m:
            return None
        if letter not in "XYZFN" or letter in words:
            return 20
        words[letter] = float(m.group(0))
        pos = m.end()
    if words.get("F", 0.0) < 0:
        return None
    return words


def marlin_seen(args: str, letter: str) -> bool:
    """Marlin's ``code_seen``: whether ``letter`` is anywhere in the arguments (``strchr``)."""
    return letter in args


def marlin_after(args: str, letter: str) -> str:
    """The text after the first ``letter`` of the arguments, where Marlin's ``code_value`` reads."""
    return args[args.index(letter) + 1:]
