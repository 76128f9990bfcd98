"""The SO-101's calibration, in LeRobot's file format, and the servo steps <-> joint angles.

``lerobot-calibrate`` writes one JSON file per arm (under
``~/.cache/huggingface/lerobot/calibration/robots/so101_follower/<id>.json``, or
``teleoperators/so101_leader/`` for a leader arm), one object per motor, by joint name::

    {"shoulder_pan": {"id": 1, "drive_mode": 0, "homing_offset": -1470,
                      "range_min": 758, "range_max": 3292}, ...}

(LeRobot's ``MotorCalibration`` dataclass in ``lerobot/motors/motors_bus.py``). LeRobot also
writes ``homing_offset`` and the range into each servo's EEPROM, so the servo's present
position is already in the calibrated frame: ``present = raw - homing_offset``. The joint angle
is LeRobot's ``DEGREES`` normalisation (``MotorsBus._normalize``), in radians here: the middle
of the range is 0, and 4095 steps are a turn::

    angle = (present - (range_min + range_max) / 2) * 2 pi / 4095

which is how LeRobot hands an SO-101's joints to its URDF kinematics. ``drive_mode`` (0 or 1)
is kept and written back; like LeRobot's degrees it does not change the angle.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path

from .arm import SO101_IDS
from .control_table import STEPS_PER_TURN
from .errors import CalibrationError

#: The steps of LeRobot's degrees normalisation: 4095 (its ``max_res``) steps a turn.
_STEPS = STEPS_PER_TURN - 1


@dataclass(frozen=True)
class JointCalibration:
    """One motor's calibration, LeRobot's fields and meaning."""

    id: int
    drive_mode: int
    homing_offset: int
    range_min: int
    range_max: int

    @property
    def middle(self) -> float:
        return (self.range_min + self.range_max) / 2

    def to_radians(self, present: float) -> float:
        """A present position (steps) as the joint angle (rad)."""
        return (present - self.middle) * 2 * math.pi / _STEPS

    def to_steps(self, angle: float) -> int:
        """A joint angle (rad) as the nearest present position (steps)."""
        return int(round(angle * _STEPS / (2 * math.pi) + self.middle))

    @property
    def range_radians(self) -> tuple[float, float]:
        return self.to_radians(self.range_min), self.to_radians(self.range_max)


def _integer(joint: str, key: str, value, low: int, high: int) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or not low <= value <= high:
        raise CalibrationError(f"calibration: {joint}.{key}: expected an integer {low}..{high}, got {value!r}")
    return value


def calibration_from_dict(data, source: str = "calibration") -> dict[str, JointCalibration]:
    """Check LeRobot's calibration mapping and return {joint: JointCalibration}.

    Raises:
        CalibrationError: not the six SO-101 motors with their ids (another arm's file), or a
            value out of its range.
    """
    if not isinstance(data, dict):
        raise CalibrationError(f"{source}: expected a JSON object of motors, got {type(data).__name__}")
    if set(data) != set(SO101_IDS):
        raise CalibrationError(f"{source}: expected the SO-101's motors {list(SO101_IDS)}, got {sorted(data)}: "
                               f"is this the calibration of another arm?")
    result = {}
    for joint, expected_id in SO101_IDS.items():
        entry = data[joint]
        fields = {"id", "drive_mode", "homing_offset", "range_min", "range_max"}
        if not isinstance(entry, dict) or set(entry) != fields:
            raise CalibrationError(f"{source}: {joint}: expected the keys {sorted(fields)}, got "
                                   f"{sorted(entry) if isinstance(entry, dict) else entry!r}")
        if entry["id"] != expected_id:
            raise CalibrationError(f"{source}: {joint}: expected id {expected_id}, got {entry['id']!r}: "
                                   f"is this the calibration of another arm?")
        calibration = JointCalibration(
            id=expected_id,
            drive_mode=_integer(joint, "drive_mode", entry["drive_mode"], 0, 1),
            # Sign-magnitude in 11 bits on the servo (control_table.py).
            homing_offset=_integer(joint, "homing_offset", entry["homing_offset"], -2047, 2047),
            range_min=_integer(joint, "range_min", entry["range_min"], 0, STEPS_PER_TURN - 1),
            range_max=_integer(joint, "range_max", entry["range_max"], 0, STEPS_PER_TURN - 1),
        )
        if calibration.range_min >= calibration.range_max:
            raise CalibrationError(f"{source}: {joint}: expected range_min < range_max, got "
                                   f"{calibration.range_min} and {calibration.range_max}")
        result[joint] = calibration
    return result


def read_calibration(path) -> dict[str, JointCalibration]:
    """Read a LeRobot calibration file (``lerobot-calibrate``'s JSON)."""
    path = Path(path).expanduser()
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError as error:
        raise CalibrationError(f"calibration: no file {str(path)!r}: run lerobot-calibrate, or "
                               f"SO101.calibrate(), first") from error
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise CalibrationError(f"calibration: {str(path)!r} is not a JSON file: {error}") from error
    return calibration_from_dict(data, source=str(path))


def write_calibration(path, calibration: dict[str, JointCalibration]) -> Path:
    """Write ``calibration`` in LeRobot's format (so LeRobot reads it too)."""
    checked = calibration_from_dict({joint: asdict(c) for joint, c in calibration.items()})
    path = Path(path).expanduser()
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({joint: asdict(c) for joint, c in checked.items()}, indent=4) + "\n",
                    encoding="utf-8")
    return path
