"""The STS3215's control table: the registers this suite reads and writes.

Addresses and sizes are Feetech's STS/SMS memory table, as LeRobot's
``lerobot/motors/feetech/tables.py`` (``STS_SMS_SERIES_CONTROL_TABLE``) and Feetech's manual
give them (``docs/user/so101.md`` cites both). Addresses below 40 are the EEPROM area (kept
through a power cycle, written only while ``lock`` is 0); from 40 on, the RAM area (reset at
power-on). A few registers hold a sign in one bit (sign-magnitude, not two's complement):
``homing_offset`` in bit 11, the speeds in bit 15, the load in bit 10.
"""

from __future__ import annotations

from dataclasses import dataclass

#: The model number an STS3215 answers at address 3 (LeRobot's ``MODEL_NUMBER_TABLE``).
STS3215_MODEL = 777
#: Encoder steps in one turn (12 bits).
STEPS_PER_TURN = 4096
#: The first address of the RAM area.
RAM_START = 40
#: Bits a second on the bus at 1 Mbit/s: 8N1 framing, 10 bits a byte, so 10 us a byte.
BAUD = 1_000_000


@dataclass(frozen=True)
class Register:
    """One register: address, size in bytes, writable or not, sign bit (sign-magnitude) or None."""

    name: str
    address: int
    size: int
    writable: bool = True
    sign_bit: int | None = None

    @property
    def eeprom(self) -> bool:
        return self.address < RAM_START


_REGISTERS = (
    Register("firmware_major", 0, 1, writable=False),
    Register("firmware_minor", 1, 1, writable=False),
    Register("model_number", 3, 2, writable=False),
    Register("id", 5, 1),
    Register("baud_rate", 6, 1),
    Register("return_delay", 7, 1),          # units of 2 us before a servo answers
    Register("response_level", 8, 1),
    Register("min_position_limit", 9, 2),
    Register("max_position_limit", 11, 2),
    Register("max_temperature_limit", 13, 1),  # deg C
    Register("max_voltage_limit", 14, 1),      # 0.1 V
    Register("min_voltage_limit", 15, 1),      # 0.1 V
    Register("max_torque_limit", 16, 2),       # 0.1 %
    Register("homing_offset", 31, 2, sign_bit=11),
    Register("operating_mode", 33, 1),         # 0: position servo
    Register("torque_enable", 40, 1),
    Register("acceleration", 41, 1),           # 100 steps/s^2 a unit; 0: the largest
    Register("goal_position", 42, 2),
    Register("goal_time", 44, 2),
    Register("goal_speed", 46, 2, sign_bit=15),  # steps/s; 0: the largest
    Register("torque_limit", 48, 2),
    Register("lock", 55, 1),
    Register("present_position", 56, 2, writable=False),
    Register("present_speed", 58, 2, writable=False, sign_bit=15),
    Register("present_load", 60, 2, writable=False, sign_bit=10),
    Register("present_voltage", 62, 1, writable=False),      # 0.1 V
    Register("present_temperature", 63, 1, writable=False),  # deg C
    Register("status", 65, 1, writable=False),
    Register("moving", 66, 1, writable=False),
    Register("present_current", 69, 2, writable=False),
)

#: Register name -> Register.
REGISTERS: dict[str, Register] = {register.name: register for register in _REGISTERS}


def encode(register: Register, value: int) -> bytes:
    """``value`` as the register's little-endian bytes (sign-magnitude where it has a sign bit)."""
    if not isinstance(value, int) or isinstance(value, bool):
        raise ValueError(f"{register.name}: expected an integer, got {value!r}")
    if register.sign_bit is not None:
        magnitude = abs(value)
        if magnitude >= 1 << register.sign_bit:
            raise ValueError(f"{register.name}: expected |value| < {1 << register.sign_bit}, got {value}")
        raw = magnitude | ((1 << register.sign_bit) if value < 0 else 0)
    else:
        raw = value
        if not 0 <= raw < 1 << (8 * register.size):
            raise ValueError(f"{register.name}: expected 0..{(1 << (8 * register.size)) - 1}, got {value}")
    return raw.to_bytes(register.size, "little")


def decode(register: Register, data: bytes) -> int:
    """The register's value from its bytes."""
    if len(data) != register.size:
        raise ValueError(f"{register.name}: expected {register.size} bytes, got {len(data)}")
    raw = int.from_bytes(data, "little")
    if register.sign_bit is not None and raw & (1 << register.sign_bit):
        return -(raw & ((1 << register.sign_bit) - 1))
    return raw
