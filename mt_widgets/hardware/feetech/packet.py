"""The Feetech STS/SMS serial protocol's packets: framing, checksum, instructions, status error bits.

The STS3215 speaks Feetech's "protocol 0" (a Dynamixel 1.0-like packet; the SDK's
``scservo_sdk/protocol_packet_handler.py`` and Feetech's STS/SMS manual, see
``docs/user/so101.md``)::

    instruction  FF FF  id  length  instruction  parameters...  checksum
    status       FF FF  id  length  error        parameters...  checksum

``length`` counts the parameters plus two (the instruction or error byte and the checksum);
the checksum is the bitwise NOT of the low byte of the sum of every byte from ``id`` to the
last parameter. Multi-byte values in parameters are little-endian (the SDK's ``SCS_END = 0``
for the STS series). Id 0xFE is the broadcast id: every servo obeys and none answers.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

HEADER = b"\xff\xff"
BROADCAST_ID = 0xFE
#: Bytes around the parameters: two header bytes, id, length, instruction/error, checksum.
OVERHEAD = 6


class Instruction(enum.IntEnum):
    """The instruction byte of a host's packet."""

    PING = 0x01
    READ = 0x02
    WRITE = 0x03
    REG_WRITE = 0x04   # stored until ACTION
    ACTION = 0x05      # runs the stored REG_WRITEs (usually broadcast, to start servos together)
    SYNC_READ = 0x82   # one packet, each listed servo answers in the order of the list
    SYNC_WRITE = 0x83  # one packet, one block of data per servo, no answer


class StatusError(enum.IntFlag):
    """The error byte of a servo's status packet (the STS/SMS manual; the SDK's ``ERRBIT_*``)."""

    VOLTAGE = 0x01      # supply outside Min/Max_Voltage_Limit
    SENSOR = 0x02       # the magnetic angle sensor failed
    OVERHEAT = 0x04     # temperature above Max_Temperature_Limit
    OVERCURRENT = 0x08  # current above Protection_Current
    OVERLOAD = 0x20     # load above Overload_Torque for Protection_Time: the servo drops its torque


def checksum(body: bytes | bytearray) -> int:
    """The checksum of ``body`` (id, length, instruction/error and parameters)."""
    return ~sum(body) & 0xFF


def _frame(servo_id: int, code: int, parameters: bytes) -> bytes:
    if not (isinstance(servo_id, int) and 0 <= servo_id <= BROADCAST_ID):
        raise ValueError(f"servo_id: expected an integer 0..254, got {servo_id!r}")
    if len(parameters) > 250:
        raise ValueError(f"parameters: expected at most 250 bytes, got {len(parameters)}")
    body = bytes((servo_id, len(parameters) + 2, code)) + bytes(parameters)
    return HEADER + body + bytes((checksum(body),))


def instruction_packet(servo_id: int, instruction: Instruction, parameters: bytes = b"") -> bytes:
    """The bytes of an instruction packet from the host."""
    return _frame(servo_id, int(Instruction(instruction)), bytes(parameters))


def status_packet(servo_id: int, error: int, parameters: bytes = b"") -> bytes:
    """The bytes of a servo's status packet (its answer)."""
    if not (isinstance(error, int) and 0 <= error <= 0xFF):
        raise ValueError(f"error: expected a byte 0..255, got {error!r}")
    return _frame(servo_id, error, bytes(parameters))


@dataclass(frozen=True)
class Packet:
    """A decoded packet: ``code`` is the instruction (host's packet) or the error byte (status)."""

    servo_id: int
    code: int
    parameters: bytes
    valid: bool = True  # False: the checksum did not match


def split_packets(buffer: bytes | bytearray) -> tuple[list[Packet], bytes]:
    """The complete packets at the front of ``buffer`` and the bytes left over.

    Bytes before a header are skipped (noise on the bus). A packet whose checksum does not
    match is returned with ``valid=False``: the caller decides (a servo ignores it, a host
    reports a corrupted reply). The rest is an incomplete packet to wait for.
    """
    data = bytes(buffer)
    packets: list[Packet] = []
    while True:
        start = data.find(HEADER)
        if start < 0:
            # Keep a trailing 0xFF: it may be the first half of the next header.
            return packets, data[-1:] if data.endswith(b"\xff") else b""
        data = data[start:]
        # A third 0xFF is not an id a packet can carry: skip one byte of a longer run of 0xFF.
        if len(data) >= 3 and data[2] == 0xFF:
            data = data[1:]
            continue
        if len(data) < 4:
            return packets, data
        length = data[3]
        if length < 2:
            data = data[2:]
            continue
        end = 4 + length
        if len(data) < end:
            return packets, data
        body = data[2:end - 1]
        packets.append(Packet(data[2], data[4], bytes(data[5:end - 1]), checksum(body) == data[end - 1]))
        data = data[end:]
