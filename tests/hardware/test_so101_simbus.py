"""The simulated SO-101 bus in process (no serial port): the servos' control table, EEPROM lock,
limits, motion, wire timing at 1 Mbit/s and the faults tests inject."""

from __future__ import annotations

import numpy as np
import pytest

from mt_widgets.hardware.feetech.control_table import REGISTERS, encode
from mt_widgets.hardware.feetech.packet import (
    BROADCAST_ID,
    Instruction,
    StatusError,
    instruction_packet,
    split_packets,
)
from mt_widgets.hardware.feetech.sim_bus import BYTE_TIME, SimulatedBus


def write(servo_id: int, name: str, value: int) -> bytes:
    register = REGISTERS[name]
    return instruction_packet(servo_id, Instruction.WRITE, bytes([register.address]) + encode(register, value))


def answers(bus: SimulatedBus, now: float):
    return split_packets(bus.read_available(now))[0]


def test_a_sync_read_is_answered_in_id_order_with_the_wire_time_of_every_byte():
    bus = SimulatedBus()
    for servo in bus.servos.values():
        servo.write(REGISTERS["return_delay"].address, bytes([0]), 0.0)
    request = instruction_packet(BROADCAST_ID, Instruction.SYNC_READ, bytes([56, 2, 1, 2, 3, 4, 5, 6]))
    bus.write(request, 1.0)
    # 14 bytes in, then six answers of 8 bytes one after the other on the one wire.
    assert len(request) == 14
    assert bus.next_due(1.0) == pytest.approx(1.0 + (14 + 8) * BYTE_TIME)
    last = 1.0 + (14 + 6 * 8) * BYTE_TIME
    assert len(answers(bus, last - 1e-7)) == 5
    (packet,) = answers(bus, last + 1e-9)
    assert packet.servo_id == 6 and packet.parameters == (2048).to_bytes(2, "little") and packet.valid
    assert BYTE_TIME == pytest.approx(10e-6)


def test_the_factory_return_delay_of_500_us_comes_before_each_answer():
    bus = SimulatedBus()
    bus.write(instruction_packet(3, Instruction.PING), 0.0)
    assert bus.next_due(0.0) == pytest.approx(6 * BYTE_TIME + 250 * 2e-6 + 6 * BYTE_TIME)


def test_eeprom_writes_are_kept_only_with_the_lock_open():
    bus = SimulatedBus()
    servo = bus.servos[2]
    bus.write(write(2, "min_position_limit", 1000), 0.0)      # lock = 1 (power-on): not saved
    assert servo.value("min_position_limit") == 1000
    servo.power_on(0.1)
    assert servo.value("min_position_limit") == 0
    bus.write(write(2, "lock", 0) + write(2, "min_position_limit", 1100) + write(2, "lock", 1), 0.2)
    servo.power_on(0.3)
    assert servo.value("min_position_limit") == 1100
    # Read-only registers ignore writes.
    bus.write(write(2, "lock", 0) + instruction_packet(2, Instruction.WRITE, bytes([3, 1, 0])), 0.4)
    assert servo.value("model_number") == 777


def test_goals_are_clamped_to_the_position_limits_and_the_moving_flag_follows_the_shaft():
    bus = SimulatedBus(speed_scale=1.0)
    servo = bus.servos[1]
    servo.flash("max_position_limit", 2500)
    bus.write(write(1, "torque_enable", 1) + write(1, "goal_speed", 1000) + write(1, "goal_position", 3000), 0.0)
    assert servo.goals_written == [3000] and servo.goals == [2500]
    assert servo.value("moving") == 1
    servo.advance(0.2)   # 452 steps at 1000 steps/s with the largest acceleration: a bit under 0.46 s
    assert 2048 < servo.value("present_position") < 2500 and servo.value("moving") == 1
    assert servo.value("present_speed") == 1000
    servo.advance(1.0)
    assert servo.value("present_position") == 2500 and servo.value("moving") == 0


