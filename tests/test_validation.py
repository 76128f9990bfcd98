"""One validation module (mt_widgets/core/validation.py) serves every layer, with one message
style, "name: expected ..., got ...": the layers call it instead of keeping checks of their own."""

import ast
from pathlib import Path

import numpy as np
import pytest

from mt_widgets import SKILLS
from mt_widgets.analysis.power import analytic_power, sample_size_per_group
from mt_widgets.analysis.statistics import analyse_changes
from mt_widgets.core.validation import (
    UnknownKeyError,
    as_bool,
    as_count,
    as_finite,
    as_float_array,
    as_fraction,
    as_positive,
    is_real,
)
from mt_widgets.hardware.envelope import SafetyEnvelope
from mt_widgets.hardware.errors import UnsafeMoveError
from mt_widgets.in_silico import run_in_silico
from mt_widgets.in_silico.teachers import TeacherParameters
from mt_widgets.study.analysis_plan import AnalysisPlan
from mt_widgets.widgets.coords import ViewTransform

PACKAGE = Path(__file__).resolve().parents[1] / "mt_widgets"

#: Private checks that once lived beside their callers, each a copy of a core.validation check.
RETIRED_CHECKS = {"is_real", "_check_level", "_check_confidence", "_as_points"}


def test_no_layer_keeps_its_own_copy_of_a_shared_check():
    assert (PACKAGE / "core" / "validation.py").is_file()
    for path in PACKAGE.rglob("*.py"):
        if path.name == "validation.py":
            continue
        defined = {node.name for node in ast.walk(ast.parse(path.read_text(encoding="utf-8")))
                   if isinstance(node, ast.FunctionDef)}
        assert not defined & RETIRED_CHECKS, f"{path.relative_to(PACKAGE)} defines {defined & RETIRED_CHECKS}"


def test_a_real_number_is_never_a_bool_nor_a_string():
    assert is_real(1) and is_real(2.5) and is_real(np.float32(1)) and is_real(np.int64(3))
    assert not is_real(True) and not is_real("1") and not is_real(None)
    assert as_finite("x", np.float32(1.5)) == 1.5
    for value, message, error in ((np.nan, "expected a finite number", ValueError),
                                  (True, "expected a real number", TypeError)):
        with pytest.raises(error, match=rf"^x: {message}, got "):
            as_finite("x", value)


@pytest.mark.parametrize("value", [0, 1, 1.5, -0.1, True, "0.05", np.nan])
def test_levels_and_confidences_are_fractions_checked_in_one_place(value):
    message = r": expected a number strictly between 0 and 1, got "
    error = TypeError if isinstance(value, (bool, str)) else ValueError   # a wrong type, or a wrong number
    with pytest.raises(error, match="^alpha" + message):
        as_fraction("alpha", value)
    with pytest.raises(error, match="^alpha" + message):
        analytic_power(16, 0.8, alpha=value)
    with pytest.raises(error, match="^power" + message):
        sample_size_per_group(0.8, power=value)
    assert as_fraction("alpha", np.float64(0.05)) == 0.05


def test_the_envelope_checks_coordinates_with_the_shared_predicate_and_its_own_safety_error():
    envelope = SafetyEnvelope()
    # A numpy float is a coordinate (the shared is_real), a bool is not; the envelope's message
    # and error type are its own.
    envelope.check_point(np.float32(200.0), np.float64(0.0), np.int64(80))
    with pytest.raises(UnsafeMoveError, match=r"^z: expected a finite real number of mm \(arm frame\), got True"):
        envelope.check_point(200.0, 0.0, True)


