"""The right answers the course's checks compare a student's functions with, from the library.

One function per exercise function, with the student's signature, so a test cell names the
reference (``references.ridge_fit``) instead of holding its code: a released notebook shows no
formula and no expected number. Each is a thin call of the library (``mt_widgets.core``), the
one place the science is computed; what is added here is only the exercise's own framing (a
rank-deficient case returns the least-error answer without a warning, an exercise's index or
a study's table).
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy import stats

from mt_widgets.core import PointTarget, RidgeLearner, Skill, analyse_demonstrations, optimal_actions, teaching_risk
from mt_widgets.core.kernel_learners import KernelRidgeLearner
from mt_widgets.core.learner_teaching import policy_risk
from mt_widgets.core.machine_teaching import UnderdeterminedTeachingWarning, ridge_operator
from mt_widgets.core.query_states import condition_number as _condition_number

# -- a1: the ridge learner ------------------------------------------------------------------------


def ridge_fit(Phi, U, lam) -> np.ndarray:
    """Theta_hat (R, S) of ridge regression."""
    return RidgeLearner(lam).fit(Phi, U).theta


def teaching_error(theta_hat, theta) -> float:
    """E = ||vec(Theta_hat) - vec(Theta)||_2 (the Frobenius norm of the difference)."""
    return teaching_risk(theta_hat, theta)


# -- a2: the optimal demonstration ---------------------------------------------------------------


def ridge_matrix(Phi, lam) -> np.ndarray:
    """A = (Phi^T Phi + lam I)^-1 Phi^T, (S, N)."""
    return ridge_operator(Phi, lam).matrix()


def optimal_demo(Phi, theta, lam) -> np.ndarray:
    """U_bar (N, R), the least-error one (pinv) when the states do not span the features."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnderdeterminedTeachingWarning)
        return optimal_actions(Phi, theta, lam)


def correction(Phi, theta, lam) -> float:
    """The largest entry of |U_bar - Phi Theta^T|: what undoes the ridge shrinkage."""
    return float(np.max(np.abs(optimal_demo(Phi, theta, lam) - np.asarray(Phi) @ np.asarray(theta).T)))


def teach_error(Phi, U, theta, lam) -> float:
    """The teaching error of the ridge learner taught (Phi, U)."""
    return teaching_risk(ridge_fit(Phi, U, lam), theta)


# -- a3 and a4: the bound and the conditioning -----------------------------------------------------


def rho1(Phi, lam) -> float:
    """||A||_2 = max_i s_i / (s_i^2 + lam) over Phi's nonzero singular values."""
    return ridge_operator(Phi, lam).rho1()


def rho2(U, U_bar) -> float:
    """||U - U_bar||_F."""
    return float(np.linalg.norm(np.asarray(U, dtype=float) - np.asarray(U_bar, dtype=float)))


def error_from_gap(A, U, U_bar) -> float:
    """E = ||A (U - U_bar)||_F, the teaching error from the learner's matrix and the gap (exact teaching)."""
    return float(np.linalg.norm(np.asarray(A, dtype=float) @ (np.asarray(U, dtype=float) - np.asarray(U_bar))))


def terms(A, U, U_bar) -> np.ndarray:
    """(N,) ||a_n|| ||u_n - u_bar_n||: the size of each demonstration's term a_n (u_n - u_bar_n)^T."""
    A = np.asarray(A, dtype=float)
    return np.linalg.norm(A, axis=0) * np.linalg.norm(np.asarray(U, dtype=float) - np.asarray(U_bar), axis=1)


def condition_number(Phi) -> float:
    """s_max / s_min of Phi."""
    return _condition_number(np.asarray(Phi, dtype=float))


def slip_error(Phi, theta, lam, slip) -> float:
    """The teaching error of the optimal demonstration plus ``slip`` on the states of Phi."""
    return analyse_demonstrations(Phi, optimal_demo(Phi, theta, lam) + np.asarray(slip), theta, lam).risk


# -- a5: the widget -----------------------------------------------------------------------------


