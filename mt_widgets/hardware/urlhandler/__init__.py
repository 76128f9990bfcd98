"""pyserial URL handlers of mt_widgets (``uarm-sim://``); registered by :mod:`mt_widgets.hardware`."""
