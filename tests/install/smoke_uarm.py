"""The uarm shape (``pip install "mt-widgets[uarm]"``): the simulated Swift Pro through pyserial's URL
handler, connected, homed and moved as a real arm would be."""

from mt_widgets.hardware import SwiftPro
from mt_widgets.hardware.bridge import FAST_SIMULATOR_URL

arm = SwiftPro(FAST_SIMULATOR_URL)
arm.connect()
try:
    assert arm.firmware_major == 4, arm.firmware_major
    arm.home()
    arm.move_to(250.0, 0.0, 100.0, speed=100.0)  # returns once the arm reports the move done
    x, y, z = arm.position()
finally:
    arm.close()
assert abs(x - 250.0) < 0.5 and abs(y) < 0.5 and abs(z - 100.0) < 0.5, (x, y, z)
print(f"uarm: at ({x:.1f}, {y:.1f}, {z:.1f}) mm")
