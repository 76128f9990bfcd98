"""Machine teaching against its defining property: the optimal demonstration teaches Theta."""

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mt_widgets import SKILLS, RidgeLearner, analyse_demonstrations, optimal_actions, teaching_risk
from mt_widgets.core import DEFAULT_LAMBDA, UnderdeterminedTeachingWarning, action_difference


@st.composite
def teaching_problems(draw, below_teaching_dimension=False):
    S = draw(st.integers(2, 6))
    R = draw(st.integers(1, 3))
    N = draw(st.integers(1, S - 1)) if below_teaching_dimension else draw(st.integers(S, S + 4))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    # Random full-rank features with a bounded condition number (up to 1e3), as query states are.
    left, _ = np.linalg.qr(rng.normal(size=(N, min(N, S))))
    right, _ = np.linalg.qr(rng.normal(size=(S, S)))
    singular = np.geomspace(1.0, 10 ** draw(st.floats(0, 3)), min(N, S)) * draw(st.floats(0.1, 10))
    Phi = (left * singular) @ right[:, :min(N, S)].T
    theta = rng.normal(size=(R, S)) * 3
    lam = draw(st.one_of(st.just(0.0), st.floats(1e-6, 10.0)))
    return Phi, theta, lam, rng


@pytest.mark.slow
@settings(max_examples=200, deadline=None)
@given(teaching_problems())
def test_learning_from_the_optimal_demonstration_gives_back_theta(problem):
    Phi, theta, lam, _ = problem
    learnt = RidgeLearner(lam).fit(Phi, optimal_actions(Phi, theta, lam)).theta
    assert np.linalg.norm(learnt - theta) / np.linalg.norm(theta) < 1e-8


@settings(max_examples=200, deadline=None)
@given(teaching_problems())
def test_the_risk_bound_holds_and_contributions_add_up(problem):
    Phi, theta, lam, rng = problem
    U = optimal_actions(Phi, theta, lam) + rng.normal(scale=2.0, size=(Phi.shape[0], theta.shape[0]))
    analysis = analyse_demonstrations(Phi, U, theta, lam)
    assert analysis.exact
    assert analysis.risk <= analysis.rho1 * analysis.rho2 * (1 + 1e-9) + 1e-12
    np.testing.assert_allclose(analysis.risk, teaching_risk(RidgeLearner(lam).fit(Phi, U).theta, theta), rtol=1e-9)
    # Each demonstration's share: the triangle inequality over the exact decomposition.
    assert analysis.risk <= analysis.contributions.sum() * (1 + 1e-9) + 1e-12
    singular = np.linalg.svd(Phi, compute_uv=False)
    np.testing.assert_allclose(analysis.rho1, np.max(singular / (singular**2 + lam)), rtol=1e-10)


@settings(max_examples=150, deadline=None)
@given(teaching_problems(below_teaching_dimension=True))
def test_below_the_teaching_dimension_no_demonstration_does_better(problem):
    Phi, theta, lam, rng = problem
    with pytest.warns(UnderdeterminedTeachingWarning, match="rank"):
        best = optimal_actions(Phi, theta, lam)
    learner = RidgeLearner(lam)
    best_risk = teaching_risk(learner.fit(Phi, best).theta, theta)
    assert best_risk > 0
    for scale in (1e-3, 1e-1, 10.0):
        other = best + rng.normal(scale=scale, size=best.shape)
        assert teaching_risk(learner.fit(Phi, other).theta, theta) >= best_risk * (1 - 1e-9)
    # First-order optimality of min ||A U - Theta^T||, with A built independently: ridge as the
    # least-squares problem on Phi stacked over sqrt(lam) I (stable where Phi^T Phi + lam I is not).
    N, S = Phi.shape
    A = np.linalg.lstsq(np.vstack([Phi, np.sqrt(lam) * np.eye(S)]), np.vstack([np.eye(N), np.zeros((S, N))]),
                        rcond=None)[0]
    gradient = A.T @ (A @ best - theta.T)
    assert np.linalg.norm(gradient) <= 1e-8 * np.linalg.norm(A) * np.linalg.norm(theta)


def test_optimal_actions_equal_the_closed_form_with_full_rank():
    rng = np.random.default_rng(3)
    Phi, theta, lam = rng.normal(size=(7, 5)), rng.normal(size=(2, 5)), 0.3
    expected = Phi @ theta.T + lam * Phi @ np.linalg.solve(Phi.T @ Phi, theta.T)
    np.testing.assert_allclose(optimal_actions(Phi, theta, lam), expected, rtol=1e-10)