def test_view_points_teacher_parameters_and_unknown_skills_are_refused_in_the_one_style():
    transform = ViewTransform((0.0, 1.0), (0.0, 1.0), 100, 100)
    with pytest.raises(ValueError, match=r"^points: expected shape \(2\) \(trailing axes\), got \(3,\)"):
        transform.to_pixel([1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match=r"^retention: expected a non-negative finite number, got -0.5"):
        TeacherParameters(retention=-0.5)
    with pytest.raises(TypeError, match=r"^drawing_s: expected a real number, got bool True"):
        TeacherParameters(drawing_s=True)
    with pytest.raises(UnknownKeyError) as error:
        SKILLS["nope"]
    # Readable as written (a plain KeyError would print it in quotes), and still a KeyError.
    assert isinstance(error.value, KeyError)
    assert str(error.value) == ("skill: expected one of the known skills (panda-conveyor, panda-place, panda-reach, "
                                "sim-line, sim-point, so101-place, so101-reach, uarm-line, uarm-point, ur5-conveyor, "
                                "ur5-place, ur5-reach), got 'nope'")


@pytest.mark.parametrize(("check", "wrong_type", "wrong_value"), [
    (lambda v: as_bool("x", v), "no", None),
    (lambda v: as_count("x", v), 2.0, 0),
    (lambda v: as_finite("x", v), "1", np.inf),
    (lambda v: as_positive("x", v), True, -1.0),
    (lambda v: as_fraction("x", v), "0.05", 1.0),
    (lambda v: as_float_array("x", v, shape=(2,)), ["a", "b"], [1.0, 2.0, 3.0]),
    (lambda v: as_float_array("x", v), None, [[1.0, 2.0], [3.0]]),
], ids=["bool", "count", "finite", "positive", "fraction", "array", "array-none-or-ragged"])
def test_a_wrong_type_is_a_type_error_and_a_wrong_value_a_value_error(check, wrong_type, wrong_value):
    with pytest.raises(TypeError, match=r"^x: expected "):
        check(wrong_type)
    if wrong_value is None:   # as_bool: None is a wrong type too, unless the option allows it
        assert as_bool("x", None, allow_none=True) is None
        return
    with pytest.raises(ValueError, match=r"^x: expected ") as error:
        check(wrong_value)
    assert not isinstance(error.value, TypeError)


def test_the_effort_bars_check_their_budgets_with_the_core_checks():
    from mt_widgets.widgets.progress import EffortProgress
    with pytest.raises(TypeError, match=r"^demonstration_budget: expected a whole number, got float 2.5"):
        EffortProgress(2.5)
    with pytest.raises(ValueError, match=r"^episode_budget: expected a whole number >= 1, got 0"):
        EffortProgress(3, episode_budget=0)
    with pytest.raises(ValueError, match=r"^demonstrations_done: expected a whole number >= 0, got -1"):
        EffortProgress(3, demonstrations_done=-1)
    bars = EffortProgress(3, 2, demonstrations_done=1)
    assert (bars.demonstration_bar.max, bars.episode_bar.max, bars.demonstrations_done) == (3, 2, 1)


def test_the_study_and_analysis_layers_check_with_the_core_checks():
    # One message and one convention for alpha, power and counts, in every layer.
    message = r": expected a number strictly between 0 and 1, got "
    with pytest.raises(TypeError, match="^alpha" + message):
        AnalysisPlan(alpha="0.05")
    with pytest.raises(ValueError, match="^power" + message):
        AnalysisPlan(power=1.0)
    with pytest.raises(TypeError, match=r"^effect_size: expected a real number, got str '0.9'"):
        AnalysisPlan(effect_size="0.9")
    with pytest.raises(ValueError, match=r"^effect_size: expected a non-zero number \(Cohen's d\), got 0"):
        AnalysisPlan(effect_size=0)
    with pytest.raises(TypeError, match="^alpha" + message):
        analyse_changes(None, alpha=True)
    with pytest.raises(ValueError, match="^alpha" + message):
        analyse_changes(None, alpha=1.5)
    with pytest.raises(TypeError, match=r"^n_participants: expected a whole number, got float 2.0"):
        run_in_silico(n_participants=2.0)
    with pytest.raises(ValueError, match=r"^n_per_group: expected a whole number >= 2, got 1"):
        analytic_power(1, 0.8)
