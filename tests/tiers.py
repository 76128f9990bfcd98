"""The test suite's tiers: which tests a tier runs, in the order ``./scripts/run-tests.sh`` runs them.

A tier is a pytest marker expression over five marks, set by tests/conftest.py (``mark_tiers``):

- ``lint``: tests/test_lint.py (ruff over the tree);
- ``browser``: a test that drives Chromium (it takes the ``browser`` fixture, lives in a folder named
  ``browser*``, or carries ``@pytest.mark.browser``);
- ``notebook``: a notebook cell run by nbval;
- ``hub``: a test that starts a JupyterHub or loads its config as root (tests/course/test_hub.py, test_hub_config.py);
- ``slow``: a test that takes seconds, marked ``@pytest.mark.slow`` where it is written;
- ``docs``: tests/docs/test_docs_build.py, which builds the documentation site with Sphinx (and opens
  built pages in Chromium, offline: it looks at this tier's build rather than building again).
- ``install``: a test that builds the wheel and installs it into fresh venvs (tests/install/test_shapes.py),
  or runs the getting-started pages in such a venv (tests/install/test_getting_started_from_wheel.py).

Beside them, ``OTHER_PYTHONS``: the fast tier again on the oldest and the newest supported Python,
each in its own venv (``.venv-py3XX`` in the repository, ignored by git, kept between runs).

Every test belongs to exactly one tier (tests/test_fast_tier.py checks it over every combination
of marks). The cheap tiers come first, so a lint error or a broken core stops the run in a minute
or two instead of after every browser test.

``python tests/tiers.py`` prints the tiers, one ``name<TAB>expression[<TAB>path...]`` a line, for
scripts/run-tests.sh; ``python tests/tiers.py fast`` one tier's expression, for scripts/test-fast.sh.
This module imports nothing from pytest: the scripts read it before any test runs.
"""

from __future__ import annotations

#: The marks tests/conftest.py sets; a tier selects by these only.
MARKS = ("lint", "browser", "notebook", "hub", "slow", "docs", "install")

#: The files whose tests are ``lint``, and ``hub``, as paths from the repository's root.
LINT_TESTS = ("tests/test_lint.py",)
# test_hub_config.py makes system users and needs the students' Python of scripts/install-hub.sh,
# which run-tests.sh prepares only after the cheap tiers.
HUB_TESTS = ("tests/course/test_hub.py", "tests/course/test_hub_config.py", "tests/course/test_server_template.py",
             "tests/course/test_hub_lti.py")
# The documentation site's build (./scripts/build-docs.sh, about a minute): a tier of its own, after
# the cheap ones and before the browser, which it does not need.
DOCS_TESTS = ("tests/docs/test_docs_build.py",)
INSTALL_TESTS = ("tests/install/test_shapes.py", "tests/install/test_getting_started_from_wheel.py")

#: (name, marker expression), in the order they run. ``fast`` is what scripts/test-fast.sh runs
#: after ``lint``: the edit loop's tiers.
TIERS = (
    ("lint", "lint"),
    ("fast", "not lint and not browser and not notebook and not hub and not slow and not docs and not install"),
    ("slow", "slow and not lint and not browser and not notebook and not hub and not docs and not install"),
    ("docs", "docs and not lint and not browser and not notebook and not hub and not install"),
    ("install", "install and not lint"),
    ("browser", "browser and not lint and not notebook and not hub and not install"),
    ("notebook", "notebook and not lint and not hub and not install"),
    ("hub", "hub and not lint and not install"),
)

#: (name, Python version): the fast tier run again with these Pythons, the oldest and the newest that
#: pyproject.toml's classifiers list (the shared venv is 3.11). scripts/run-tests.sh runs them right
#: after the fast tier, all at once, each with scripts/python-venv.sh's venv of its Python.
OTHER_PYTHONS = (("fast-py3.10", "3.10"), ("fast-py3.13", "3.13"))


def tier_expression(name: str) -> str:
    """The marker expression of the tier ``name`` (one of ``TIERS``)."""
    for tier, expression in TIERS:
        if tier == name:
            return expression
    raise ValueError(f"name: expected one of {[tier for tier, _ in TIERS]}, got {name!r}")


def tier_paths(name: str) -> tuple[str, ...]:
    """Where the tier ``name``'s tests are, when its mark is given by files (``lint``, ``hub``, ``docs``): the
    run collects only those (seconds instead of the whole suite's minute); () for the whole suite."""
    tier_expression(name)
    return {"lint": LINT_TESTS, "hub": HUB_TESTS, "docs": DOCS_TESTS, "install": INSTALL_TESTS}.get(name, ())


if __name__ == "__main__":
    import sys

    if len(sys.argv) > 1:  # one tier's expression
        print(tier_expression(sys.argv[1]))
    else:
        for tier, expression in TIERS:
            print("\t".join([tier, expression, *tier_paths(tier)]))
            if tier == "fast":
                for other, _ in OTHER_PYTHONS:
                    print("\t".join([other, expression]))
