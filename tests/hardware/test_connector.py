"""The SwiftPro connector against the simulated arm: every documented behaviour and fault."""

from __future__ import annotations

import math
import threading
import time

import numpy as np
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

from .helpers import arm_is_moving, device_of, sent_lines, sim_url, wait_until


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
        assert time.monotonic() - start < 3.0  # the 0.2 s timeout, not a hang
        assert arm.position() == (200.0, 0.0, 100.0)


def test_the_21st_queued_command_raises_buffer_full():
    with SwiftPro(sim_url(motion_scale=1), max_in_flight=20 + 1, timeout=0.5) as arm:
        pendings = [arm._link.submit("G1", ("X", 201 + n), ("Y", 0), ("Z", 100), ("F", 1)) for n in range(21)]
        with pytest.raises(SwiftProBufferFull):
            arm._link.wait(pendings[-1], 0.5)
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
    assert time.monotonic() - start < 3.0  # woken by the failure, not by the 1 s timeout or a hang
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

    asked = len(sent_lines(arm))
    worker = threading.Thread(target=ask)
    worker.start()
    wait_until(lambda: len(sent_lines(arm)) > asked, what="the request to reach the arm")
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
        SwiftPro(sim_url(busy=1), ready_timeout=10.0).connect()
    assert time.monotonic() - start < 5.0  # told at once, not after the 10 s ready_timeout


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
        wait_until(lambda: arm_is_moving(arm), what="the move to start")
        arm.stop()
        worker.join(timeout=5.0)
        assert not worker.is_alive() and isinstance(errors[0], SwiftProStopped)
        x = arm.position()[0]
        assert 200.0 < x < 299.0  # under way, then cut short
        assert device_of(arm).position_at(time.monotonic() + 0.1)[0] == pytest.approx(x)  # and it stays
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


def _closest_to_axis(p, q):
    """Nearest horizontal distance to the base axis along the straight path p -> q (mm)."""
    d = np.subtract(q[:2], p[:2])
    t = 0.0 if not d.any() else float(np.clip(-np.dot(p[:2], d) / np.dot(d, d), 0.0, 1.0))
    return float(np.hypot(*(np.asarray(p[:2]) + t * d)))


def _sent_moves(lines):
    """(x, y, z, F) of every G0/G1 line, in order."""
    out = []
    for line in lines:
        words = line.split()
        if len(words) > 1 and words[1] in ("G0", "G1"):
            fields = {w[0]: float(w[1:]) for w in words[2:]}
            out.append((fields["X"], fields["Y"], fields["Z"], fields["F"]))
    return out


def test_an_arm_outside_the_envelope_is_never_moved_by_move_to_only_brought_in_by_home():
    with SwiftPro(sim_url(start="120,0,150")) as arm:
        for speed in (20.0, 50.0):
            with pytest.raises(UnsafeMoveError, match=r"outside the safety envelope.*home\(\)"):
                arm.move_to(200.0, 0.0, speed=speed)
        assert moves_sent(arm) == []
        legs = arm.home()
        assert arm.position() == pytest.approx((200.0, 0.0, arm.teaching_height_mm))
        sent = _sent_moves(sent_lines(arm))
        np.testing.assert_allclose([m[:3] for m in sent], legs, atol=1e-4)
        previous = (120.0, 0.0, 150.0)
        for x, y, z, feed in sent:
            assert feed <= arm.envelope.entry_speed_mm_s
            assert math.dist(previous, (x, y, z)) <= 40.0 + 1e-6
            # never further out than it started: not nearer the base (anywhere along the
            # chord), not higher than 150 mm
            assert _closest_to_axis(previous, (x, y, z)) >= 120.0 - 1e-3 and z <= 150.0
            previous = (x, y, z)
        arm.move_to(250.0, 30.0)  # inside now: ordinary moves go
        assert arm.position()[:2] == pytest.approx((250.0, 30.0))


