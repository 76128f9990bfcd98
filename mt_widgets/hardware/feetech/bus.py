"""The Feetech bus from the host's side: this suite's own client over pyserial.

Why our own and not the SDK's ``PacketHandler`` (``docs/user/so101.md``): the SDK keeps its
byte order in a module global set by whoever built the last ``PacketHandler``; it reports a
failure as a number and drops a servo's error byte in a sync read; and it waits 34 ms (twice a
16 ms USB latency timer, plus 2) for an answer that takes 0.1 ms at 1 Mbit/s. Here every
instruction is one method, every failure a typed exception naming the servo, and the timeout
is the caller's. The SDK still talks to the simulated arm in the tests
(``tests/hardware/test_so101_sdk.py``): the wire format is the same.

A reply lost or damaged in a read is asked for once more (a read changes nothing); writes are
never repeated.
"""

from __future__ import annotations

import time
from collections import deque

import serial

try:
    import termios
    # On POSIX a port whose device went away fails in tcflush with termios.error, not OSError.
    _PORT_ERRORS: tuple[type[BaseException], ...] = (serial.SerialException, OSError, termios.error)
except ImportError:  # Windows
    _PORT_ERRORS = (serial.SerialException, OSError)

from .control_table import BAUD
from .errors import BusDisconnected, CorruptReply, ServoNotAnswering
from .packet import BROADCAST_ID, OVERHEAD, Instruction, Packet, instruction_packet, split_packets


