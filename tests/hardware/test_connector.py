"""The SwiftPro connector against the simulated arm: every documented behaviour and fault."""

from __future__ import annotations

import threading
import time

import pytest
import serial

import mt_widgets.hardware as hw
from mt_widgets.hardware import (
    SafetyEnvelope,
    SwiftPro,
    SwiftProBufferFull,
    SwiftProDisconnected,
    SwiftProError,
    SwiftProMotorsDetached,
    SwiftProNotFound,
    SwiftProParameterError,
    SwiftProPortBusy,
    SwiftProStopped,
    SwiftProTimeout,
    SwiftProUnknownCommand,
    SwiftProUnreachable,
    UnsafeMoveError,
)

from .helpers import device_of, sent_lines, sim_url


def moves_sent(arm):
    return [ln for ln in sent_lines(arm) if " G" in ln]


def test_both_url_spellings_open_the_simulated_arm():
    for scheme in ("uarm-sim", "uarmsim"):
        port = serial.serial_for_url(f"{scheme}://?boot=0.01", timeout=0.2)
        try:
            assert port.read_until(b"@1\n").endswith(b"@1\n")
        finally:
            port.close()


@pytest.mark.parametrize("firmware, version", [(4, (4, 10, 0)), (3, (3, 2, 0))])
def test_connect_detects_the_firmware_and_reads_the_position(firmware, version):
    with SwiftPro(sim_url(firmware=firmware)) as arm:
        assert arm.firmware_version == version
        assert arm.device_name == "SwiftPro"
        assert arm.position() == (200.0, 0.0, 100.0)
    assert not arm.connected


@pytest.mark.parametrize("firmware", [4, 3])
def test_move_to_reaches_the_target_at_the_teaching_height(firmware):
    with SwiftPro(sim_url(firmware=firmware)) as arm:
        arm.move_to(250.0, 60.0)
        x, y, z = arm.position()
        assert (x, y, z) == pytest.approx((250.0, 60.0, arm.teaching_height_mm))
        word = "G1" if firmware == 4 else "G0"
        assert moves_sent(arm)[-1].split()[1] == word


def test_replies_are_matched_by_number_with_events_interleaved():
    with SwiftPro(sim_url(chatter=0.0005, latency=0.001)) as arm:
        seen = []
        arm.on_event(seen.append)
        for _ in range(30):
            assert arm.position()[0] == pytest.approx(200.0)
            assert arm.firmware_version == (4, 10, 0)
        arm.move_to(220.0, 10.0)
        assert arm.position() == pytest.approx((220.0, 10.0, 80.0))
        assert {e.kind for e in seen} >= {"@3", "@5", "@6", "@9"}
        assert arm.next_event("@5", timeout=1.0).line == "@5 V1"


def test_position_reports_arrive_as_events_not_replies(arm4):
    arm4.set_position_reports(0.01)
    event = arm4.next_event("@3", timeout=1.0)
    assert event.values["X"] == pytest.approx(200.0)
    arm4.set_position_reports(None)
    assert arm4.position()[0] == pytest.approx(200.0)


@pytest.mark.parametrize("firmware", [4, 3])
def test_e22_is_recognised_in_both_firmware_forms(firmware):
    with SwiftPro(sim_url(firmware=firmware), timeout=0.5) as arm:
        with pytest.raises(SwiftProUnreachable) as info:
            arm._request("G0", ("X", 500), ("Y", 0), ("Z", 80), ("F", 1000))
        assert info.value.code == 22
        assert arm.position() == (200.0, 0.0, 100.0)  # still in step


def test_moving_with_motors_detached_raises_e27(arm4):
    arm4.detach()
    with pytest.raises(SwiftProMotorsDetached):
        arm4.move_to(210.0, 0.0)
    arm4.attach()
    arm4.move_to(210.0, 0.0)


def test_missing_fields_raise_e21(arm4):
    with pytest.raises(SwiftProParameterError):
        arm4._request("M2222", ("X", 200), ("Y", 0))


def test_unknown_command_raises_e20_on_4x(arm4):
    with pytest.raises(SwiftProUnknownCommand):
        arm4._request("G28")


def test_unknown_command_on_3x_times_out_then_the_link_recovers():
    with SwiftPro(sim_url(firmware=3), timeout=0.2) as arm:
        start = time.monotonic()
        with pytest.raises(SwiftProTimeout, match="Unknown command"):
            arm._request("G28")
        assert time.monotonic() - start < 0.5
        assert arm.position() == (200.0, 0.0, 100.0)


