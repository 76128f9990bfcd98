"""``python -m mt_widgets.cli``: the ``mt-widgets`` command."""

from .main import main

# Only when run: the documentation's API walk imports every module of the package.
if __name__ == "__main__":
    raise SystemExit(main())
