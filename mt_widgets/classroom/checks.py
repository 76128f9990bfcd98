"""Checks for exercises: they say in words what is wrong, never the expected number, and record the attempt.

A check compares a student's answer with what the library computes and, when they differ,
raises ``CheckFailed`` (an ``AssertionError``, so nbgrader counts the test cell as failed)
whose message names the answer and says what is wrong and in which direction (its shape, a
transpose, the sign, too large or too small, a constant factor) without printing the
expected value, so a failure message cannot be pasted back as the answer. The exercise's
hint follows, also when the student's function raised. Each run is recorded by a
``ProgressRecorder`` (nothing is written without a class folder), so the instructor's view
sees which check a student is stuck on.

Grading a function, not a number: ``function`` calls the student's function on a list of
cases (the visible one in a visible test cell; other seeds, shapes and lam, including 0 and
rank-deficient features, in nbgrader's hidden tests) and compares each result with a
reference from ``mt_widgets.classroom.references``. Where an exercise says "by hand"
(``by_hand=True``), a function that uses anything of this package (its learner, its optimal
actions, its analysis) fails: its code's names are read, through the student's own helper
functions, and the call runs with every package object in the student's namespace replaced
by one that raises. ``consistent`` grades a value by what the student's own functions give,
so a wrong function does not cost its value twice, and a pasted number with no function
earns nothing.

Example (a test cell of an assignment)::

    checks = ExerciseChecks("a1_ridge_learner")
    checks.function("ridge-fit", ridge_fit, [("Phi, U_novice, lam", (Phi, U_novice, lam))],
                    references.ridge_fit, by_hand=True, hint="transpose at the end")
"""

from __future__ import annotations

import numbers
import types
from collections.abc import Callable, Iterable

import numpy as np

from .progress import ProgressRecorder

#: The package whose objects a "by hand" answer may not use.
PACKAGE = "mt_widgets"


class CheckFailed(AssertionError):
    """An exercise's check that did not pass; the message says why in words."""


class PackageUsedByHand(RuntimeError):
    """Raised by a package object a "by hand" answer called (it stands in for the object during the check)."""


def _describe(value) -> str:
    if isinstance(value, np.ndarray):
        return f"an array of shape {value.shape}"
    if value is None:
        return "None (not answered yet, or a function that does not return its result)"
    return f"a {type(value).__name__}"


#: The part of the package no answer may use: the checks and their references.
CLASSROOM = PACKAGE + ".classroom"


def _in(name, prefix: str) -> bool:
    return isinstance(name, str) and (name == prefix or name.startswith(prefix + "."))


def _is_package_object(value, prefix: str = PACKAGE) -> bool:
    if isinstance(value, types.ModuleType):
        return _in(value.__name__, prefix)
    if isinstance(value, (int, float, str, bool, np.ndarray, np.generic)) or value is None:
        return False
    module = getattr(value, "__module__", None) or getattr(type(value), "__module__", "")
    return _in(module, prefix)


def _code_names(code: types.CodeType) -> set[str]:
    names = set(code.co_names)
    for constant in code.co_consts:
        if isinstance(constant, types.CodeType):
            names |= _code_names(constant)
        elif isinstance(constant, str) and _in(constant.split(".")[0], PACKAGE):
            names.add(PACKAGE)          # __import__("mt_widgets...") or importlib
    return names


def package_names_used(function, prefix: str = PACKAGE, skip: set[str] = frozenset()) -> list[str]:
    """The names of this package's objects (under ``prefix``) that ``function`` refers to.

    Reads the function's code (nested functions and lambdas included) and looks each global
    name up in the function's own namespace; a student's function it calls is read in turn.
    ``import mt_widgets`` (or a string naming the package) inside the function counts too.
    """
    found, seen, todo = set(), set(), [function]
    while todo:
        current = todo.pop()
        code = getattr(current, "__code__", None)
        if code is None or id(code) in seen:
            continue
        seen.add(id(code))
        namespace = dict(getattr(current, "__globals__", {}))
        for free, cell in zip(code.co_freevars, getattr(current, "__closure__", None) or ()):
            try:
                namespace[free] = cell.cell_contents        # a name the function closes over
            except ValueError:                              # an empty cell
                continue
        for name in _code_names(code) | set(code.co_freevars):
            if name == PACKAGE and name not in namespace and prefix == PACKAGE:
                found.add(name)
                continue
            if name not in namespace or name in skip:
                continue
            value = namespace[name]
            if _is_package_object(value, prefix):
                found.add(name)
            elif isinstance(value, types.FunctionType) and not _is_package_object(value):
                todo.append(value)
    return sorted(found)


