"""What differs between the uArm Swift Pro's firmware generations (``docs/uarm-protocol.md``).

Three dialects: 3.x (Marlin-based), 4.0-4.4 and 4.5+ (grbl-based; 4.5 added the planner
clear ``S1100``). The connector detects the version (P2203) and asks :func:`dialect_for`;
nothing else in the package looks at version numbers.
"""

from __future__ import annotations

from dataclasses import dataclass

Command = tuple  # ("S1000", ("V", 0)): a command word and its (letter, value) parameters


@dataclass(frozen=True)
class Dialect:
    """The firmware-specific words of one generation.

    Attributes:
        name: for messages, e.g. ``"4.0-4.4"``.
        move_word: the linear move: ``G1`` on 4.x (``G0`` is joint-space there), ``G0`` on 3.x,
            its documented move.
        feed_per_mm_s: F per mm/s: 60 on 3.x (F in mm/min, the 3.x guide); 1 on 4.x, where F
            is sent as mm/s. UNCERTAIN (the protocol notes): if 4.x read it as mm/min, the arm
            would move slower, never faster.
        ok_when_queued: 3.x answers a move when it is queued (the end is polled with M2200);
            4.x answers G/M commands only when idle, so ``ok`` means the move has finished.
        stop_command: the command that stops at once.
        stop_pauses: the stop is a pause (``S1000 V0``): nothing moves until ``resume_command``,
            and the cut move is still at the head of the firmware's queue.
        resume_command: ends the pause, or None where the stop clears the planner.
        refresh_position: what makes the firmware re-read where the arm is after it was moved
            by hand, or None where attaching does it (4.x re-reads its encoders on M17; 3.x
            only on ``update_current_pos``, which M2000 runs: without it the next move lands
            off by the hand's displacement).
    """

    name: str
    move_word: str
    feed_per_mm_s: float
    ok_when_queued: bool
    stop_command: Command
    stop_pauses: bool
    resume_command: Command | None
    refresh_position: Command | None = None

    def device_name(self, payload: str) -> str:
        """The P2201 answer without the ``V`` prefix 3.x puts in front (``VSwiftPro``)."""
        name = payload.strip()
        return name[1:] if name.startswith("VSwift") else name


FIRMWARE_3 = Dialect("3.x", "G0", 60.0, True, ("M2000",), False, None, ("M2000",))
FIRMWARE_4_0 = Dialect("4.0-4.4", "G1", 1.0, False, ("S1000", ("V", 0)), True, ("S1000", ("V", 1)))
FIRMWARE_4_5 = Dialect("4.5+", "G1", 1.0, False, ("S1100",), False, None)


def dialect_for(version: tuple[int, int, int] | None) -> Dialect:
    """The dialect of a firmware version; 4.0-4.4 when unknown (its stop, a pause, is the
    one that never leaves a move running on any 4.x)."""
    if version is None:
        return FIRMWARE_4_0
    if version[0] == 3:
        return FIRMWARE_3
    return FIRMWARE_4_5 if version >= (4, 5, 0) else FIRMWARE_4_0
