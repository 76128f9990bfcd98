"""Kernels that start in milliseconds: forked from a template that has imported the heavy modules.

``template`` is the process (run as ``python -m mt_widgets.kernels.template``); ``provisioner``
is the Jupyter side (a kernel provisioner and the kernel manager that uses it), used by the
study and demo pages' Voila (docs/guide/scaling.md says why the class hub does not use it).
Nothing here imports the rest of the package: the template imports what its server names. The
template process imports the provisioner's Jupyter modules with this package; the study pages'
template preloads Voila's server side anyway (deploy/voila/voila.py).
"""

from .provisioner import ForkingKernelManager, ForkingProvisioner, start_template

__all__ = ["ForkingKernelManager", "ForkingProvisioner", "start_template"]