class _PackageDisabled:
    """While active, every package object in a namespace raises ``PackageUsedByHand`` when used."""

    def __init__(self, namespace: dict, prefix: str = PACKAGE, substitute: dict | None = None):
        self.namespace = namespace
        self.prefix = prefix
        self.substitute = substitute or {}
        self.saved: dict[str, object] = {}
        self.missing: list[str] = []

    def __enter__(self):
        for name, value in self.substitute.items():
            if name in self.namespace:
                self.saved[name] = self.namespace[name]
            else:
                self.missing.append(name)
            self.namespace[name] = value
        for name, value in list(self.namespace.items()):
            if name in self.substitute:
                continue
            if not name.startswith("__") and _is_package_object(value, self.prefix) \
                    and not isinstance(value, ExerciseChecks):
                self.saved[name] = value
                self.namespace[name] = _Raiser(name)
        return self

    def __exit__(self, *exc):
        self.namespace.update(self.saved)
        for name in self.missing:
            self.namespace.pop(name, None)
        return False


class _Raiser:
    def __init__(self, name: str):
        self._name = name

    def _fail(self, *args, **kwargs):
        raise PackageUsedByHand(f"uses the package's {self._name}")

    __call__ = _fail

    def __getattr__(self, attribute):
        if attribute.startswith("__"):
            raise AttributeError(attribute)
        self._fail()


def _direction(got: np.ndarray, expected: np.ndarray) -> str:
    """What is wrong with ``got`` against ``expected`` (same shape), in words and without the expected numbers."""
    if got.ndim == 2 and got.shape[0] == got.shape[1] and np.allclose(got.T, expected, rtol=1e-6, atol=1e-9) \
            and not np.allclose(got, expected, rtol=1e-6, atol=1e-9):
        return "it is the transpose of the right answer"
    if np.allclose(-got, expected, rtol=1e-6, atol=1e-9) and np.any(np.abs(expected) > 1e-12):
        return "it has the wrong sign"
    flat_got, flat_expected = got.ravel(), expected.ravel()
    scale = float(flat_expected @ flat_expected)
    if scale > 0 and got.size > 1:
        factor = float(flat_got @ flat_expected) / scale
        if abs(factor - 1) > 1e-6 and np.allclose(got, factor * expected, rtol=1e-6, atol=1e-9):
            return f"it is the right answer times a constant factor (too {'large' if abs(factor) > 1 else 'small'})"
    difference = got - expected
    worst = np.unravel_index(int(np.argmax(np.abs(difference))), got.shape) if got.ndim else ()
    where = f" (the largest error is at index {tuple(int(i) for i in worst)})" if got.ndim else ""
    if got.ndim == 0 or got.size == 1:
        g, e = float(got.ravel()[0]), float(expected.ravel()[0])
        if np.sign(g) != np.sign(e) and e != 0 and g != 0:
            return "it has the wrong sign"
        return "it is too large" if g > e else "it is too small"
    too_large = difference[worst] > 0
    if np.all(difference >= -1e-12) or np.all(difference <= 1e-12):
        return f"its entries are all too {'large' if too_large else 'small'} or right{where}"
    return f"some entries are too large and some too small{where}"


