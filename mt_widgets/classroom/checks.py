"""Visible checks for exercises: they say in words what is wrong, and record the attempt.

A check compares a student's answer with what the library computes and, when they differ,
raises ``CheckFailed`` (an ``AssertionError``, so nbgrader counts the test cell as failed)
whose message names the answer, says what was expected and what came, and adds the
exercise's hint. Each run is recorded by a ``ProgressRecorder`` (nothing is written without a
class folder), so the instructor's view sees which check a student is stuck on.

Example (a test cell of an assignment)::

    checks = ExerciseChecks("a1_ridge_learner")
    checks.close("fit-shape", "theta_hat", theta_hat, RidgeLearner(0.01).fit(Phi, U),
                 hint="Theta_hat^T = (Phi^T Phi + lam I)^-1 Phi^T U: did you transpose at the end?")
"""

from __future__ import annotations

import numbers

import numpy as np

from .progress import ProgressRecorder


class CheckFailed(AssertionError):
    """An exercise's check that did not pass; the message says why in words."""


def _describe(value) -> str:
    if isinstance(value, np.ndarray):
        return f"an array of shape {value.shape}"
    if value is None:
        return "None (not answered yet, or a function that does not return its result)"
    return f"{type(value).__name__} {value!r}"[:100]


class ExerciseChecks:
    """The checks of one exercise notebook.

    Args:
        exercise: the exercise's name (the nbgrader assignment, e.g. "a1_ridge_learner").
        recorder: where attempts are recorded; default a ``ProgressRecorder()`` that follows
            ``MT_WIDGETS_CLASS_FOLDER`` (disabled when it is unset).
    """

    def __init__(self, exercise: str, recorder: ProgressRecorder | None = None):
        if not isinstance(exercise, str) or not exercise:
            raise ValueError(f"exercise: expected a non-empty name, got {exercise!r}")
        if recorder is not None and not isinstance(recorder, ProgressRecorder):
            raise TypeError(f"recorder: expected a ProgressRecorder or None, got {type(recorder).__name__}")
        self.exercise = exercise
        self.recorder = recorder if recorder is not None else ProgressRecorder()
        self.recorder.lesson(exercise)

    def _result(self, check: str, message: str | None) -> None:
        self.recorder.check(self.exercise, check, message is None, message)
        if message is not None:
            raise CheckFailed(message)
        print(f"\u2713 {check}: passed")

    def true(self, check: str, condition: bool, message: str) -> None:
        """Passes when ``condition`` is true; else fails with ``message``."""
        self._result(check, None if bool(condition) else message)

    def call(self, check: str, function, *args):
        """Calls the student's ``function(*args)`` and returns its result; an exception fails the check.

        A function still raising ``NotImplementedError`` (nbgrader's placeholder) is reported as
        not written yet; any other error by its type and message.
        """
        name = getattr(function, "__name__", "the function")
        if not callable(function):
            self._result(check, f"{name}: expected a function, got {_describe(function)}.")
        try:
            return function(*args)
        except NotImplementedError:
            self._result(check, f"{name}: not written yet (its body still raises NotImplementedError); "
                                f"replace the placeholder in its cell with your code and run that cell.")
        except Exception as error:  # noqa: BLE001 - any error in a student's code becomes words
            self._result(check, f"{name}: raised {type(error).__name__}: {error}.")

    def close(self, check: str, name: str, value, expected, *, atol: float = 1e-8, rtol: float = 1e-6,
              hint: str = "") -> None:
        """Passes when ``value`` has ``expected``'s shape and equals it within the tolerances.

        Args:
            check: the check's name (as recorded).
            name: the answer's name, as the student wrote it.
            value: the student's answer.
            expected: the right answer, computed with the library.
            atol, rtol: tolerances as for ``numpy.allclose``.
            hint: one sentence on the usual cause of a wrong answer.
        """
        self._result(check, self._compare(name, value, expected, atol, rtol, hint))

    @staticmethod
    def _compare(name, value, expected, atol, rtol, hint) -> str | None:
        expected = np.asarray(expected, dtype=float)
        suffix = f" {hint}" if hint else ""
        if isinstance(value, bool) or value is None or not isinstance(value, (numbers.Real, np.ndarray, list,
                                                                             tuple, np.generic)):
            return f"{name}: expected numbers of shape {expected.shape}, got {_describe(value)}.{suffix}"
        try:
            got = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            return f"{name}: expected numbers of shape {expected.shape}, got {_describe(value)}.{suffix}"
        if got.shape != expected.shape:
            return f"{name}: expected shape {expected.shape}, got shape {got.shape}.{suffix}"
        if not np.all(np.isfinite(got)):
            return f"{name}: expected finite numbers, got NaN or infinity.{suffix}"
        if np.allclose(got, expected, atol=atol, rtol=rtol):
            return None
        worst = np.unravel_index(np.argmax(np.abs(got - expected)), got.shape) if got.ndim else ()
        where = f" at index {tuple(int(i) for i in worst)}" if got.ndim else ""
        return (f"{name}: expected {float(expected[worst]):.6g}{where}, got {float(got[worst]):.6g} "
                f"(largest difference {float(np.max(np.abs(got - expected))):.3g}).{suffix}")
