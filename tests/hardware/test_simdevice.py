"""The simulated arm (device model, no serial) behaves as docs/uarm-protocol.md's last section says."""

from __future__ import annotations

import math

import pytest

from mt_widgets.hardware.simdevice import SimulatedSwiftPro, is_reachable


def booted(firmware: int = 4, **kwargs) -> tuple[SimulatedSwiftPro, float]:
    dev = SimulatedSwiftPro(firmware=firmware, boot_delay=0.5, **kwargs)
    dev.power_on(0.0)
    dev.read_available(1.0)  # banner
    return dev, 1.0


def lines(dev: SimulatedSwiftPro, now: float) -> list[str]:
    return [ln.rstrip("\r") for ln in dev.read_available(now).decode().split("\n") if ln.strip()]


def test_boot_drops_early_input_then_sends_banner_and_ready_on_4x():
    dev = SimulatedSwiftPro(firmware=4, boot_delay=0.5)
    dev.power_on(0.0)
    dev.write(b"#1 P2220\n", 0.1)
    assert dev.read_available(0.4) == b""
    out = lines(dev, 0.6)
    assert out[0] == "device name : SwiftPro" and out[-1] == "@1"
    assert not any(ln.startswith("$1") for ln in out)  # the early request was lost


def test_3x_banner_has_no_ready_line_and_ends_lines_with_crlf():
    dev = SimulatedSwiftPro(firmware=3, boot_delay=0.1)
    dev.power_on(0.0)
    raw = dev.read_available(0.2)
    assert b"start\r\n" in raw and b"@1" not in raw


def test_replies_carry_the_request_number_and_position_reads_fixed_decimals():
    dev, t = booted()
    dev.write(b"#42 P2220\n#7 P2203\n", t)
    assert lines(dev, t) == ["$42 ok X200.0000 Y0.0000 Z100.0000", "$7 ok V4.10.0"]


def test_4x_move_replies_when_done_and_position_query_overtakes_it():
    dev, t = booted()
    dev.write(b"#1 G1 X250 Y0 Z100 F50\n", t)  # 50 mm at 50 mm/s: 1 s
    dev.write(b"#2 P2220\n", t + 0.5)
    out = lines(dev, t + 0.5)
    assert out == ["$2 ok X225.0000 Y0.0000 Z100.0000"]  # halfway, the move not answered yet
    assert lines(dev, t + 1.01) == ["$1 ok"]


def test_3x_answers_a_move_when_queued_and_reports_moving_with_m2200():
    dev, t = booted(3)
    dev.write(b"#1 G0 X250 Y0 Z100 F3000\n", t)  # F in mm/min: 50 mm/s
    assert lines(dev, t) == ["$1 ok "]  # Marlin prints "ok ", then the (empty) reply buffer
    dev.write(b"#2 M2200\n", t + 0.5)
    assert lines(dev, t + 0.5) == ["$2 ok V1"]
    dev.write(b"#3 M2200\n", t + 1.1)
    assert lines(dev, t + 1.1) == ["$3 ok V0"]


@pytest.mark.parametrize("firmware, expected", [(4, "$5 E22"), (3, "$5 ok E22 unreachable")])
def test_unreachable_move_gives_e22_in_each_firmware_form(firmware, expected):
    dev, t = booted(firmware)
    dev.write(b"#5 G0 X500 Y0 Z100 F1000\n", t)
    assert lines(dev, t + 0.01) == [expected]


def test_move_with_motors_detached_gives_e27_on_4x():
    dev, t = booted()
    dev.write(b"#1 M2019\n#2 G0 X210 Y0 Z100 F100\n", t)
    assert lines(dev, t) == ["$1 ok", "$2 E27"]


@pytest.mark.parametrize("line, answer", [
    (b"#3 G0 X1e-05 Y0 Z100 F100\n", "$3 E20"),    # grbl reads X1, then E-05 is an unsupported word
    (b"#3 M2222 X200 Y0 Z100\n", "$3 E21"),         # the fixed pattern wants P too
    (b"#3 M2222 X2e2 Y0 Z100 P0\n", "$3 E21"),      # %[0-9-+.] stops at the E
    (b"#3 G0 X2.0.1\n", "$3"),                      # grbl: expected a letter, reported with nothing
    (b"#3 G1 X210 Y0 Z100\n", "$3"),                # G1 with no feed rate ever: likewise
])
def test_4x_number_grammar_and_missing_fields(line, answer):
    dev, t = booted()
    dev.write(line, t)
    assert lines(dev, t) == [answer]


def test_3x_number_grammar_is_marlins_strtod():
    dev, t = booted(3)
    dev.write(b"#3 G0 X200 Y1e-05 Z100 F6000\n", t)  # strtod takes the exponent
    assert lines(dev, t) == ["$3 ok "]
    dev.write(b"#4 M2222 X2e2 Y0 Z100\n#5 M2222 X200 Y0\n", t)
    assert lines(dev, t) == ["$4 ok V1", "$5 E21 "]