def test_the_21st_queued_command_raises_buffer_full():
    with SwiftPro(sim_url(motion_scale=1), max_in_flight=20 + 1, timeout=0.5) as arm:
        pendings = [arm._submit("G1", ("X", 201 + n), ("Y", 0), ("Z", 100), ("F", 1)) for n in range(21)]
        with pytest.raises(SwiftProBufferFull):
            arm._wait(pendings[-1], 0.5)
        arm._request("S1100")  # clear the planner
        assert arm.position()[2] == pytest.approx(100.0)


def test_a_lost_reply_times_out_and_a_late_one_is_never_taken_for_a_later_request():
    with SwiftPro(sim_url(), timeout=1.0) as arm:
        device = device_of(arm)
        device.drop_next_reply()
        with pytest.raises(SwiftProTimeout):
            arm._request("P2203", timeout=0.1)
        assert arm.position() == (200.0, 0.0, 100.0)
        # A late reply: P2220 answered 0.3 s late arrives while a 0.5 s move is pending.
        device.latency = 0.3
        with pytest.raises(SwiftProTimeout):
            arm._request("P2203", timeout=0.1)
        device.latency = 0.0
        arm.default_speed_mm_s = 100.0
        device.motion_scale = 1.0
        t0 = time.monotonic()
        arm.move_to(250.0, 0.0, 100.0, speed=100.0)  # 50 mm at 100 mm/s
        assert time.monotonic() - t0 >= 0.45  # it waited for its own reply, not the late one
        assert arm.position() == pytest.approx((250.0, 0.0, 100.0))


def test_port_closed_mid_command_raises_disconnected_without_hanging(arm4):
    device_of(arm4).disconnect_on_command()
    start = time.monotonic()
    with pytest.raises(SwiftProDisconnected):
        arm4.position()
    assert time.monotonic() - start < 0.5
    with pytest.raises(SwiftProDisconnected):
        arm4.move_to(210.0, 0.0)
    arm4.close()
    assert not arm4.connected


def test_close_wakes_a_waiting_request():
    arm = SwiftPro(sim_url(), timeout=5.0)
    arm.connect()
    device_of(arm).latency = 10.0
    errors = []

    def ask():
        try:
            arm.position()
        except SwiftProError as exc:
            errors.append(exc)

    worker = threading.Thread(target=ask)
    worker.start()
    time.sleep(0.05)
    arm.close()
    worker.join(timeout=1.0)
    assert not worker.is_alive()
    assert isinstance(errors[0], SwiftProDisconnected)
    arm.close()  # twice is fine


def test_a_port_held_by_another_program_raises_port_busy():
    with SwiftPro(sim_url(name="held")):
        with pytest.raises(SwiftProPortBusy, match="another program"):
            SwiftPro(sim_url(name="held")).connect()
    start = time.monotonic()
    with pytest.raises(SwiftProPortBusy, match="SDK issue #11"):
        SwiftPro(sim_url(busy=1), ready_timeout=1.0).connect()
    assert time.monotonic() - start < 0.5


def test_an_arm_that_never_boots_times_out():
    with pytest.raises(SwiftProTimeout, match="not ready"):
        SwiftPro(sim_url(boot=10), ready_timeout=0.3).connect()


def test_stop_cuts_a_move_short():
    with SwiftPro(sim_url(motion_scale=1), timeout=1.0) as arm:
        errors = []

        def move():
            try:
                arm.move_to(300.0, 0.0, 100.0, speed=50.0)  # 2 s
            except SwiftProError as exc:
                errors.append(exc)

        worker = threading.Thread(target=move)
        worker.start()
        time.sleep(0.3)
        arm.stop()
        worker.join(timeout=1.0)
        assert not worker.is_alive() and isinstance(errors[0], SwiftProStopped)
        x = arm.position()[0]
        assert 205.0 < x < 250.0
        arm.move_to(220.0, 0.0, 100.0, speed=100.0)
        assert arm.position()[0] == pytest.approx(220.0)


def test_beep_sends_both_fields(arm4):
    arm4.beep(440, 100)
    assert device_of(arm4).beeps == [(440.0, 100.0)]
    with pytest.raises(ValueError, match="frequency_hz"):
        arm4.beep(5, 100)


def test_a_plain_swift_is_refused():
    with pytest.raises(SwiftProError, match="Swift Pro only"):
        SwiftPro(sim_url(device="Swift")).connect()


class _FakePort:
    def __init__(self, device, vid, pid):
        self.device, self.vid, self.pid = device, vid, pid


