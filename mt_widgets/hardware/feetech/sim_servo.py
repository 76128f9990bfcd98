"""One simulated STS3215 servo: its control table, its EEPROM, its motion and its faults.

Pure Python and deterministic: time is passed in (``now``, seconds on any monotonic clock).
The bus (:mod:`.sim_bus`) parses the packets and calls :meth:`SimulatedServo.read` and
:meth:`SimulatedServo.write`; this module is what one servo does with them, as Feetech's
STS/SMS manual describes (``docs/user/so101.md``):

- the control table is 256 bytes; addresses below 40 are the EEPROM area, copied from the
  non-volatile EEPROM at power-on; a write there while ``lock`` (55) is 1 changes the value
  until power-off but is not saved (the manual's "write lock");
- read-only registers (model number, present values, status) ignore writes;
- ``present_position = raw - homing_offset`` (mod 4096), and goal positions are in the same
  frame, clamped into ``[min_position_limit, max_position_limit]`` (both 0 = no limit);
- with torque on the shaft moves towards the goal at ``goal_speed`` (0: the servo's largest)
  with ``acceleration`` x 100 steps/s^2 (0: the largest), a trapezoid; ``moving`` is 1 while
  it does; with torque off it stays where a hand puts it;
- an overload drops the torque and sets error bit 0x20 until torque is enabled again; a
  supply outside the voltage limits sets bit 0x01 in every answer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .control_table import REGISTERS, STEPS_PER_TURN, STS3215_MODEL, Register, decode, encode
from .packet import StatusError

#: The STS3215's largest speed (steps/s) and acceleration (steps/s^2), for goal_speed 0 / acceleration 0.
MAX_SPEED = 3400.0
MAX_ACCELERATION = 25400.0

#: Factory values of the EEPROM area (the manual's defaults; LeRobot's configure_motors lowers return_delay to 0).
_FACTORY = {
    "firmware_major": 3, "firmware_minor": 10, "model_number": STS3215_MODEL, "baud_rate": 0,
    "return_delay": 250, "response_level": 1, "min_position_limit": 0, "max_position_limit": 4095,
    "max_temperature_limit": 70, "max_voltage_limit": 140, "min_voltage_limit": 40, "max_torque_limit": 1000,
    "homing_offset": 0, "operating_mode": 0,
}


@dataclass
class SimulatedServo:
    """One STS3215 on the simulated bus.

    Args:
        servo_id: its id (the EEPROM's ``id``).
        position: the shaft's raw encoder position at power-on, steps.
        model: the model number it answers (another model is a wrong servo on the bus).
        speed_scale: factor on speeds and accelerations (tests use 10 to make moves short).
    """

    servo_id: int
    position: float = 2048.0
    model: int = STS3215_MODEL
    speed_scale: float = 1.0
    #: Every goal position written, in the present-position frame after clamping (for tests).
    goals: list[int] = field(default_factory=list)
    #: Every goal position as written by the host, before clamping (for tests).
    goals_written: list[int] = field(default_factory=list)
    #: For each of ``goals_written``: whether it was where the shaft already was (a hold, no motion).
    holds: list[bool] = field(default_factory=list)

    def __post_init__(self):
        self.eeprom = bytearray(256)
        for name, value in _FACTORY.items():
            self._poke(self.eeprom, REGISTERS[name], value)
        self._poke(self.eeprom, REGISTERS["id"], self.servo_id)
        self._poke(self.eeprom, REGISTERS["model_number"], self.model)
        self.voltage = 12.0
        self.temperature = 30.0
        self.power_on(0.0)

    # ------------------------------------------------------------------ memory
    @staticmethod
    def _poke(memory: bytearray, register: Register, value: int) -> None:
        memory[register.address:register.address + register.size] = encode(register, value)

    def value(self, name: str) -> int:
        """The control table's value of register ``name`` (as the host would read it)."""
        register = REGISTERS[name]
        return decode(register, bytes(self.table[register.address:register.address + register.size]))

    def power_on(self, now: float) -> None:
        """(Re)start: RAM reset, the EEPROM area copied from the EEPROM, torque off."""
        self.table = bytearray(self.eeprom)
        self._poke(self.table, REGISTERS["lock"], 1)
        self._poke(self.table, REGISTERS["torque_limit"], self.value("max_torque_limit"))
        self.velocity = 0.0
        self.target = self.position
        self.overloaded = False
        self.t = now
        self._refresh()

    # ------------------------------------------------------------------ frames
    def _present(self, raw: float) -> int:
        return int(round(raw - self.value("homing_offset"))) % STEPS_PER_TURN

    def _raw(self, present: int) -> float:
        # The raw target nearest the shaft with that present-frame value (no wrap-around jump).
        raw = present + self.value("homing_offset")
        turns = round((self.position - raw) / STEPS_PER_TURN)
        return raw + turns * STEPS_PER_TURN

    @property
    def torque(self) -> bool:
        return self.table[REGISTERS["torque_enable"].address] == 1

    @property
    def error(self) -> int:
        """The error byte of its next answer."""
        bits = StatusError(0)
        if not self.value("min_voltage_limit") <= round(self.voltage * 10) <= self.value("max_voltage_limit"):
            bits |= StatusError.VOLTAGE
        if self.temperature > self.value("max_temperature_limit"):
            bits |= StatusError.OVERHEAT
        if self.overloaded:
            bits |= StatusError.OVERLOAD
        return int(bits)

    # ------------------------------------------------------------------ the host's side
    def read(self, address: int, size: int, now: float) -> bytes:
        self.advance(now)
        end = min(256, address + size)
        return bytes(self.table[address:end]).ljust(size, b"\0")

    def write(self, address: int, data: bytes, now: float) -> None:
        """A WRITE (or an ACTION'd REG_WRITE) of ``data`` at ``address``, byte by byte."""
        self.advance(now)
        lock_was = self.table[REGISTERS["lock"].address]
        written = {}
        for offset, byte in enumerate(data):
            a = address + offset
            if a > 255:
                break
            register = next((r for r in REGISTERS.values() if r.address <= a < r.address + r.size), None)
            if register is not None and not register.writable:
                continue
            self.table[a] = byte
            if a < 40 and lock_was == 0:
                self.eeprom[a] = byte
            if register is not None:
                written[register.name] = register
        if "torque_enable" in written:
            if self.torque:
                # Enabling torque clears an overload and holds the shaft where it is (the goal
                # register follows), so the arm never jumps to an old goal.
                self.overloaded = False
                self.target = self.position
                self._poke(self.table, REGISTERS["goal_position"], self._present(self.position))
            else:
                self.velocity = 0.0
        if "goal_position" in written:
            goal = self.value("goal_position")
            self.goals_written.append(goal)
            self.holds.append(abs(goal - self._present(self.position)) <= 1)
            low, high = self.value("min_position_limit"), self.value("max_position_limit")
            if low or high:
                goal = min(max(goal, low), high)
            self.goals.append(goal)
            self.target = self._raw(goal)
        self._refresh()

    # ------------------------------------------------------------------ motion
    def advance(self, now: float) -> None:
        """Move the shaft up to ``now``."""
        dt_total = now - self.t
        if dt_total <= 0:
            return
        self.t = now
        if not self.torque or self.overloaded:
            self.velocity = 0.0
            self._refresh()
            return
        speed = (abs(self.value("goal_speed")) or MAX_SPEED) * self.speed_scale
        acceleration = (self.value("acceleration") * 100.0 or MAX_ACCELERATION) * self.speed_scale
        # Trapezoid in closed form over 1 ms slices: exact enough, and cheap for long gaps.
        steps = max(1, min(10_000, math.ceil(dt_total / 0.001)))
        dt = dt_total / steps
        for _ in range(steps):
            error = self.target - self.position
            if abs(error) < 0.5 and abs(self.velocity) < acceleration * dt:
                self.position, self.velocity = self.target, 0.0
                break
            stopping = self.velocity * self.velocity / (2 * acceleration)
            direction = math.copysign(1.0, error)
            if abs(error) <= stopping and self.velocity * direction > 0:
                wanted = 0.0
            else:
                wanted = direction * speed
            change = max(-acceleration * dt, min(acceleration * dt, wanted - self.velocity))
            self.velocity += change
            step = self.velocity * dt
            if abs(step) >= abs(error) and step * error >= 0:
                self.position, self.velocity = self.target, 0.0
                break
            self.position += step
        self._refresh()

    def _refresh(self) -> None:
        """Present values from the shaft's state."""
        self._poke(self.table, REGISTERS["present_position"], self._present(self.position))
        self._poke(self.table, REGISTERS["present_speed"], int(round(max(-32767, min(32767, self.velocity)))))
        self._poke(self.table, REGISTERS["present_voltage"], max(0, min(255, round(self.voltage * 10))))
        self._poke(self.table, REGISTERS["present_temperature"], max(0, min(255, round(self.temperature))))
        self._poke(self.table, REGISTERS["status"], self.error)
        moving = self.torque and not self.overloaded and self.position != self.target
        self._poke(self.table, REGISTERS["moving"], int(moving))

    def flash(self, name: str, value: int) -> None:
        """Set register ``name`` in the EEPROM and the table (as a factory or an earlier
        calibration left it; the host writes through :meth:`write`)."""
        register = REGISTERS[name]
        if not register.eeprom:
            raise ValueError(f"name: expected a register of the EEPROM area, got {name!r}")
        self._poke(self.eeprom, register, value)
        self._poke(self.table, register, value)
        self._refresh()

    # ------------------------------------------------------------------ a hand, and faults
    def hand_move(self, present: int, now: float) -> bool:
        """A hand turns the joint to ``present`` (present-frame steps). Only with torque off
        (or after an overload dropped it): a powered servo holds its position."""
        self.advance(now)
        if self.torque and not self.overloaded:
            return False
        self.position = self._raw(int(present))
        self.target = self.position
        self._refresh()
        return True

    def overload(self, now: float) -> None:
        """The load stays above the overload torque: the servo drops its torque and says so."""
        self.advance(now)
        self.overloaded = True
        self.velocity = 0.0
        self.target = self.position
        self._refresh()
