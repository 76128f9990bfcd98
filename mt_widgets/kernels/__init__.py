"""Kernels that start in milliseconds: forked from a template that has imported the heavy modules.

``template`` is the process (run as ``python -m mt_widgets.kernels.template``); ``provisioner``
is the Jupyter side (a kernel provisioner and the kernel manager that uses it), used by the
study and demo pages' Voila (docs/guide/scaling.md says why the class hub does not use it).
Nothing here imports the rest of the package: the template imports what its server names.
"""

__all__ = ["ForkingKernelManager", "ForkingProvisioner", "start_template"]


def __getattr__(name: str):
    # On first use, not at import: the template (``python -m mt_widgets.kernels.template``) imports
    # this package first and must not import jupyter_server with it.
    if name in __all__:
        from . import provisioner

        return getattr(provisioner, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