def test_unknown_command_gives_e20_on_4x_and_an_echo_without_reply_on_3x():
    dev4, t = booted(4)
    dev4.write(b"#9 M2999\n", t)
    assert lines(dev4, t) == ["$9 E20"]
    dev3, t = booted(3)
    dev3.write(b"#9 M2999\n", t)
    out = lines(dev3, t)
    assert len(out) == 1 and out[0].startswith("echo:Unknown command") and "$9" not in out[0]


def test_the_21st_pending_command_gets_a_bare_e23():
    dev, t = booted()
    for n in range(1, 22):
        dev.write(f"#{n} G1 X{200 + n} Y0 Z100 F1\n".encode(), t)
    out = lines(dev, t)
    assert out == ["E23 buffer full"]


def test_real_time_characters_are_swallowed_by_4x():
    dev, t = booted()
    dev.write(b"#1 P22?20\n", t)
    assert bytes(dev.realtime_received) == b"?"
    assert lines(dev, t) == ["$1 ok X200.0000 Y0.0000 Z100.0000"]


def test_position_reports_and_chatter_are_interleaved_unsolicited_lines():
    dev, t = booted(chatter=0.01)
    dev.write(b"#1 M2120 V0.05\n", t)
    out = lines(dev, t + 0.2)
    assert "$1 ok" in out
    assert sum(ln.startswith("@3") for ln in out) >= 4
    assert {ln.split()[0] for ln in out if ln.startswith("@")} >= {"@3", "@5", "@6"}


def test_dropped_reply_and_disconnect_faults():
    dev, t = booted()
    dev.drop_next_reply()
    dev.write(b"#1 P2220\n#2 P2220\n", t)
    assert [ln.split()[0] for ln in lines(dev, t)] == ["$2"]
    dev.disconnect_on_command()
    dev.write(b"#3 P2220\n", t)
    assert dev.disconnected and lines(dev, t) == []


def test_latency_delays_every_line():
    dev, t = booted(latency=0.003)
    dev.write(b"#1 P2203\n", t)
    assert dev.read_available(t + 0.002) == b""
    assert lines(dev, t + 0.0031) == ["$1 ok V4.10.0"]


@pytest.mark.parametrize("z, lo, hi", [(0, 87, 359), (50, 105, 360), (100, 124, 353), (150, 134, 322)])
def test_reach_follows_the_docs_4x_table(z, lo, hi):
    reach = [s for s in range(0, 420) if is_reachable(s, 0.0, z)]
    assert abs(reach[0] - lo) <= 1.5 and abs(reach[-1] - hi) <= 1.5


def test_nothing_reachable_from_z190_or_behind_the_base():
    assert not any(is_reachable(s, 0.0, 190.0) for s in range(0, 420))
    assert not is_reachable(-200.0, 0.0, 80.0)
    assert not is_reachable(math.nan, 0.0, 80.0)


def test_before_4_5_stop_is_a_pause_and_resume_carries_the_cut_move_on_before_anything_queued():
    dev, t = booted(version="4.2")
    dev.write(b"#1 P2203\n#2 S1100\n", t)
    assert lines(dev, t) == ["$1 ok V4.2.0", "$2 E20"]  # no planner clear before 4.5
    dev.write(b"#3 G1 X250 Y0 Z100 F50\n", t)  # 1 s
    dev.write(b"#4 S1000 V0\n", t + 0.5)
    assert lines(dev, t + 0.5) == ["$4 ok"]
    dev.write(b"#5 G1 X200 Y50 Z100 F50\n#6 M2222 X200 Y0 Z100 P0\n#7 P2220\n", t + 0.6)
    assert lines(dev, t + 5.0) == ["$7 ok X225.0000 Y0.0000 Z100.0000"]  # paused: G/M queue unanswered
    dev.write(b"#8 S1000 V1\n", t + 5.0)
    assert lines(dev, t + 5.0) == ["$8 ok"]
    assert dev.position_at(t + 5.25) == pytest.approx((237.5, 0.0, 100.0))  # the cut move goes on
    assert lines(dev, t + 5.51) == ["$3 ok"]
    assert dev.position_at(t + 5.51)[0] < 250.0 and dev.moving_at(t + 5.51)  # then the queued one
    out = lines(dev, t + 7.0)
    assert out == ["$5 ok", "$6 ok V1"] and dev.position_at(t + 7.0) == pytest.approx((200.0, 50.0, 100.0))


def test_firmware_version_option_must_match_the_generation():
    assert SimulatedSwiftPro(firmware=3, version="3.1").version_tuple == (3, 1, 0)
    with pytest.raises(ValueError, match="version"):
        SimulatedSwiftPro(firmware=4, version="3.2")
