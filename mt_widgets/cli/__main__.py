"""``python -m mt_widgets.cli``: the ``mt-widgets`` command."""

from .main import main

raise SystemExit(main())