class FeetechBus:
    """One serial port with Feetech servos on it.

    Args:
        port: a device path (``/dev/ttyACM0``, ``COM3``) or an open ``serial.Serial``-like object.
        baudrate: the servos' baud rate (the STS3215's factory 1 000 000).
        timeout: seconds to wait for an answer before the servo counts as silent.
    """

    def __init__(self, port, baudrate: int = BAUD, timeout: float = 0.02):
        if not (isinstance(timeout, (int, float)) and not isinstance(timeout, bool) and 0 < timeout <= 10):
            raise ValueError(f"timeout: expected seconds in (0, 10], got {timeout!r}")
        if isinstance(port, str):
            if not port:
                raise ValueError("port: expected a serial device path such as '/dev/ttyACM0', got ''")
            try:
                self._serial = serial.Serial(port, baudrate=baudrate, timeout=timeout)
            except (serial.SerialException, OSError) as error:
                raise BusDisconnected(f"cannot open the serial port {port!r}: {error}. Is the arm's USB cable "
                                      f"plugged in, and is this its port?") from error
        else:
            self._serial = port
        self.port = port if isinstance(port, str) else getattr(port, "port", repr(port))
        self.timeout = float(timeout)
        self._rest = b""
        self._queue: deque[Packet] = deque()

    # ------------------------------------------------------------------ link
    def close(self) -> None:
        try:
            self._serial.close()
        except (serial.SerialException, OSError):
            pass

    @property
    def is_open(self) -> bool:
        return bool(getattr(self._serial, "is_open", False))

    def _send(self, packet: bytes) -> None:
        try:
            self._serial.reset_input_buffer()
            self._rest = b""
            self._queue.clear()
            self._serial.write(packet)
        except (*_PORT_ERRORS, TypeError, AttributeError) as error:
            raise BusDisconnected(f"the serial port {self.port!r} failed while sending: {error}. "
                                  f"Was the arm's USB cable pulled?") from error

    def _receive(self, servo_id: int, deadline: float) -> Packet:
        """The next packet from ``servo_id`` (packets of other ids are skipped)."""
        while True:
            if not self._queue:
                packets, self._rest = split_packets(self._rest)
                self._queue.extend(packets)
            if self._queue:
                packet = self._queue.popleft()
                if packet.servo_id != servo_id:
                    continue
                if not packet.valid:
                    raise CorruptReply(f"servo {servo_id}'s answer arrived damaged", servo_id=servo_id)
                return packet
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                raise ServoNotAnswering(f"servo {servo_id} did not answer within {self.timeout * 1e3:.0f} ms",
                                        servo_id=servo_id)
            try:
                self._serial.timeout = remaining
                chunk = self._serial.read(max(1, self._serial.in_waiting))
            except (*_PORT_ERRORS, TypeError, AttributeError) as error:
                raise BusDisconnected(f"the serial port {self.port!r} failed while reading: {error}. "
                                      f"Was the arm's USB cable pulled?") from error
            self._rest += chunk

    def _transact(self, servo_id: int, instruction: Instruction, parameters: bytes, retry: bool) -> Packet:
        for attempt in range(2 if retry else 1):
            self._send(instruction_packet(servo_id, instruction, parameters))
            try:
                return self._receive(servo_id, time.monotonic() + self.timeout)
            except (CorruptReply, ServoNotAnswering):
                if attempt == 1 or not retry:
                    raise
        raise AssertionError("unreachable")

    # ------------------------------------------------------------------ instructions
    def ping(self, servo_id: int) -> int:
        """PING: the servo's error byte (raises :class:`ServoNotAnswering` if it is silent)."""
        return self._transact(_check_id(servo_id), Instruction.PING, b"", retry=True).code

    def read(self, servo_id: int, address: int, size: int) -> tuple[bytes, int]:
        """READ ``size`` bytes at ``address``: (data, the servo's error byte)."""
        packet = self._transact(_check_id(servo_id), Instruction.READ, bytes((address, size)), retry=True)
        if len(packet.parameters) != size:
            raise CorruptReply(f"servo {servo_id} answered {len(packet.parameters)} bytes instead of {size}",
                               servo_id=servo_id)
        return packet.parameters, packet.code

    def write(self, servo_id: int, address: int, data: bytes) -> int:
        """WRITE ``data`` at ``address``: the servo's error byte."""
        return self._transact(_check_id(servo_id), Instruction.WRITE, bytes((address,)) + bytes(data),
                              retry=False).code

    def reg_write(self, servo_id: int, address: int, data: bytes) -> int:
        """REG_WRITE: store ``data`` for ``address`` until :meth:`action`; the servo's error byte."""
        return self._transact(_check_id(servo_id), Instruction.REG_WRITE, bytes((address,)) + bytes(data),
                              retry=False).code

    def action(self) -> None:
        """ACTION to every servo (broadcast, no answer): run the stored REG_WRITEs together."""
        self._send(instruction_packet(BROADCAST_ID, Instruction.ACTION))

    def sync_write(self, address: int, blocks: dict[int, bytes]) -> None:
        """SYNC_WRITE: one packet, ``blocks[id]`` written at ``address`` of each servo; no answer."""
        sizes = {len(block) for block in blocks.values()}
        if len(sizes) != 1:
            raise ValueError(f"blocks: expected data of one size for every servo, got sizes {sorted(sizes)}")
        size = sizes.pop()
        parameters = bytes((address, size)) + b"".join(bytes((_check_id(i),)) + bytes(b) for i, b in blocks.items())
        self._send(instruction_packet(BROADCAST_ID, Instruction.SYNC_WRITE, parameters))

    def sync_read(self, ids: list[int], address: int, size: int) -> dict[int, tuple[bytes, int]]:
        """SYNC_READ: ``size`` bytes at ``address`` of each servo in ``ids``, one packet out and
        one answer each, in order: {id: (data, error byte)}. Asked once more if an answer is
        lost or damaged."""
        ids = [_check_id(i) for i in ids]
        parameters = bytes((address, size)) + bytes(ids)
        for attempt in range(2):
            self._send(instruction_packet(BROADCAST_ID, Instruction.SYNC_READ, parameters))
            # Every answer shares one deadline: the wire time of all answers plus the timeout.
            deadline = time.monotonic() + self.timeout + len(ids) * (size + OVERHEAD) * 10.0 / BAUD
            try:
                result = {}
                for servo_id in ids:
                    packet = self._receive(servo_id, deadline)
                    if len(packet.parameters) != size:
                        raise CorruptReply(f"servo {servo_id} answered {len(packet.parameters)} bytes instead of "
                                           f"{size}", servo_id=servo_id)
                    result[servo_id] = (packet.parameters, packet.code)
                return result
            except (CorruptReply, ServoNotAnswering):
                if attempt == 1:
                    raise
        raise AssertionError("unreachable")


def _check_id(servo_id) -> int:
    if not (isinstance(servo_id, int) and not isinstance(servo_id, bool) and 0 <= servo_id < BROADCAST_ID):
        raise ValueError(f"servo_id: expected an integer 0..253, got {servo_id!r}")
    return servo_id
