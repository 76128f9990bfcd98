"""The bank of wrong answers the course tests grade, with the score each gets (the instructor's guide shows them).

Each entry: (student id, what the student did, {answer cell: its code}, the autograded score out of 10). The
seeded wrong answers of the instructor's guide come first in each assignment; then the usual mistakes every
assignment is tried with where they apply: values pasted without functions, the package's solver inside a
"by hand" function, a transposed result, the spectral norm for a Frobenius one, lam left out, np.eye(N) for
np.eye(S), a hard-coded 0.0. ``guide_table()`` writes the table docs/course/instructors-guide.md holds; a test
checks the guide holds it verbatim.
"""

from __future__ import annotations


def _unwritten(*signatures: str) -> dict[str, str]:
    """Answer cells of functions left as released: a def whose body is nbgrader's placeholder."""
    return {name.split("(")[0]: f"def {name}:\n    # YOUR CODE HERE\n    raise NotImplementedError()"
            for name in signatures}


BANK: dict[str, list[tuple[str, str, dict[str, str], float]]] = {
    "a1_ridge_learner": [
        ("lam-left-out", "ridge_fit without lam", {"ridge_fit": """
def ridge_fit(Phi, U, lam):
    return np.linalg.solve(Phi.T @ Phi, Phi.T @ U).T
"""}, 5.0),
        ("pasted", "values pasted, no functions", {
            **_unwritten("ridge_fit(Phi, U, lam)", "teaching_error(theta_hat, theta)"),
            "E_novice": "E_novice = 2.40314", "shrinks": "shrinks = True"}, 1.0),
        ("solver", "RidgeLearner inside ridge_fit", {"ridge_fit": """
from mt_widgets import RidgeLearner
def ridge_fit(Phi, U, lam):
    return RidgeLearner(lam).fit(Phi, U).theta
"""}, 4.0),
        ("transposed", "ridge_fit returns (S, R)", {"ridge_fit": """
def ridge_fit(Phi, U, lam):
    return np.linalg.solve(Phi.T @ Phi + lam * np.eye(Phi.shape[1]), Phi.T @ U)
"""}, 4.0),
        ("spectral", "spectral norm for E", {"teaching_error": """
def teaching_error(theta_hat, theta):
    return float(np.linalg.norm(np.asarray(theta_hat) - np.asarray(theta), 2))
"""}, 7.0),
        ("eye-N", "np.eye(N) for np.eye(S)", {"ridge_fit": """
def ridge_fit(Phi, U, lam):
    return np.linalg.solve(Phi.T @ Phi + lam * np.eye(Phi.shape[0]), Phi.T @ U).T
"""}, 6.0),
        ("zero", "teaching_error returns 0.0", {"teaching_error": """
def teaching_error(theta_hat, theta):
    return 0.0
"""}, 7.0),
    ],
    "a2_optimal_demonstration": [
        ("own-actions", "optimal_demo returns the skill's own actions", {"optimal_demo": """
def optimal_demo(Phi, theta, lam):
    return Phi @ np.asarray(theta).T
"""}, 6.0),
        ("lam-left-out", "ridge_matrix without lam", {"ridge_matrix": """
def ridge_matrix(Phi, lam):
    return np.linalg.solve(Phi.T @ Phi, Phi.T)
"""}, 7.0),
        ("pasted", "values pasted, no functions", {
            **_unwritten("ridge_matrix(Phi, lam)", "optimal_demo(Phi, theta, lam)", "correction(Phi, theta, lam)"),
            "E_optimal": "E_optimal = 0.0"}, 0.0),
        ("solver", "optimal_actions inside optimal_demo", {"optimal_demo": """
from mt_widgets import optimal_actions
def optimal_demo(Phi, theta, lam):
    return optimal_actions(Phi, theta, lam)
"""}, 5.0),
        ("transposed", "ridge_matrix returns (N, S)", {"ridge_matrix": """
def ridge_matrix(Phi, lam):
    return np.linalg.solve(Phi.T @ Phi + lam * np.eye(Phi.shape[1]), Phi.T).T
"""}, 7.0),
        ("eye-N", "np.eye(N) for np.eye(S)", {"ridge_matrix": """
def ridge_matrix(Phi, lam):
    return np.linalg.solve(Phi.T @ Phi + lam * np.eye(Phi.shape[0]), Phi.T)
"""}, 8.0),
        ("closed-form", "the N = S closed form with (Phi^T Phi)^-1", {"optimal_demo": """
def optimal_demo(Phi, theta, lam):
    theta = np.asarray(theta)
    return Phi @ theta.T + lam * Phi @ np.linalg.inv(Phi.T @ Phi) @ theta.T
"""}, 9.0),
        ("zero", "correction returns 0.0", {"correction": """
def correction(Phi, theta, lam):
    return 0.0
"""}, 8.0),
    ],
    "a3_risk_bound": [
        ("largest-s", "rho1 from the largest singular value only", {"rho1": """
def rho1(Phi, lam):
    s = np.linalg.svd(Phi, compute_uv=False)
    return float(s[0] / (s[0] ** 2 + lam))
"""}, 7.0),
        ("lam-left-out", "rho1 = 1 / s_min (lam left out)", {"rho1": """
def rho1(Phi, lam):
    s = np.linalg.svd(Phi, compute_uv=False)
    return float(1 / s[-1])
"""}, 7.0),
        ("pasted", "values pasted, no functions", {
            **_unwritten("rho1(Phi, lam)", "rho2(U, U_bar)", "error_from_gap(A, U, U_bar)", "terms(A, U, U_bar)")},
         0.0),
        ("solver", "the package's ridge operator inside rho1", {"rho1": """
from mt_widgets.core.machine_teaching import ridge_operator
def rho1(Phi, lam):
    return ridge_operator(Phi, lam).rho1()
"""}, 7.0),
        ("spectral", "spectral norm for E", {"error_from_gap": """
def error_from_gap(A, U, U_bar):
    return float(np.linalg.norm(A @ (U - U_bar), 2))
"""}, 7.0),
        ("transposed", "terms over A's rows", {"terms": """
def terms(A, U, U_bar):
    return np.linalg.norm(A, axis=1) * np.linalg.norm(U - U_bar, axis=1)
"""}, 8.0),
        ("zero", "error_from_gap returns 0.0", {"error_from_gap": """
def error_from_gap(A, U, U_bar):
    return 0.0
"""}, 7.0),
    ],
    "a4_query_states": [
        ("squared", "condition number of Phi^T Phi", {"condition_number": """
def condition_number(Phi):
    return float(np.linalg.cond(Phi.T @ Phi))
"""}, 7.0),
        ("inverse", "||Phi|| ||Phi^-1|| (no inverse when not square)", {"condition_number": """
def condition_number(Phi):
    return float(np.linalg.norm(Phi, 2) * np.linalg.norm(np.linalg.inv(Phi), 2))
"""}, 8.0),
        ("pasted", "values pasted, no functions", {
            **_unwritten("condition_number(Phi)", "slip_error(Phi, theta, lam, slip)"),
            "rho1": ('def rho1(Phi, lam):\n    # YOUR CODE HERE\n    raise NotImplementedError()\n\n'
                     'which_amplifies = "bad"')},
         1.0),
        ("solver", "the package's condition_number", {"condition_number": """
from mt_widgets.core import condition_number as cond
def condition_number(Phi):
    return cond(Phi)
"""}, 7.0),
        ("lam-left-out", "rho1 = 1 / s_min (lam left out)", {"rho1": """
def rho1(Phi, lam):
    s = np.linalg.svd(Phi, compute_uv=False)
    return float(1 / s[-1])

which_amplifies = "bad"
"""}, 7.0),
        ("spectral", "spectral norm for E", {"slip_error": """
def slip_error(Phi, theta, lam, slip):
    theta_hat = RidgeLearner(lam).fit(Phi, optimal_actions(Phi, theta, lam) + slip).theta
    return float(np.linalg.norm(theta_hat - theta, 2))
"""}, 7.0),
        ("globals", "slip_error uses the notebook's theta and slip", {"slip_error": """
def slip_error(Phi, theta_, lam_, slip_):
    return teaching_risk(RidgeLearner(lam).fit(Phi, optimal_actions(Phi, skill.theta, lam) + slip).theta, skill.theta)
"""}, 8.0),
        ("zero", "slip_error returns 0.0", {"slip_error": """
def slip_error(Phi, theta, lam, slip):
    return 0.0
"""}, 7.0),
    ],
    "a5_teach_in_widget": [
        ("no-damping", "my_action forgets the damper", {"my_action": """
def my_action(skill, state):
    position, velocity = skill.end_effector(np.asarray(state))
    return np.array(skill.target.point) - position
"""}, 4.0),
        ("pasted", "values pasted, no functions", {
            **_unwritten("my_action(skill, state)", "gaps(records)", "final_distance(positions, point)")}, 0.0),
        ("solver", "the package's optimal actions inside my_action", {"my_action": """
from mt_widgets import optimal_actions
def my_action(skill, state):
    return optimal_actions(skill.features(np.asarray(state)[None]), skill.theta, 0.01)[0]
"""}, 4.0),
        ("fixed-target", "my_action aims at (0.8, 1.2) for every skill", {"my_action": """
def my_action(skill, state):
    position, velocity = skill.end_effector(np.asarray(state))
    return (np.array([0.8, 1.2]) - position) - velocity
"""}, 8.0),
        ("zero", "final_distance returns 0.0", {"final_distance": """
def final_distance(positions, point):
    return 0.0
"""}, 8.0),
    ],
    "a6_own_skill": [
        ("rest-point", "the rest point not times k", {"make_skill": """
def make_skill(k, d, point):
    r1, r2 = point
    return Skill("my-reach", "Reach", base.plant, base.feature_map,
                 theta=[[-k, 0, -d, 0, r1], [0, -k, 0, -d, r2]], start=base.start, target=PointTarget((r1, r2)))

my_skill = make_skill(2.0, 1.5, (1.0, 0.6))
"""}, 6.0),
        ("pasted", "values pasted, no functions", {
            "make_skill": "def make_skill(k, d, point):\n    # YOUR CODE HERE\n    raise NotImplementedError()",
            "teach_exactly": "def teach_exactly(skill, seed):\n    # YOUR CODE HERE\n    raise NotImplementedError()",
            "end_distance": "def end_distance(skill):\n    # YOUR CODE HERE\n    raise NotImplementedError()"}, 0.0),
        ("transposed", "theta as (5, 2)", {"make_skill": """
def make_skill(k, d, point):
    r1, r2 = point
    return Skill("my-reach", "Reach", base.plant, base.feature_map,
                 theta=np.array([[-k, 0, -d, 0, k * r1], [0, -k, 0, -d, k * r2]]).T, start=base.start,
                 target=PointTarget((r1, r2)))
"""}, 6.0),
        ("fixed-point", "end_distance measures to (1.0, 0.6) for every skill", {"end_distance": """
def end_distance(skill):
    return float(np.linalg.norm(skill.reproduce(skill.theta).positions[-1] - np.array([1.0, 0.6])))
"""}, 8.0),
        ("zero", "end_distance returns 0.0", {"end_distance": """
def end_distance(skill):
    return 0.0
"""}, 7.0),
    ],
    "a7_reading_a_study": [
        ("two-sided", "Welch two-sided", {"p_value": """
test_choice = "welch-two-sided"

def p_value(target, control):
    return float(stats.ttest_ind(target, control, equal_var=False).pvalue)
"""}, 5.0),
        ("pasted", "values pasted, no functions", {
            **_unwritten("retention(episodes)", "group_means(retention_values, groups)"),
            "p_value": 'test_choice = "welch-one-sided"\np_value = 0.07769'}, 1.0),
        ("sign", "retention as before minus after", {"retention": """
def retention(episodes):
    first = episodes[episodes["episode"] == 1].pivot_table(index="participant", columns="phase",
                                                         values="theta_error")
    return first["P1"] - first["P4"]
"""}, 7.0),
        ("student", "Student's t, one-sided", {"p_value": """
test_choice = "welch-one-sided"

def p_value(target, control):
    return float(stats.ttest_ind(target, control, alternative="less").pvalue)
"""}, 6.0),
        ("positional", "group_means by position, not by participant", {"group_means": """
def group_means(retention_values, groups):
    values = np.asarray(retention_values)
    labels = np.asarray(groups)
    return {g: float(values[labels == g].mean()) for g in ("target", "control")}
"""}, 9.0),
        ("zero", "p_value returns 0.0", {"p_value": """
test_choice = "welch-one-sided"

def p_value(target, control):
    return 0.0
"""}, 6.0),
    ],
    "a8_kernel_machine_teaching": [
        ("lam-left-out", "smoother without lam", {"smoother": """
def smoother(X, X_star, length_scale, lam):
    def k(A, B):
        return np.exp(-np.sum((A[:, None, :] - B[None, :, :]) ** 2, axis=-1) / (2 * length_scale ** 2))
    return k(X_star, X) @ np.linalg.inv(k(X, X))
"""}, 7.0),
        ("no-inverse", "smoother is k(X*, X), the learner's fit left out", {"smoother": """
def smoother(X, X_star, length_scale, lam):
    return np.exp(-np.sum((X_star[:, None, :] - X[None, :, :]) ** 2, axis=-1) / (2 * length_scale ** 2))
"""}, 7.0),
        ("pasted", "values pasted, no functions", {
            **_unwritten("smoother(X, X_star, length_scale, lam)", "teaching_actions(S, Y)", "risk(S, U, Y)"),
            "E_values": "E_representable = 1e-16\nE_target = 2.38183\nE_own = 2.50578"}, 0.0),
        ("solver", "KernelRidgeLearner inside smoother", {"smoother": """
from mt_widgets.core import KernelRidgeLearner
def smoother(X, X_star, length_scale, lam):
    return KernelRidgeLearner(length_scale, lam, linear_weight=0.0).smoother(X, X_star)
"""}, 6.0),
        ("transposed", "smoother returns (N, M)", {"smoother": """
def smoother(X, X_star, length_scale, lam):
    def k(A, B):
        return np.exp(-np.sum((A[:, None, :] - B[None, :, :]) ** 2, axis=-1) / (2 * length_scale ** 2))
    return np.linalg.solve(k(X, X) + lam * np.eye(len(X)), k(X, X_star))
"""}, 6.0),
        ("normal-equations", "teaching_actions by the normal equations (S^T S)^-1 S^T Y", {"teaching_actions": """
def teaching_actions(S, Y):
    return np.linalg.solve(S.T @ S, S.T @ Y)
"""}, 8.0),
        ("own-actions", "teaching_actions returns the first N rows of Y", {"teaching_actions": """
def teaching_actions(S, Y):
    return np.asarray(Y)[: np.shape(S)[1]]
"""}, 5.0),
        ("sum-not-mean", "risk as the Frobenius norm (a sum, not a mean)", {"risk": """
def risk(S, U, Y):
    return float(np.linalg.norm(S @ U - Y))
"""}, 7.0),
        ("zero", "risk returns 0.0", {"risk": """
def risk(S, U, Y):
    return 0.0
"""}, 7.0),
    ],
    "a9_industrial_arm": [
        ("own-actions", "optimal_actions_3d returns the skill's own actions", {"optimal_actions_3d": """
def optimal_actions_3d(Phi, theta, lam):
    return np.asarray(Phi) @ np.asarray(theta).T
"""}, 7.0),
        ("bias-first", "tool_features with the bias first", {"tool_features": """
def tool_features(positions, phases=None):
    positions = np.asarray(positions, dtype=float)
    columns = [np.ones((len(positions), 1)), positions]
    if phases is not None:
        columns.append(np.asarray(phases, dtype=float)[:, None])
    return np.hstack(columns)
"""}, 8.0),
        ("phase-last", "tool_features puts the conveyor's phase after the bias", {"tool_features": """
def tool_features(positions, phases=None):
    positions = np.asarray(positions, dtype=float)
    columns = [positions, np.ones((len(positions), 1))]
    if phases is not None:
        columns.append(np.asarray(phases, dtype=float)[:, None])
    return np.hstack(columns)
"""}, 9.0),
        ("pasted", "values pasted, no functions", {
            **_unwritten("tool_features(positions, phases=None)", "optimal_actions_3d(Phi, theta, lam)",
                         "teaching_risk_3d(Phi, U, theta, lam)", "stop_report(skill, theta)")}, 0.0),
        ("solver", "optimal_actions inside optimal_actions_3d", {"optimal_actions_3d": """
from mt_widgets import optimal_actions
def optimal_actions_3d(Phi, theta, lam):
    return optimal_actions(Phi, theta, lam)
"""}, 7.0),
        ("closed-form", "the N = S closed form with (Phi^T Phi)^-1", {"optimal_actions_3d": """
def optimal_actions_3d(Phi, theta, lam):
    theta = np.asarray(theta)
    return Phi @ theta.T + lam * Phi @ np.linalg.inv(Phi.T @ Phi) @ theta.T
"""}, 8.0),
        ("spectral", "spectral norm for E", {"teaching_risk_3d": """
def teaching_risk_3d(Phi, U, theta, lam):
    theta_hat = np.linalg.solve(Phi.T @ Phi + lam * np.eye(Phi.shape[1]), Phi.T @ U).T
    return float(np.linalg.norm(theta_hat - theta, 2))
"""}, 8.0),
        ("stopped-flag", "stop_report says \"stopped\" for any stop, not why", {"stop_report": """
def stop_report(skill, theta):
    trajectory = skill.reproduce(theta)
    return ("stopped" if trajectory.diverged else ""), trajectory.positions[-1]
"""}, 7.0),
        ("target-end", "stop_report gives the skill's target, not where the tool stopped", {"stop_report": """
def stop_report(skill, theta):
    trajectory = skill.reproduce(theta)
    return trajectory.stop_reason, np.array(skill.target.point)
"""}, 7.0),
        ("zero", "teaching_risk_3d returns 0.0", {"teaching_risk_3d": """
def teaching_risk_3d(Phi, U, theta, lam):
    return 0.0
"""}, 8.0),
    ],
}


def guide_table() -> str:
    """The instructor's guide's table of the bank: assignment, student id, mistake, autograded score."""
    lines = ["| assignment | submission | the mistake | autograded score |", "| --- | --- | --- | --- |"]
    for assignment, entries in BANK.items():
        lines.append(f"| {assignment} | untouched | the released notebook, nothing written | 0 / 10 |")
        lines.extend(f"| {assignment} | {student} | {what} | {score:g} / 10 |" for student, what, _, score in entries)
    return "\n".join(lines)