def test_with_no_ridge_the_optimal_actions_are_the_skills_own_actions():
    rng = np.random.default_rng(4)
    Phi, theta = rng.normal(size=(5, 5)), rng.normal(size=(2, 5))
    np.testing.assert_allclose(optimal_actions(Phi, theta, 0.0), Phi @ theta.T, rtol=1e-10)


def test_a_wrong_demonstration_has_positive_risk_and_the_optimal_none():
    rng = np.random.default_rng(5)
    Phi, theta = rng.normal(size=(5, 5)), rng.normal(size=(2, 5))
    analysis = analyse_demonstrations(Phi, optimal_actions(Phi, theta, 0.01) + [[0.5, 0]] + 0 * Phi[:, :2], theta, 0.01)
    assert analysis.risk > 0.01 and analysis.contributions.min() > 0
    perfect = analyse_demonstrations(Phi, optimal_actions(Phi, theta, 0.01), theta, 0.01)
    assert perfect.risk < 1e-12 and perfect.rho2 < 1e-12


def test_repeated_states_with_no_ridge_fit_without_failing():
    Phi = np.array([[1.0, 2.0, 1.0], [1.0, 2.0, 1.0], [3.0, 0.0, 1.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnderdeterminedTeachingWarning)
        U = optimal_actions(Phi, np.ones((2, 3)), 0.0)
    assert np.all(np.isfinite(RidgeLearner(0.0).fit(Phi, U).theta))


def test_action_difference_speaks_in_angle_and_magnitude():
    difference = action_difference([0.0, 2.0], [1.0, 0.0])
    assert difference.angle_deg == pytest.approx(90.0)
    assert difference.magnitude_ratio == pytest.approx(2.0)
    assert action_difference([1.0, -1.0], [1.0, 0.0]).angle_deg == pytest.approx(-45.0)


@pytest.mark.parametrize("call, name", [
    (lambda: RidgeLearner(-1.0).fit(np.ones((3, 2)), np.ones((3, 2))).theta, "lam: expected a non-negative"),
    (lambda: RidgeLearner(0.1).fit(np.ones((3, 2)), np.ones((4, 2))).theta, "U: expected one action per row"),
    (lambda: RidgeLearner(0.1).fit(np.ones(3), np.ones((3, 2))).theta, "Phi"),
    (lambda: RidgeLearner(0.1).fit(np.ones((3, 2)), np.full((3, 2), np.inf)).theta, "U: expected finite"),
    (lambda: optimal_actions(np.ones((5, 5)), np.ones((2, 3)), 0.1), r"theta: expected shape \(R, 5\)"),
    (lambda: optimal_actions(np.ones((5, 5)), np.ones((2, 5)), -0.1), "lam"),
    (lambda: optimal_actions(np.ones((5, 5)), np.ones((2, 5)), "big"), "lam: expected a real number"),
    (lambda: teaching_risk(np.ones((2, 5)), np.ones((2, 3))), "theta_hat"),
    (lambda: analyse_demonstrations(np.eye(3), np.ones((3, 1)), np.ones((2, 3)), 0.1), "U: expected 2"),
])
def test_bad_input_names_the_argument(call, name):
    # A str where a number goes is a wrong type; the rest are wrong values.
    with pytest.raises(TypeError if "expected a real number" in name else ValueError, match=name):
        call()


def test_features_with_no_columns_are_refused_by_name():
    with pytest.raises(ValueError, match=r"Phi: expected at least one feature"):
        RidgeLearner(0.1).fit(np.ones((3, 0)), np.ones((3, 2))).theta


def test_analysis_and_optimal_actions_agree_on_rank():
    # One rank rule for both paths: the analysis's exact flag and the warning must agree.
    rng = np.random.default_rng(9)
    Phi = rng.normal(size=(5, 5))
    Phi[4] = Phi[3] * (1 + 1e-15)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        optimal_actions(Phi, np.ones((2, 5)), 0.01)
    warned = any(issubclass(w.category, UnderdeterminedTeachingWarning) for w in caught)
    assert analyse_demonstrations(Phi, np.ones((5, 2)), np.ones((2, 5)), 0.01).exact == (not warned)


def test_optimal_actions_defaults_to_the_learners_lambda():
    skill = SKILLS["sim-point"]
    Phi = skill.features(skill.query_states(seed=0))
    U_bar = optimal_actions(Phi, skill.theta)
    np.testing.assert_array_equal(U_bar, optimal_actions(Phi, skill.theta, DEFAULT_LAMBDA))
    # The README's and docs/user/core.md's promise: with the defaults on both sides, the optimal arrows teach theta.
    assert teaching_risk(RidgeLearner().fit(Phi, U_bar).theta, skill.theta) < 1e-10
    assert not np.allclose(U_bar, optimal_actions(Phi, skill.theta, 0.0), atol=1e-6), "lam must matter here"
