"""The Feetech packets and registers against Feetech's own SDK (scservo_sdk, the client LeRobot
uses): the bytes our packets are made of are the bytes the SDK sends, and our decoding of
sign-magnitude registers is the SDK's."""

from __future__ import annotations

import pytest
import scservo_sdk as scs

from mt_widgets.hardware.feetech.control_table import REGISTERS, decode, encode
from mt_widgets.hardware.feetech.errors import describe
from mt_widgets.hardware.feetech.packet import (
    BROADCAST_ID,
    Instruction,
    StatusError,
    checksum,
    instruction_packet,
    split_packets,
    status_packet,
)


class CapturePort:
    """Just enough of the SDK's PortHandler to keep what its PacketHandler sends."""

    def __init__(self):
        self.is_using = False
        self.sent: list[bytes] = []

    def clearPort(self):  # noqa: N802 (the SDK's name)
        pass

    def writePort(self, packet):  # noqa: N802
        self.sent.append(bytes(packet))
        return len(packet)

    def setPacketTimeout(self, length):  # noqa: N802
        pass


@pytest.fixture
def sdk():
    return scs.PacketHandler(0), CapturePort()


def test_instruction_packets_are_the_sdks_bytes(sdk):
    handler, port = sdk
    handler.writeTxOnly(port, 3, 42, 2, [0x34, 0x12])
    handler.regWriteTxOnly(port, 6, 40, 1, [1])
    handler.readTx(port, 2, 56, 2)
    port.is_using = False   # the SDK keeps the port for the answer readRx would take
    handler.syncWriteTxOnly(port, 42, 2, [1, 0x00, 0x08, 2, 0xFF, 0x0F], 6)
    handler.syncReadTx(port, 56, 2, [1, 2, 3, 4, 5, 6], 6)
    port.is_using = False
    ping = [0] * 6
    ping[scs.PKT_ID], ping[scs.PKT_LENGTH], ping[scs.PKT_INSTRUCTION] = 1, 2, scs.INST_PING
    handler.txPacket(port, ping)
    port.is_using = False
    action = [0] * 6
    action[scs.PKT_ID], action[scs.PKT_LENGTH], action[scs.PKT_INSTRUCTION] = BROADCAST_ID, 2, scs.INST_ACTION
    handler.txPacket(port, action)
    ours = [
        instruction_packet(3, Instruction.WRITE, bytes([42, 0x34, 0x12])),
        instruction_packet(6, Instruction.REG_WRITE, bytes([40, 1])),
        instruction_packet(2, Instruction.READ, bytes([56, 2])),
        instruction_packet(BROADCAST_ID, Instruction.SYNC_WRITE, bytes([42, 2, 1, 0x00, 0x08, 2, 0xFF, 0x0F])),
        instruction_packet(BROADCAST_ID, Instruction.SYNC_READ, bytes([56, 2, 1, 2, 3, 4, 5, 6])),
        instruction_packet(1, Instruction.PING),
        instruction_packet(BROADCAST_ID, Instruction.ACTION),
    ]
    assert port.sent == ours
    # A hand-checked one: FF FF 01 02 01 ~(1+2+1)=0xFB.
    assert instruction_packet(1, Instruction.PING) == bytes([0xFF, 0xFF, 0x01, 0x02, 0x01, 0xFB])


def test_the_instruction_codes_and_error_bits_are_the_sdks():
    assert (Instruction.PING, Instruction.READ, Instruction.WRITE, Instruction.REG_WRITE, Instruction.ACTION,
            Instruction.SYNC_READ, Instruction.SYNC_WRITE) == (
        scs.INST_PING, scs.INST_READ, scs.INST_WRITE, scs.INST_REG_WRITE, scs.INST_ACTION, scs.INST_SYNC_READ,
        scs.INST_SYNC_WRITE)
    assert (StatusError.VOLTAGE, StatusError.SENSOR, StatusError.OVERHEAT, StatusError.OVERCURRENT,
            StatusError.OVERLOAD) == (scs.ERRBIT_VOLTAGE, scs.ERRBIT_ANGLE, scs.ERRBIT_OVERHEAT, scs.ERRBIT_OVERELE,
                                      scs.ERRBIT_OVERLOAD)


def test_split_packets_resynchronises_and_flags_a_bad_checksum():
    good = status_packet(4, 0x20, bytes([0x10, 0x08]))
    bad = bytearray(status_packet(5, 0, bytes([1])))
    bad[-1] ^= 0xFF
    stream = b"\x00\x13" + good + bytes(bad) + good[:5]
    packets, rest = split_packets(stream)
    assert [(p.servo_id, p.code, p.parameters, p.valid) for p in packets] == [
        (4, 0x20, bytes([0x10, 0x08]), True), (5, 0, bytes([1]), False)]
    assert rest == good[:5]
    assert split_packets(rest + good[5:])[0][0].valid
    assert checksum(bytes([4, 4, 0x20, 0x10, 0x08])) == good[-1]


@pytest.mark.parametrize("name, bit", [("homing_offset", 11), ("goal_speed", 15), ("present_speed", 15)])
@pytest.mark.parametrize("value", [0, 1, -1, 300, -2047 + 1, 2047])
def test_sign_magnitude_registers_decode_as_the_sdk_does(name, bit, value):
    register = REGISTERS[name]
    data = encode(register, value)
    raw = int.from_bytes(data, "little")
    assert raw == scs.SCS_TOSCS(value, bit)
    assert decode(register, data) == scs.SCS_TOHOST(raw, bit) == value


def test_register_values_out_of_range_are_refused_with_the_registers_name():
    with pytest.raises(ValueError, match="goal_position"):
        encode(REGISTERS["goal_position"], 70000)
    with pytest.raises(ValueError, match="homing_offset"):
        encode(REGISTERS["homing_offset"], 2048)
    with pytest.raises(ValueError, match="servo_id"):
        instruction_packet(255, Instruction.PING)


def test_status_errors_are_described_in_words():
    assert "too hot" in describe(StatusError.OVERHEAT)
    text = describe(StatusError.VOLTAGE | StatusError.OVERLOAD)
    assert "power supply" in text and "blocked" in text
    assert describe(0x40) == "it reported an unknown error (bits 0x40)"
