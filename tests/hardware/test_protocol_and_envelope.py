"""Line building and parsing, and the safety envelope's defaults and checks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mt_widgets.hardware import (
    TEACHING_HEIGHT_MM,
    TEACHING_MAX_YAW_DEG,
    TEACHING_RADIUS_MM,
    SafetyEnvelope,
    UnsafeMoveError,
    is_reachable,
)
from mt_widgets.hardware.protocol import Event, Reply, build_request, check_line, classify_line, format_number


@pytest.mark.parametrize("value, text", [(1e-5, "0"), (0.00016, "0.0002"), (180, "180"), (-12.5, "-12.5"),
                                         (-0.00001, "0"), (123456.78901, "123456.789")])
def test_numbers_are_written_in_fixed_decimal_form(value, text):
    assert format_number(value) == text


@pytest.mark.parametrize("bad", [math.nan, math.inf, 1e7, "abc"])
def test_non_finite_or_huge_numbers_are_refused_naming_the_parameter(bad):
    with pytest.raises(ValueError, match="speed"):
        format_number(bad, name="speed")


def test_request_lines_are_numbered_and_checked():
    assert build_request(25, "G0", ("X", 180), ("Y", 0), ("Z", 150), ("F", 5000)) == "#25 G0 X180 Y0 Z150 F5000"
    for bad in ["#1 P2220?", "#1 M2210 F1 T1 @", "#1 P2220\x18", "#1 G0 " + "X1 " * 30]:
        with pytest.raises(ValueError):
            check_line(bad)
    with pytest.raises(ValueError, match="command"):
        build_request(1, "G0\n#2 G0")


def test_replies_are_parsed_in_both_firmware_forms():
    assert classify_line("$25 ok\r\n") == Reply(25, True, None, "", "$25 ok")
    assert classify_line("$7 ok X200.0000 Y0.0000 Z80.0000").payload == "X200.0000 Y0.0000 Z80.0000"
    four, three = classify_line("$5 E22"), classify_line("$5 ok E22 unreachable")
    assert (four.ok, four.error_code) == (False, 22) and (three.ok, three.error_code) == (False, 22)


def test_unsolicited_lines_are_events():
    assert classify_line("@3 X200 Y1.5 Z80 R90") == Event("@3", "@3 X200 Y1.5 Z80 R90",
                                                          {"X": 200.0, "Y": 1.5, "Z": 80.0, "R": 90.0})
    assert classify_line("E23 buffer full").error_code == 23
    assert classify_line('echo:Unknown command: "G28"').kind == "echo"
    assert classify_line("device name : SwiftPro").kind == "info"
    assert classify_line("\r\n") is None


def test_the_default_envelope_contains_the_teaching_workspace_at_the_teaching_height():
    env = SafetyEnvelope()
    assert env.contains_teaching_workspace(TEACHING_HEIGHT_MM)
    assert env.min_z_mm < TEACHING_HEIGHT_MM < env.max_z_mm
    # ...and a smaller envelope would not: the check can fail.
    assert not SafetyEnvelope(max_yaw_deg=55).contains_teaching_workspace()
    assert not SafetyEnvelope(min_radius_mm=145).contains_teaching_workspace()


def test_the_simulated_arm_reaches_every_point_of_the_default_envelope():
    env = SafetyEnvelope()
    for z in (env.min_z_mm, TEACHING_HEIGHT_MM, env.max_z_mm):
        for i in range(21):
            r = env.min_radius_mm + (env.max_radius_mm - env.min_radius_mm) * i / 20
            for j in range(21):
                yaw = math.radians(-env.max_yaw_deg + 2 * env.max_yaw_deg * j / 20)
                assert is_reachable(r * math.cos(yaw), r * math.sin(yaw), z), (r, yaw, z)


def test_teaching_workspace_constants_match_the_plant():
    assert TEACHING_RADIUS_MM == (140.0, 300.0) and TEACHING_MAX_YAW_DEG == 60.0


@pytest.mark.parametrize("point, coordinate", [((200, 0, 20), "z"), ((200, 0, 130), "z"), ((120, 0, 80), "radius"),
                                               ((320, 0, 80), "radius"), ((100, 250, 80), "yaw"),
                                               ((200, math.inf, 80), "y")])
def test_points_outside_raise_unsafe_move_naming_coordinate_and_limit(point, coordinate):
    with pytest.raises(UnsafeMoveError) as info:
        SafetyEnvelope().check_point(*point)
    assert info.value.coordinate == coordinate and coordinate in str(info.value)


def test_envelope_parameters_are_validated():
    with pytest.raises(ValueError, match="min_radius_mm"):
        SafetyEnvelope(min_radius_mm=400)
    with pytest.raises(ValueError, match="max_yaw_deg"):
        SafetyEnvelope(max_yaw_deg=120)


def test_envelope_checks_take_numpy_numbers_and_refuse_bools_naming_argument_range_and_value():
    env = SafetyEnvelope()
    assert env.check_point(np.float32(200.0), np.int64(0), np.float32(80.0)) == (200.0, 0.0, 80.0)
    assert env.check_speed(np.float32(50.0)) == 50.0
    with pytest.raises(UnsafeMoveError, match=r"x: expected a finite real number of mm.*got True \(bool\)") as info:
        env.check_point(True, 0.0, 80.0)
    assert info.value.coordinate == "x"
    with pytest.raises(UnsafeMoveError, match=r"z: expected .*got '80'"):
        env.check_point(200.0, 0.0, "80")
    with pytest.raises(UnsafeMoveError, match=r"speed: expected .*\[1\.0, 20\.0\], got True"):
        env.check_speed(True, entering=True)
    with pytest.raises(UnsafeMoveError, match=r"z = 20\.000 mm .*z must be in \[40\.0, 120\.0\] mm"):
        env.check_point(200.0, 0.0, 20.0)
    with pytest.raises(ValueError, match=r"max_step_mm: expected a finite real number .*got True"):
        SafetyEnvelope(max_step_mm=True)
    assert SafetyEnvelope(max_step_mm=np.float32(150.0)).max_step_mm == 150.0


def test_a_move_into_the_envelope_may_never_take_the_arm_further_out():
    env = SafetyEnvelope()
    start = (120.0, 0.0, 150.0)  # in the hole round the base, above the band
    env.check_entering_segment(start, (145.0, 0.0, 150.0))  # out of the hole along its yaw
    env.check_entering_segment(start, (120.0, 0.0, 110.0))  # down into the band
    for end, coordinate in [((110.0, 0.0, 150.0), "radius"), ((145.0, 0.0, 160.0), "z"),
                            ((120.0, 0.0, 30.0), "z"), ((60.0, 150.0, 150.0), "yaw"),
                            ((310.0, 0.0, 40.0), "step")]:
        with pytest.raises(UnsafeMoveError) as info:
            env.check_entering_segment(start, end)
        assert info.value.coordinate == coordinate, (end, info.value)
    # Both ends at 120 mm, yaw -30 and +30 degrees: the chord passes 104 mm from the axis.
    a = math.radians(30.0)
    with pytest.raises(UnsafeMoveError, match="base axis"):
        env.check_entering_segment((120 * math.cos(a), -120 * math.sin(a), 80.0),
                                   (120 * math.cos(a), 120 * math.sin(a), 80.0))


@pytest.mark.parametrize("start", [(120.0, 0.0, 150.0), (60.0, -40.0, 10.0), (340.0, 50.0, 60.0),
                                   (150.0, 200.0, 30.0), (200.0, 0.0, 100.0)])
def test_the_entry_path_is_checked_leg_by_leg_and_ends_at_the_target(start):
    env = SafetyEnvelope()
    target = (200.0, 30.0, 80.0)
    legs = env.entry_path(start, target, 40.0)
    np.testing.assert_allclose(legs[-1], target)
    here = start
    for leg in legs:
        assert math.dist(here, leg) <= 40.0 + 1e-9
        if env.contains(*here):
            env.check_segment(here, leg)
        else:
            env.check_entering_segment(here, leg)
        here = leg
    if start[2] < env.min_z_mm:
        assert legs[0][:2] == pytest.approx(start[:2])  # lifted before anything else