def _as_numbers(value):
    if isinstance(value, bool) or value is None or not isinstance(value, (numbers.Real, np.ndarray, list, tuple,
                                                                           np.generic)):
        return None
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None


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

    def call(self, check: str, function, *args, hint: str = "", by_hand: bool = False,
             substitute: dict | None = None):
        """Calls the student's ``function(*args)`` and returns its result; an exception fails the check.

        A function still raising ``NotImplementedError`` (nbgrader's placeholder) is reported as
        not written yet; any other error by its type and message, followed by ``hint``. With
        ``by_hand`` a function using this package fails; without, one using the checks or their
        references (``mt_widgets.classroom``) does (see the module's docstring). ``substitute``
        ({name: function}) puts the reference in place of the student's other functions for this
        call, so a function is graded on its own and not through an earlier answer's mistake.
        """
        name = getattr(function, "__name__", "the function")
        suffix = f" {hint}" if hint else ""
        if not callable(function):
            self._result(check, f"{name}: expected a function, got {_describe(function)}.{suffix}")
        substitute = dict(substitute or {})
        prefix = PACKAGE if by_hand else CLASSROOM
        used = package_names_used(function, prefix, skip=set(substitute))
        if used:
            what = "by hand (numpy only)" if by_hand else "with your own code"
            self._result(check, f"{name}: uses the package's {', '.join(used)}; this exercise asks for it {what}, "
                                f"so it earns nothing.")
        namespace = getattr(function, "__globals__", None)
        try:
            if isinstance(namespace, dict):
                with _PackageDisabled(namespace, prefix, substitute):
                    return function(*args)
            return function(*args)
        except NotImplementedError:
            self._result(check, f"{name}: not written yet (its body still raises NotImplementedError); "
                                f"replace the placeholder in its cell with your code and run that cell.")
        except PackageUsedByHand as error:
            what = "by hand (numpy only)" if by_hand else "with your own code"
            self._result(check, f"{name}: {error}; this exercise asks for it {what}, so it earns nothing.")
        except Exception as error:  # noqa: BLE001 - any error in a student's code becomes words
            self._result(check, f"{name}: raised {type(error).__name__}: {error}.{suffix}")

    def close(self, check: str, name: str, value, expected, *, atol: float = 1e-8, rtol: float = 1e-6,
              hint: str = "") -> None:
        """Passes when ``value`` has ``expected``'s shape and equals it within the tolerances.

        Args:
            check: the check's name (as recorded).
            name: the answer's name, as the student wrote it.
            value: the student's answer.
            expected: the right answer, computed with the library (never shown).
            atol, rtol: tolerances as for ``numpy.allclose``.
            hint: one sentence on the usual cause of a wrong answer.
        """
        self._result(check, self._compare(name, value, expected, atol, rtol, hint))

    def function(self, check: str, function, cases: Iterable[tuple[str, tuple]], reference: Callable, *,
                 by_hand: bool = False, substitute: dict | None = None, convert: tuple | None = None,
                 atol: float = 1e-8, rtol: float = 1e-6, hint: str = "") -> None:
        """Calls the student's ``function`` on each case and compares it with ``reference`` on the same arguments.

        Args:
            check: the check's name.
            function: the student's function.
            cases: (label, arguments) pairs; the label says which input failed ("a 7 x 4 Phi, lam = 0").
            reference: the library's answer for the same arguments.
            by_hand: whether using this package inside ``function`` fails the check.
            substitute: the references to use in place of the student's other functions.
            convert: (function, what it expects) turning the student's result into numbers (a pandas
                Series sorted by its index, say); a result it cannot convert fails as "expected <what>".
        """
        name = getattr(function, "__name__", "the function")
        for label, args in cases:
            got = self.call(check, function, *args, hint=hint, by_hand=by_hand, substitute=substitute)
            if convert is not None:
                to_numbers, expected_kind = convert
                try:
                    got = to_numbers(got)
                except Exception:  # noqa: BLE001 - the result is not of the kind asked for
                    self._result(check, f"{name}({label}): expected {expected_kind}, got {_describe(got)}.")
            self.close(check, f"{name}({label})", got, reference(*args), atol=atol, rtol=rtol, hint=hint)

    def consistent(self, check: str, name: str, value, functions: dict, compute: Callable, *,
                   by_hand: bool = False, atol: float = 1e-8, rtol: float = 1e-6, hint: str = "") -> None:
        """Passes when ``value`` is what the student's own ``functions`` give: ``compute(**results)``.

        ``functions`` maps a name to ``(student's function, *its arguments)`` on the exercise's
        inputs; each must run (a placeholder fails the check), so a
        number pasted without its functions earns nothing, and a wrong function is graded once,
        by its own check, not again through every value built on it.
        """
        results = {key: self.call(check, function, *args, hint=hint, by_hand=by_hand)
                   for key, (function, *args) in functions.items()}
        self.close(check, name, value, compute(**results), atol=atol, rtol=rtol, hint=hint)

    @staticmethod
    def _compare(name, value, expected, atol, rtol, hint) -> str | None:
        expected = np.asarray(expected, dtype=float)
        suffix = f" {hint}" if hint else ""
        got = _as_numbers(value)
        if got is None:
            shape = "a number" if expected.ndim == 0 else f"numbers of shape {expected.shape}"
            return f"{name}: expected {shape}, got {_describe(value)}.{suffix}"
        if got.shape != expected.shape:
            transposed = " (the transpose's shape: transpose it)" if got.shape == expected.shape[::-1] else ""
            return f"{name}: expected shape {expected.shape}, got shape {got.shape}{transposed}.{suffix}"
        if not np.all(np.isfinite(got)):
            return f"{name}: expected finite numbers, got NaN or infinity.{suffix}"
        if np.allclose(got, expected, atol=atol, rtol=rtol):
            return None
        return f"{name}: not right: {_direction(got, expected)}.{suffix}"

