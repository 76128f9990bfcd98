"""The simulated uArm Swift Pro's EEPROM: M2211 reads it, M2212 writes it.

One store of 64 KiB per device number, blank (0xFF) at first, kept across a power cycle;
values are stored little-endian as the AVR does: a byte (T1), a signed 16-bit integer (T2)
or a float (T4). 4.x reads fixed patterns and accepts only device 1; 3.x reads Marlin's
letters anywhere in the arguments. A mixin of
:class:`~mt_widgets.hardware.simdevice.SimulatedSwiftPro`.
"""

from __future__ import annotations

import struct

from .sim_grammar import grbl_read_float, marlin_float, marlin_int, scan4, scan_pattern

#: EEPROM size the simulated store has per device (4.x accepts addresses up to 65524).
EEPROM_BYTES = 65536


class Eeprom:
    """The EEPROM's store and its two commands, in both dialects."""

    def _eeprom_of(self, device: int) -> bytearray:
        return self._eeprom.setdefault(device, bytearray(b"\xff" * EEPROM_BYTES))

    def _eeprom_read(self, device, addr, kind):
        mem = self._eeprom_of(device)
        size = {1: 1, 2: 2, 4: 4}[kind]
        raw = bytes(mem[(addr + i) % EEPROM_BYTES] for i in range(size))
        if kind == 1:
            return raw[0]
        if kind == 2:
            return struct.unpack("<h", raw)[0]
        return struct.unpack("<f", raw)[0]

    def _eeprom_write(self, device, addr, kind, value):
        mem = self._eeprom_of(device)
        if kind == 1:
            raw = bytes([int(value) & 0xFF])
        elif kind == 2:
            raw = struct.pack("<h", max(-32768, min(32767, int(value))))
        else:
            raw = struct.pack("<f", float(value))
        for i, b in enumerate(raw):
            mem[(addr + i) % EEPROM_BYTES] = b

    def _m2211(self, cmd, t):
        if self.firmware == 4:
            fields = scan4(scan_pattern("N d A d T d"), cmd.args)
            if len(fields) < 3:
                self._r4(cmd, t, 21)
                return
            device, addr, kind = (int(v) for v in fields)
            if device != 1 or not 0 <= addr <= 65524 or kind not in (1, 2, 4):
                self._r4(cmd, t, 21)  # 4.x reads only device 1 (the SDK's N0 gets E21)
                return
            v = self._eeprom_read(device, addr, kind)
            if kind == 1:
                v = v - 256 if v > 127 else v  # printed through (char): signed
            text = self._num(v) if kind == 4 else str(int(v))
            self._r4(cmd, t, 0, f" V{text}")
            return
        if not all(self._seen(cmd, c) for c in "NAT"):
            self._r3(cmd, t, 21)
            return
        device = marlin_int(self._after(cmd, "N"))
        addr = marlin_int(self._after(cmd, "A")) & 0xFFFF
        kind = marlin_int(self._after(cmd, "T"))
        if kind not in (1, 2, 4):
            self._r3(cmd, t, 0, "")  # no case matches: "ok" and an empty buffer
            return
        v = self._eeprom_read(device, addr, kind)
        self._r3(cmd, t, 0, f"V{self._num(v) if kind == 4 else int(v)}")

    def _m2212(self, cmd, t):
        if self.firmware == 4:
            fields = scan4(scan_pattern("N d A d T d V u"), cmd.args)
            value = grbl_read_float(fields[3]) if len(fields) == 4 else None
            if len(fields) < 4 or value is None:
                self._r4(cmd, t, 21)  # includes negative values: the pattern has no sign
                return
            device, addr, kind = (int(v) for v in fields[:3])
            if device != 1 or not 0 <= addr <= 65524 or kind not in (1, 2, 4):
                self._r4(cmd, t, 21)
                return
            self._eeprom_write(device, addr, kind, value)
            self._r4(cmd, t)
            return
        if all(self._seen(cmd, c) for c in "NATV"):
            kind = marlin_int(self._after(cmd, "T"))
            if kind in (1, 2, 4):
                self._eeprom_write(marlin_int(self._after(cmd, "N")), marlin_int(self._after(cmd, "A")) & 0xFFFF,
                                   kind, marlin_float(self._after(cmd, "V")))
        self._r3_ok(cmd, t)