def test_an_entering_move_is_never_sent_straight_through_the_hole_round_the_base():
    # Power-up below the height band at yaw -40 degrees; the target at +40 degrees: the
    # straight chord passes 115 mm from the base axis, inside min_radius_mm = 135.
    a = math.radians(40.0)
    start, target = (150 * math.cos(a), -150 * math.sin(a), 20.0), (150 * math.cos(a), 150 * math.sin(a), 80.0)
    with SwiftPro(sim_url(start=",".join(f"{v:.4f}" for v in start))) as arm:
        with pytest.raises(UnsafeMoveError, match="home"):
            arm.move_to(*target, speed=20.0)
        assert moves_sent(arm) == []
        arm.home(*target)
        assert arm.position() == pytest.approx(target, abs=1e-3)
        sent = _sent_moves(sent_lines(arm))
        assert sent[0][:2] == pytest.approx(start[:2], abs=1e-3) and sent[0][2] > 40.0  # lifted first
        path = [start] + [m[:3] for m in sent]
        assert min(_closest_to_axis(p, q) for p, q in zip(path, path[1:])) >= 135.0 - 1e-3


def test_home_is_cut_by_stop_like_any_move():
    with SwiftPro(sim_url(start="120,0,150"), timeout=1.0) as arm:
        generation = arm.stop_generation
        arm.stop()
        with pytest.raises(SwiftProStopped):
            arm.home(unless_stopped_since=generation)
        assert moves_sent(arm) == []


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
        last_stop = max(i for i, line in enumerate(lines) if line.split()[1:2] in (["S1100"], ["S1000"], ["M2000"]))
        assert not any(line.split()[1] in ("G0", "G1") for line in lines[last_stop:])
        assert not any(line.split()[1] in ("G0", "G1") for line in lines if "X250" in line.replace(" ", ""))
        arm.is_reachable = ask_arm
        arm.move_to(250.0, 20.0)  # a new move after the stop goes through
        assert arm.position()[:2] == pytest.approx((250.0, 20.0), abs=0.01)


# ----------------------------------------------------------------------------- stop always wins
def _move_in_thread(arm, *target, speed):
    errors = []

    def move():
        try:
            arm.move_to(*target, speed=speed)
        except SwiftProError as exc:
            errors.append(exc)

    worker = threading.Thread(target=move)
    worker.start()
    wait_until(lambda: arm_is_moving(arm), what="the move to start")
    return worker, errors


def test_stop_does_not_wait_for_a_request_slot():
    # Both in-flight slots taken: the move, and a position poll whose reply is lost.
    with SwiftPro(sim_url(motion_scale=1), timeout=1.0) as arm:
        worker, errors = _move_in_thread(arm, 300.0, 0.0, 100.0, speed=50.0)  # 2 s
        device_of(arm).drop_next_reply()
        arm._link.submit("P2220")
        arm.stop()  # must neither wait for a slot nor raise
        worker.join(timeout=5.0)
        assert not worker.is_alive() and isinstance(errors[0], SwiftProStopped)
        assert not arm_is_moving(arm)


def test_a_move_begun_before_a_stop_is_refused_even_if_its_checks_start_after_it():
    with SwiftPro(sim_url(), timeout=1.0) as arm:
        generation = arm.stop_generation  # a job starts
        arm.stop()
        assert arm.stop_generation == generation + 1
        before = len(sent_lines(arm))
        with pytest.raises(SwiftProStopped, match="stop"):
            arm.move_to(250.0, 0.0, unless_stopped_since=generation)
        assert sent_lines(arm)[before:] == []  # not even the M2222 question
        arm.move_to(250.0, 0.0, unless_stopped_since=arm.stop_generation)
        assert arm.position()[:2] == pytest.approx((250.0, 0.0))
        with pytest.raises(ValueError, match="unless_stopped_since"):
            arm.move_to(250.0, 0.0, unless_stopped_since=arm.stop_generation + 1)
        with pytest.raises(AttributeError):
            arm.stop_generation = 0


