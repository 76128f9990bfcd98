"""Robot models read from their URDFs: the files are read here, ``core`` gets plain data.

``urdf`` reads a URDF (a shipped arm's, in ``urdf_files/``, or a user's file) into the
description ``mt_widgets.core.serial_chain.SerialChain`` builds its chain from. This subpackage
imports nothing of the package, and core imports nothing of it: ``mt_widgets.arms`` joins the two.
"""

from .urdf import (
    EXAMPLE_ROBOT_DATA,
    SHIPPED,
    URDFError,
    example_robot_data_urdf,
    load_shipped,
    parse_urdf,
    read_urdf,
    shipped_urdf,
)

# pinocchio_reference (the tests' and the benchmark's independent stepper) is left out: it needs
# pinocchio, which only the test and bench extras install.
__all__ = ["EXAMPLE_ROBOT_DATA", "SHIPPED", "URDFError", "example_robot_data_urdf", "load_shipped", "parse_urdf",
           "read_urdf", "shipped_urdf"]
