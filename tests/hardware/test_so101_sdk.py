"""Feetech's own SDK (scservo_sdk: PortHandler, PacketHandler, GroupSyncRead, GroupSyncWrite, the
client LeRobot's FeetechMotorsBus is built on) reads and writes the simulated SO-101 through a
pseudo-terminal, as it would a real arm on /dev/ttyACM0."""

from __future__ import annotations

import sys
import time

import pytest
import scservo_sdk as scs

from mt_widgets.hardware.feetech.sim_bus import SimulatedBus
from mt_widgets.hardware.feetech.sim_pty import SimulatedArmPort

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")


@pytest.fixture
def sdk():
    bus = SimulatedBus(speed_scale=20.0)
    with SimulatedArmPort(bus) as server:
        port = scs.PortHandler(server.path)
        assert port.openPort()
        # The SDK allows 34 ms an answer; the simulated bus is a thread that the SDK's own busy
        # wait competes with for the CPU on a loaded test machine: 200 ms, the way LeRobot's
        # FeetechMotorsBus replaces setPacketTimeout with its own.
        port.setPacketTimeout = lambda packet_length: port.setPacketTimeoutMillis(200.0)
        yield bus, port, scs.PacketHandler(0)
        port.closePort()


def test_the_sdk_pings_reads_and_writes_the_simulated_servos(sdk):
    bus, port, handler = sdk
    for servo_id in range(1, 7):
        assert handler.ping(port, servo_id) == (777, scs.COMM_SUCCESS, 0)
    assert handler.read2ByteTxRx(port, 3, 56) == (2048, scs.COMM_SUCCESS, 0)
    assert handler.write1ByteTxRx(port, 3, 40, 1) == (scs.COMM_SUCCESS, 0)
    assert handler.write2ByteTxRx(port, 3, 42, 2300) == (scs.COMM_SUCCESS, 0)
    deadline = time.monotonic() + 2.0
    while handler.read1ByteTxRx(port, 3, 66)[0] and time.monotonic() < deadline:
        time.sleep(0.005)
    assert handler.read2ByteTxRx(port, 3, 56) == (2300, scs.COMM_SUCCESS, 0)
    assert bus.servos[3].goals == [2300]


def test_the_sdks_group_sync_write_and_read_move_and_read_all_six(sdk):
    bus, port, handler = sdk
    writer = scs.GroupSyncWrite(port, handler, 40, 1)
    for servo_id in range(1, 7):
        writer.addParam(servo_id, [1])
    assert writer.txPacket() == scs.COMM_SUCCESS
    goals = {servo_id: 1800 + 50 * servo_id for servo_id in range(1, 7)}
    writer = scs.GroupSyncWrite(port, handler, 42, 2)
    for servo_id, goal in goals.items():
        writer.addParam(servo_id, [scs.SCS_LOBYTE(goal), scs.SCS_HIBYTE(goal)])
    assert writer.txPacket() == scs.COMM_SUCCESS
    time.sleep(0.1)   # 200 steps at 20 x 3400 steps/s
    reader = scs.GroupSyncRead(port, handler, 56, 2)
    for servo_id in range(1, 7):
        reader.addParam(servo_id)
    assert reader.txRxPacket() == scs.COMM_SUCCESS
    assert {i: reader.getData(i, 56, 2) for i in range(1, 7)} == goals
    assert all(bus.servos[i].torque for i in range(1, 7))


def test_the_sdk_sees_the_eeprom_lock(sdk):
    bus, port, handler = sdk
    assert handler.write1ByteTxRx(port, 2, 55, 0) == (scs.COMM_SUCCESS, 0)
    assert handler.write2ByteTxRx(port, 2, 9, 700) == (scs.COMM_SUCCESS, 0)
    assert handler.write1ByteTxRx(port, 2, 55, 1) == (scs.COMM_SUCCESS, 0)
    with bus.lock:   # the server's thread drives the bus too
        bus.servos[2].power_on(time.monotonic())
    assert handler.read2ByteTxRx(port, 2, 9) == (700, scs.COMM_SUCCESS, 0)


def test_the_sdk_reports_the_injected_faults(sdk):
    bus, port, handler = sdk
    bus.overload(4, time.monotonic())
    assert handler.ping(port, 4) == (777, scs.COMM_SUCCESS, scs.ERRBIT_OVERLOAD)
    bus.corrupt_next_reply()
    assert handler.read2ByteTxRx(port, 1, 56)[1] == scs.COMM_RX_CORRUPT
    bus.silence(5)
    assert handler.ping(port, 5)[1] == scs.COMM_RX_TIMEOUT
    bus.voltage_drop(3.0, time.monotonic())
    assert handler.read1ByteTxRx(port, 6, 62) == (30, scs.COMM_SUCCESS, scs.ERRBIT_VOLTAGE)