def test_on_firmware_4_2_stop_pauses_and_resume_ends_the_cut_move_before_any_new_one():
    # 4.0-4.4 has no S1100: stop is S1000 V0, a pause; the cut move waits at the head of the
    # firmware's queue and every G/M command queues behind it (docs/uarm-protocol.md, "Commands").
    with SwiftPro(sim_url(version="4.2", motion_scale=1), timeout=1.0) as arm:
        assert arm.firmware_version == (4, 2, 0)
        worker, errors = _move_in_thread(arm, 300.0, 0.0, 100.0, speed=50.0)  # 2 s
        arm.stop()
        worker.join(timeout=5.0)
        assert isinstance(errors[0], SwiftProStopped) and arm.paused
        assert any(line.endswith("S1000 V0") for line in sent_lines(arm))
        held = arm.position()
        assert held[0] < 299.0
        with pytest.raises(SwiftProStopped, match="resume"):
            arm.move_to(250.0, 0.0, 100.0)  # would hang behind the paused move: refused at once
        arm.resume()
        assert not arm.paused and any(line.endswith("S1000 V1") for line in sent_lines(arm))
        # The cut move is over before resume returns: it cannot run after the new moves.
        assert not arm_is_moving(arm)
        assert arm.position() == pytest.approx((300.0, 0.0, 100.0))
        arm.move_to(250.0, 0.0, 100.0, speed=100.0)
        wait_until(lambda: not arm_is_moving(arm), what="the move to end")
        assert arm.position() == pytest.approx((250.0, 0.0, 100.0)) and not arm_is_moving(arm)


def test_a_stop_just_as_resume_un_pauses_the_arm_wins():
    with SwiftPro(sim_url(version="4.2", motion_scale=1), timeout=1.0) as arm:
        worker, errors = _move_in_thread(arm, 300.0, 0.0, 100.0, speed=50.0)
        arm.stop()
        worker.join(timeout=5.0)
        submit = arm._link.submit

        def stop_first(command, *params, **options):
            if command == "S1000" and params == (("V", 1),):
                arm.stop()  # Stop pressed just before the un-pause goes out
            return submit(command, *params, **options)

        arm._link.submit = stop_first
        with pytest.raises(SwiftProStopped):
            arm.resume()
        arm._link.submit = submit
        lines = sent_lines(arm)
        last_pause = max(i for i, line in enumerate(lines) if line.endswith("S1000 V0"))
        assert not any(line.endswith("S1000 V1") for line in lines[last_pause:])
        assert arm.paused and not arm_is_moving(arm)
        arm.resume()  # a later resume still works
        assert arm.position() == pytest.approx((300.0, 0.0, 100.0)) and not arm.paused


def test_resume_does_nothing_where_stop_is_no_pause(arm3):
    arm3.stop()
    arm3.resume()  # 3.x: no S1000 (it would time out as an unknown command)
    assert not any("S1000" in line for line in sent_lines(arm3))
    arm3.move_to(210.0, 0.0)


# ----------------------------------------------------------------------------- reconnecting
def test_reconnecting_after_a_link_failure_closes_the_old_port_first():
    arm = SwiftPro(sim_url(name="reconnect"), timeout=1.0)  # an exclusive port, as a real one
    arm.connect()
    try:
        old_port, old_reader = arm._link.serial, arm._link.reader
        device_of(arm).disconnect_on_command()
        with pytest.raises(SwiftProDisconnected):
            arm.position()
        assert not arm.connected
        arm.connect()  # the old port, still open, would make this SwiftProPortBusy
        assert arm.connected and arm.position() == (200.0, 0.0, 100.0)
        assert not old_port.is_open and not old_reader.is_alive() and arm._link.serial is not old_port
    finally:
        arm.close()


# ----------------------------------------------------------------------------- argument checks
def test_arguments_take_any_real_number_but_not_a_bool():
    with pytest.raises(TypeError, match=r"timeout: expected a real number, got bool True"):
        SwiftPro(sim_url(), timeout=True)
    with pytest.raises(TypeError, match=r"max_in_flight: expected a whole number, got bool True"):
        SwiftPro(sim_url(), max_in_flight=True)
    with SwiftPro(sim_url(), timeout=np.float32(1.0), max_in_flight=np.int64(2)) as arm:
        arm.move_to(np.float32(210.0), np.float64(5.0), np.int32(80), speed=np.float32(50.0))
        assert arm.position() == pytest.approx((210.0, 5.0, 80.0))
        arm.beep(np.float32(440.0), np.int64(50))
        arm.set_position_reports(np.float32(0.5))
        with pytest.raises(UnsafeMoveError, match=r"x: expected a finite real number of mm.*got True \(bool\)"):
            arm.move_to(True, 0.0)
        with pytest.raises(UnsafeMoveError, match=r"speed: expected .* in \[1\.0, 100\.0\], got False"):
            arm.move_to(210.0, 0.0, speed=False)
        with pytest.raises(ValueError, match="frequency_hz"):
            arm.beep(True, 100)
        with pytest.raises(ValueError, match="interval_s"):
            arm.set_position_reports(True)