def gaps(records) -> np.ndarray:
    """(N,) |u_n - u_bar_n| of an episode's confirmed demonstrations."""
    return np.array([np.linalg.norm(np.asarray(r.action) - np.asarray(r.optimal_action)) for r in records])


def final_distance(positions, point) -> float:
    """The distance from the last of ``positions`` (T, 2) to ``point``."""
    return float(np.linalg.norm(np.asarray(positions, dtype=float)[-1] - np.asarray(point, dtype=float)))


# -- a6: a skill of one's own -----------------------------------------------------------------------


def spring_theta(k, d, point) -> np.ndarray:
    """Theta (2, 5) of u = -k (r - r*) - d rdot on the features (r1, r2, r1dot, r2dot, 1)."""
    r1, r2 = (float(v) for v in point)
    return np.array([[-k, 0.0, -d, 0.0, k * r1], [0.0, -k, 0.0, -d, k * r2]])


def spring_skill(base: Skill, k, d, point) -> Skill:
    """The spring-damper skill to ``point`` on ``base``'s plant, features and start."""
    return Skill("reference", "reference", base.plant, base.feature_map, spring_theta(k, d, point), base.start,
                 PointTarget(tuple(float(v) for v in point)))


# -- a7: reading a study ----------------------------------------------------------------------------


def retention(episodes):
    """Each participant's E(P4, episode 1) - E(P1, episode 1), a Series indexed by participant."""
    first = episodes[episodes["episode"] == 1].pivot_table(index="participant", columns="phase",
                                                         values="theta_error")
    return (first["P4"] - first["P1"]).rename(None)


def group_means(retention_, groups) -> dict:
    """{group: mean of ``retention_`` over its participants}; ``groups`` maps participant to group."""
    frame = retention_.to_frame("delta").join(groups.rename("group"))
    return {str(k): float(v) for k, v in frame.groupby("group")["delta"].mean().items()}


def one_sided_welch_p(target, control) -> float:
    """Welch's t-test of 'the target group's change is below the control's' (one-sided)."""
    return float(stats.ttest_ind(np.asarray(target, dtype=float), np.asarray(control, dtype=float),
                                 equal_var=False, alternative="less").pvalue)


# -- a8: machine teaching for a kernel learner -----------------------------------------------------


def kernel_smoother(X, X_star, length_scale, lam) -> np.ndarray:
    """S (M, N) of kernel ridge regression with an RBF kernel: k(X*, X) (K + lam I)^-1."""
    return KernelRidgeLearner(length_scale, lam, linear_weight=0.0).smoother(X, X_star)


def smoother_teaching_actions(S, Y) -> np.ndarray:
    """The least-squares (minimum-norm) demonstration U (N, R) with S U closest to Y (M, R)."""
    return np.linalg.lstsq(np.asarray(S, dtype=float), np.asarray(Y, dtype=float), rcond=None)[0]


def smoother_risk(S, U, Y) -> float:
    """The policy risk sqrt(mean_m ||(S U)_m - Y_m||^2) of the demonstration U."""
    return policy_risk(np.asarray(S, dtype=float) @ np.asarray(U, dtype=float), Y)


# -- a9: teaching an industrial arm in 3-D -----------------------------------------------------------


def tool_features(positions, phases=None) -> np.ndarray:
    """phi (N, S) of the ``ur5-`` skills from tool points (N, 3) m: (r1, r2, r3, 1), or (r1, r2, r3, s, 1)
    with the conveyor's phases s (N,) m."""
    positions = np.asarray(positions, dtype=float)
    columns = [positions] + ([] if phases is None else [np.asarray(phases, dtype=float)[:, None]])
    return np.hstack(columns + [np.ones((len(positions), 1))])


def stop_report(skill, theta) -> tuple:
    """(why the reproduction of ``theta`` stopped, "" if it ran to the end; the tool point (3,) at its last sample)."""
    trajectory = skill.reproduce(np.asarray(theta, dtype=float))
    return trajectory.stop_reason, trajectory.positions[-1]