def test_auto_detection_picks_the_swift_pro_by_usb_id_and_p2201(monkeypatch):
    ports = [_FakePort(sim_url(device="Swift"), 0x2341, 0x0042),
             _FakePort("loop://", 0x1234, 0x0001),
             _FakePort(sim_url(firmware=3), 0x2341, 0x0042)]
    monkeypatch.setattr("serial.tools.list_ports.comports", lambda: ports)
    assert SwiftPro.find_ports() == [ports[0].device, ports[2].device]
    with SwiftPro("auto") as arm:
        assert arm.port_used == ports[2].device and arm.firmware_major == 3


def test_auto_detection_without_an_arm_fails_clearly_or_uses_the_simulator(monkeypatch):
    monkeypatch.setattr("serial.tools.list_ports.comports", lambda: [])
    with pytest.raises(SwiftProNotFound, match="2341:0042"):
        SwiftPro().connect()
    monkeypatch.setattr(hw.connector, "SIMULATOR_URL", sim_url())
    with SwiftPro(simulate_if_absent=True) as arm:
        assert arm.port_used.startswith("uarm-sim://")


def test_moves_outside_the_envelope_send_nothing(arm4):
    before = moves_sent(arm4)
    for x, y, z, what in [(100, 0, 80, "radius"), (400, 0, 80, "radius"), (100, 250, 80, "yaw"),
                          (200, 0, 20, "z"), (200, 0, 200, "z"), (float("nan"), 0, 80, "x")]:
        with pytest.raises(UnsafeMoveError, match=what) as info:
            arm4.move_to(x, y, z)
        assert isinstance(info.value, ValueError) and info.value.coordinate == what
    with pytest.raises(UnsafeMoveError, match="speed"):
        arm4.move_to(210, 0, 80, speed=500)
    assert moves_sent(arm4) == before


def test_long_steps_and_paths_through_the_inner_hole_are_refused(arm4):
    arm4.move_to(107.25, 90.0)  # radius 140 mm, yaw +40 degrees
    with pytest.raises(UnsafeMoveError, match="base axis"):
        arm4.move_to(107.25, -90.0)  # 180 mm away, but the chord passes 107 mm from the base
    with pytest.raises(UnsafeMoveError, match="max_step_mm"):
        arm4.move_to(250.0, -120.0)


def test_the_arms_own_reachability_answer_is_asked_before_moving():
    wide = SafetyEnvelope(max_radius_mm=400.0, max_z_mm=180.0, max_step_mm=500.0)
    with SwiftPro(sim_url(), envelope=wide) as arm:
        with pytest.raises(UnsafeMoveError, match="M2222"):
            arm.move_to(380.0, 0.0, 100.0)
        assert any("M2222" in ln for ln in sent_lines(arm))
        assert moves_sent(arm) == []


def test_an_arm_outside_the_envelope_is_brought_in_slowly():
    with SwiftPro(sim_url(start="120,0,150")) as arm:
        with pytest.raises(UnsafeMoveError, match="entry_speed_mm_s"):
            arm.move_to(200.0, 0.0)
        arm.move_to(200.0, 0.0, speed=20.0)
        assert arm.position() == pytest.approx((200.0, 0.0, 80.0))


def test_numbers_are_sent_in_fixed_decimal_form(arm4):
    arm4.move_to(200.00001, 1e-5, 80.0)
    line = moves_sent(arm4)[-1]
    assert "e" not in line.lower().replace("#", "") and " Y0 " in line


def test_a_stop_while_the_arm_checks_reachability_means_the_move_is_never_sent():
    # The window between the reachability answer (M2222) and the move: stop() must win.
    with SwiftPro(sim_url(), timeout=1.0) as arm:
        ask_arm = arm.is_reachable

        def reachable_then_stopped(*target):
            answer = ask_arm(*target)
            arm.stop()
            return answer

        arm.is_reachable = reachable_then_stopped
        with pytest.raises(SwiftProStopped, match="not sent"):
            arm.move_to(250.0, 20.0)
        lines = sent_lines(arm)
        last_stop = max(i for i, line in enumerate(lines) if line.split()[1:2] in (["S1100"], ["S1000"], ["G2203"]))
        assert not any(line.split()[1] in ("G0", "G1") for line in lines[last_stop:])
        assert not any(line.split()[1] in ("G0", "G1") for line in lines if "X250" in line.replace(" ", ""))
        arm.is_reachable = ask_arm
        arm.move_to(250.0, 20.0)  # a new move after the stop goes through
        assert arm.position()[:2] == pytest.approx((250.0, 20.0), abs=0.01)
