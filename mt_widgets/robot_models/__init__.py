"""Robot models read from their URDFs, outside the science: the files are read here, ``core`` gets data.

``urdf`` reads a URDF (example-robot-data's UR5) into the literals ``mt_widgets.core`` builds a
serial chain from, and regenerates ``mt_widgets/core/ur5_description.py``.
"""
