"""Robot models read from their URDFs, outside the science: the files are read here, ``core`` gets data.

``urdf`` reads a URDF (example-robot-data's UR5) into the literals ``mt_widgets.core`` builds a
serial chain from, and regenerates ``mt_widgets/core/ur5_description.py``.
"""

from .urdf import description_module, example_robot_data_urdf, generate, read_serial_chain

# pinocchio_reference (the tests' and the benchmark's independent stepper) is left out: it needs
# pinocchio, which only the test and bench extras install.
__all__ = ["description_module", "example_robot_data_urdf", "generate", "read_serial_chain"]