def test_homing_offset_shifts_the_present_position():
    bus = SimulatedBus()
    servo = bus.servos[4]
    servo.flash("homing_offset", -300)
    assert servo.value("present_position") == 2048 + 300
    servo.flash("homing_offset", 2047)
    assert servo.value("present_position") == 1


def test_reg_write_waits_for_action():
    bus = SimulatedBus()
    bus.write(instruction_packet(5, Instruction.REG_WRITE, bytes([40, 1])), 0.0)
    assert not bus.servos[5].torque
    bus.write(instruction_packet(BROADCAST_ID, Instruction.ACTION), 0.001)
    assert bus.servos[5].torque


def test_a_hand_moves_only_a_servo_without_torque():
    bus = SimulatedBus()
    assert bus.hand_move({1: 1000, 2: 3000}, 0.0)
    assert bus.present_positions(0.0)[1] == 1000
    bus.write(write(1, "torque_enable", 1), 0.1)
    assert not bus.hand_move({1: 1500}, 0.2)
    assert bus.present_positions(0.2)[1] == 1000


def test_faults_silence_corrupt_overload_voltage_and_cable():
    bus = SimulatedBus()
    bus.silence(3)
    bus.write(instruction_packet(3, Instruction.PING), 0.0)
    assert bus.next_due(0.0) is None
    bus.corrupt_next_reply()
    bus.write(instruction_packet(2, Instruction.PING), 0.0)
    (packet,) = answers(bus, 1.0)
    assert not packet.valid
    bus.write(write(1, "torque_enable", 1) + write(1, "goal_position", 3000), 1.0)
    bus.overload(1, 1.01)
    bus.write(instruction_packet(1, Instruction.PING), 1.02)
    assert answers(bus, 2.0)[-1].code == StatusError.OVERLOAD
    assert bus.servos[1].value("moving") == 0
    bus.write(write(1, "torque_enable", 1), 2.0)           # torque on again clears the overload
    assert bus.servos[1].error == 0
    bus.voltage_drop(3.5, 2.1)
    bus.write(instruction_packet(6, Instruction.READ, bytes([62, 1])), 2.1)
    packet = answers(bus, 3.0)[-1]
    assert packet.servo_id == 6 and packet.code == StatusError.VOLTAGE and packet.parameters == bytes([35])
    bus.pull_cable()
    bus.write(instruction_packet(6, Instruction.PING), 3.0)
    assert bus.disconnected and bus.read_available(4.0) == b""


def test_a_host_packet_with_a_wrong_checksum_is_ignored():
    bus = SimulatedBus()
    damaged = bytearray(write(2, "torque_enable", 1))
    damaged[-1] ^= 0x01
    bus.write(bytes(damaged), 0.0)
    assert not bus.servos[2].torque and bus.next_due(0.0) is None and bus.received == []
    bus.write(write(2, "torque_enable", 1), 0.1)   # the next good packet is read (resynchronised)
    assert bus.servos[2].torque


def test_servos_with_speed_and_acceleration_in_proportion_to_their_travel_arrive_together():
    bus = SimulatedBus()
    one, two = bus.servos[1], bus.servos[2]
    for servo, speed, acceleration, goal in ((one, 2000, 40, 2048 + 800), (two, 500, 10, 2048 - 200)):
        bus.write(write(servo.servo_id, "torque_enable", 1) + write(servo.servo_id, "acceleration", acceleration)
                  + write(servo.servo_id, "goal_speed", speed) + write(servo.servo_id, "goal_position", goal), 0.0)
    for t in np.linspace(0.01, 1.0, 40):   # a triangle of 0.89 s at 4000 steps/s^2
        bus.present_positions(t)
        a = (one.position - 2048) / 800
        b = (2048 - two.position) / 200
        assert a == pytest.approx(b, abs=0.02), t
    assert one.value("present_position") == 2848 and two.value("present_position") == 1848
