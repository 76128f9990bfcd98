"""Compiled rollouts of a serial-chain arm under a linear tool-velocity policy: the chain engine.

A rollout takes three structures: the chain (``chain_dynamics.ChainModel``: kinematics,
inertias, limits), the scene (``ChainScene``: the table, the conveyor, which capsules may
collide) and the controller (``ChainControl``). Nothing in here knows which arm it moves.

The controller runs at 1 kHz. At each sample k the policy gives the tool's velocity
``u_k = Theta phi(x_k)`` (m/s, base frame), held over the step:

1. resolved rate: ``qd_ref = J^T (J J^T + mu^2 I)^-1 u_k`` (damped least squares, so a pose near
   a singularity asks for large but finite joint speeds). An arm with more joints than the
   task's three (the Panda's seven) has joint motions that leave the tool still: with a
   null-space gain k_n > 0 these pull the arm towards its home pose, ``qd_ref += N k_n (q_home - q)``
   with ``N = I - J^T (J J^T)^-1 J`` (the projector onto J's null space: the pull never moves
   the tool; skipped at a singular pose), so the elbow does not drift over a long reproduction;
   with k_n = 0 the minimum-norm joint speeds are taken. The whole qd_ref is then scaled down when
   a joint would exceed its velocity limit
   (the direction of the tool's motion is kept);
2. a dynamic arm (torque-controlled, state q, qd): a velocity loop with gravity compensation,
   ``tau = g(q) + M(q) k_v (qd_ref - qd)``, each joint's torque clipped to its effort limit (what
   a drive does), integrated with classical RK4 through the chain's forward dynamics;
   a kinematic arm (position-controlled servos, state q): ``qd = qd_ref(q, u_k)``, integrated
   with RK4 (the servos' own position loops track far faster than the taught motion).

A reproduction stops cleanly (a code, the arrays frozen at the last valid sample, never NaN)
at the first state that is not finite, leaves a joint's position range, exceeds a joint's speed
limit by more than a tolerance, puts a link or the tool into the table, or brings two links
that may collide (the scene's pairs) closer than their capsules allow.
"""

from __future__ import annotations

import math
import threading
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from . import chain_dynamics as dyn

#: Why a rollout stopped, by code (0: it did not).
STOP_REASONS = ("", "diverged", "joint limit", "joint speed limit", "table", "self-collision")
DIVERGED, JOINT_LIMIT, JOINT_SPEED, TABLE, SELF_COLLISION = 1, 2, 3, 4, 5


class ChainScene(NamedTuple):
    """What surrounds the chain: the table, the conveyor, the capsules that may collide.

    table_height: the table top's z (m, base frame); first_table_point: the first chain point
    (base 0, joint origins 1..n, tool n + 1) checked against the table (those before stand on
    it by design); pairs (k, 2): segments (between consecutive chain points) that may collide;
    radius: the capsules' radius (m); conveyor_speed (m/s) and with_phase: the state ends with
    the conveyor's phase s and the features are (r, s, 1) instead of (r, 1).
    """

    table_height: float
    first_table_point: int
    pairs: np.ndarray
    radius: float
    conveyor_speed: float
    with_phase: bool


class ChainControl(NamedTuple):
    """The controller's settings (see the module's docstring).

    gain: k_v (1/s); damping: mu (m); speed_tolerance: the fraction a joint may exceed its speed
    limit by before a rollout stops; null_gain: k_n (1/s); home: (n,) the pose the null space
    pulls towards; kinematic: the arm's joints follow qd_ref exactly (the state carries no qd).
    """

    gain: float
    damping: float
    speed_tolerance: float
    null_gain: float
    home: np.ndarray
    kinematic: bool


@njit(cache=True, error_model="numpy", inline="always")
def segment_distance(p0, p1, q0, q1):
    """The smallest distance between the segments p0-p1 and q0-q1 (3-D), by clamped closest points."""
    d1x, d1y, d1z = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
    d2x, d2y, d2z = q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2]
    rx, ry, rz = p0[0] - q0[0], p0[1] - q0[1], p0[2] - q0[2]
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    if a <= 1e-15 and e <= 1e-15:
        s = t = 0.0
    elif a <= 1e-15:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = d1x * rx + d1y * ry + d1z * rz
        if e <= 1e-15:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = d1x * d2x + d1y * d2y + d1z * d2z
            denom = a * e - b * b
            s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > 1e-15 else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    dx = rx + d1x * s - d2x * t
    dy = ry + d1y * s - d2y * t
    dz = rz + d1z * s - d2z * t
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True, error_model="numpy", inline="always")
def chain_points(world_p, tool, out):
    """The chain's points (n + 2, 3): the base origin, each joint's origin, the tool point."""
    n = world_p.shape[0]
    for k in range(3):
        out[0, k] = 0.0
        for i in range(n):
            out[i + 1, k] = world_p[i, k]
        out[n + 1, k] = tool[k]


@njit(cache=True, error_model="numpy", inline="always")
def safety_code(model, scene, speed_tolerance, q, qd, points):
    """0 when the state is safe, else the first reason it is not (a code of ``STOP_REASONS``).

    qd: the joint speeds (a kinematic arm's commanded ones).
    """
    n = q.shape[0]
    lower, upper, velocity_limit = model.lower, model.upper, model.velocity_limit
    for i in range(n):
        if not (math.isfinite(q[i]) and math.isfinite(qd[i])):
            return DIVERGED
    for i in range(n):
        if q[i] < lower[i] or q[i] > upper[i]:
            return JOINT_LIMIT
    for i in range(n):
        if abs(qd[i]) > velocity_limit[i] * (1.0 + speed_tolerance):
            return JOINT_SPEED
    radius = scene.radius
    for i in range(scene.first_table_point, points.shape[0]):
        if points[i, 2] < scene.table_height + radius:
            return TABLE
    pairs = scene.pairs
    for k in range(pairs.shape[0]):
        a, b = pairs[k, 0], pairs[k, 1]
        if segment_distance(points[a], points[a + 1], points[b], points[b + 1]) < 2.0 * radius:
            return SELF_COLLISION
    return 0


@njit(cache=True, error_model="numpy", inline="always")
def joint_velocity_reference(J, velocity, q, velocity_limit, damping, null_gain, home, out_ref):
    """qd_ref for a tool velocity (step 1 of the module's docstring)."""
    n = J.shape[1]
    # A = J J^T + damping^2 I (3 x 3, symmetric positive definite), y = A^-1 velocity by Cramer's rule
    a00 = a11 = a22 = damping * damping
    a01 = a02 = a12 = 0.0
    for i in range(n):
        a00 += J[0, i] * J[0, i]
        a11 += J[1, i] * J[1, i]
        a22 += J[2, i] * J[2, i]
        a01 += J[0, i] * J[1, i]
        a02 += J[0, i] * J[2, i]
        a12 += J[1, i] * J[2, i]
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    y0 = (c00 * velocity[0] + c01 * velocity[1] + c02 * velocity[2]) / det
    y1 = (c01 * velocity[0] + c11 * velocity[1] + c12 * velocity[2]) / det
    y2 = (c02 * velocity[0] + c12 * velocity[1] + c22 * velocity[2]) / det
    for i in range(n):
        out_ref[i] = J[0, i] * y0 + J[1, i] * y1 + J[2, i] * y2
    if null_gain > 0.0:
        # + N k_n (home - q): z minus its part J^T (J J^T)^-1 J z that would move the tool. The
        # projector is the exact one (undamped): a damped one would leak a little of the pull into
        # the tool's motion, a steady offset of millimetres. Skipped at a singular pose.
        b00, b11, b22 = a00 - damping * damping, a11 - damping * damping, a22 - damping * damping
        e00 = b11 * b22 - a12 * a12
        e01 = a02 * a12 - a01 * b22
        e02 = a01 * a12 - a02 * b11
        e11 = b00 * b22 - a02 * a02
        e12 = a01 * a02 - b00 * a12
        e22 = b00 * b11 - a01 * a01
        det0 = b00 * e00 + a01 * e01 + a02 * e02
        if det0 > 1e-12:
            j0 = j1 = j2 = 0.0
            for i in range(n):
                z = null_gain * (home[i] - q[i])
                j0 += J[0, i] * z
                j1 += J[1, i] * z
                j2 += J[2, i] * z
            z0 = (e00 * j0 + e01 * j1 + e02 * j2) / det0
            z1 = (e01 * j0 + e11 * j1 + e12 * j2) / det0
            z2 = (e02 * j0 + e12 * j1 + e22 * j2) / det0
            for i in range(n):
                out_ref[i] += null_gain * (home[i] - q[i]) - (J[0, i] * z0 + J[1, i] * z1 + J[2, i] * z2)
    scale = 1.0
    for i in range(n):
        if abs(out_ref[i]) * scale > velocity_limit[i]:
            scale = velocity_limit[i] / abs(out_ref[i])
    for i in range(n):
        out_ref[i] = scale * out_ref[i]


@njit(cache=True, error_model="numpy", inline="always")
def held_torque(reference, q_dot, mass_matrix, gravity_torque, effort_limit, gain, out_tau):
    """tau = g(q) + M(q) k_v (qd_ref - qd), each joint's clipped to its effort limit."""
    n = reference.shape[0]
    for i in range(n):
        acc = gravity_torque[i]
        for j in range(n):
            acc += mass_matrix[i, j] * gain * (reference[j] - q_dot[j])
        out_tau[i] = min(max(acc, -effort_limit[i]), effort_limit[i])


@njit(cache=True, error_model="numpy", inline="always")
def _acceleration(model, q, qd, tau, local_R, local_p, w, v, aw, al, fn, fl, cm, ch, cJ, M, L, zeros, bias, rhs, out):
    dyn.local_frames(model, q, local_R, local_p)
    dyn.rnea(model, local_R, local_p, qd, zeros, True, w, v, aw, al, fn, fl, bias)
    dyn.crba(model, local_R, local_p, cm, ch, cJ, M)
    for i in range(q.shape[0]):
        rhs[i] = tau[i] - bias[i]
    return dyn.cholesky_solve(M, rhs, L, out)


@njit(cache=True, error_model="numpy", inline="always")
def _kinematic_rate(model, control, q, u, local_R, local_p, world_R, world_p, tool, J, out_qd):
    """A kinematic arm's joint speeds qd_ref(q, u) at q (its frames left in the scratch)."""
    dyn.local_frames(model, q, local_R, local_p)
    dyn.world_frames(local_R, local_p, world_R, world_p)
    dyn.tool_point(world_R, world_p, model.tool_p, tool)
    dyn.tool_jacobian(model, world_R, world_p, tool, J)
    joint_velocity_reference(J, u, q, model.velocity_limit, control.damping, control.null_gain, control.home, out_qd)


@njit(cache=True, error_model="numpy")
def _rollout_one(b, model, scene, control, thetas, start, dt, n_steps, record_every, out):
    """Rollout b of the batch (see ``rollout_serial``); its scratch is its own, so rollouts may run in parallel."""
    out_states, out_positions, out_velocities, out_actions, lengths, stop_step, stop_code = out
    kinematic, with_phase, conveyor_speed = control.kinematic, scene.with_phase, scene.conveyor_speed
    n = model.axis.shape[0]
    dim = out_states.shape[2]
    n_samples = out_states.shape[1]
    local_R, local_p, world_R, world_p = np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((n, 3, 3)), np.empty((n, 3))
    w, v, aw, al, fn, fl = (np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)),
                            np.empty((n, 3)), np.empty((n, 3)))
    cm, ch, cJ, M, L = np.empty(n), np.empty((n, 3)), np.empty((n, 3, 3)), np.empty((n, n)), np.zeros((n, n))
    zeros, bias, rhs, g_torque = np.zeros(n), np.empty(n), np.empty(n), np.empty(n)
    tool, J, points = np.empty(3), np.empty((3, n)), np.empty((n + 2, 3))
    tau, u, reference = np.empty(n), np.empty(3), np.empty(n)
    x, stage, k1, k2, k3, k4 = (np.empty(dim), np.empty(dim), np.empty(dim), np.empty(dim), np.empty(dim),
                                np.empty(dim))
    acc, stage_tool, stage_J, q_dot = np.empty(n), np.empty(3), np.empty((3, n)), np.empty(n)
    theta = thetas[b]
    for i in range(dim):
        x[i] = start[i]
    sample = 0
    stop_step[b] = -1
    stop_code[b] = 0
    dyn.local_frames(model, x[:n], local_R, local_p)
    dyn.world_frames(local_R, local_p, world_R, world_p)
    dyn.tool_point(world_R, world_p, model.tool_p, tool)
    for k in range(n_steps + 1):
        dyn.tool_jacobian(model, world_R, world_p, tool, J)
        for r in range(3):
            s_feature = x[dim - 1] if with_phase else 0.0
            if with_phase:
                u[r] = theta[r, 0] * tool[0] + theta[r, 1] * tool[1] + theta[r, 2] * tool[2] \
                    + theta[r, 3] * s_feature + theta[r, 4]
            else:
                u[r] = theta[r, 0] * tool[0] + theta[r, 1] * tool[1] + theta[r, 2] * tool[2] + theta[r, 3]
        joint_velocity_reference(J, u, x[:n], model.velocity_limit, control.damping, control.null_gain, control.home,
                                 reference)
        if k % record_every == 0 and sample < n_samples:
            for i in range(dim):
                out_states[b, sample, i] = x[i]
            for r in range(3):
                out_positions[b, sample, r] = tool[r]
                speed = 0.0
                for i in range(n):
                    speed += J[r, i] * (reference[i] if kinematic else x[n + i])
                out_velocities[b, sample, r] = speed
                out_actions[b, sample, r] = u[r]
            sample += 1
        if k == n_steps:
            break
        ok = True
        if kinematic:
            # RK4 of q' = qd_ref(q, u) with u held; the first stage is the reference at x.
            for i in range(n):
                k1[i] = reference[i]
            if with_phase:
                k1[dim - 1] = conveyor_speed
            for which in range(1, 4):
                h = dt if which == 3 else 0.5 * dt
                prev = k1 if which == 1 else (k2 if which == 2 else k3)
                stage_out = k2 if which == 1 else (k3 if which == 2 else k4)
                for i in range(dim):
                    stage[i] = x[i] + h * prev[i]
                _kinematic_rate(model, control, stage[:n], u, local_R, local_p, world_R, world_p, stage_tool, stage_J,
                                acc)
                for i in range(n):
                    stage_out[i] = acc[i]
                if with_phase:
                    stage_out[dim - 1] = conveyor_speed
        else:
            # The controller, once per step. local_R and world_R hold x's rotations (from the safety
            # check of the step before), and RK4's first stage is at x too: its M and rotations are
            # reused, and g(q) comes from the composites the mass matrix leaves.
            dyn.crba(model, local_R, local_p, cm, ch, cJ, M)
            dyn.gravity_from_composites(model, world_R, cm, ch, g_torque)
            held_torque(reference, x[n:2 * n], M, g_torque, model.effort_limit, control.gain, tau)
            dyn.rnea(model, local_R, local_p, x[n:2 * n], zeros, True, w, v, aw, al, fn, fl, bias)
            for i in range(n):
                rhs[i] = tau[i] - bias[i]
            ok = dyn.cholesky_solve(M, rhs, L, acc)
            for i in range(n):
                k1[i] = x[n + i]
                k1[n + i] = acc[i]
            if with_phase:
                k1[dim - 1] = conveyor_speed
            for which in range(1, 4):
                h = dt if which == 3 else 0.5 * dt
                prev = k1 if which == 1 else (k2 if which == 2 else k3)
                stage_out = k2 if which == 1 else (k3 if which == 2 else k4)
                for i in range(dim):
                    stage[i] = x[i] + h * prev[i]
                ok = ok and _acceleration(model, stage[:n], stage[n:2 * n], tau, local_R, local_p, w, v, aw, al, fn,
                                          fl, cm, ch, cJ, M, L, zeros, bias, rhs, acc)
                for i in range(n):
                    stage_out[i] = stage[n + i]
                    stage_out[n + i] = acc[i]
                if with_phase:
                    stage_out[dim - 1] = conveyor_speed
        for i in range(dim):
            stage[i] = x[i] + dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        code = 0 if ok else DIVERGED
        if code == 0:
            dyn.local_frames(model, stage[:n], local_R, local_p)
            dyn.world_frames(local_R, local_p, world_R, world_p)
            dyn.tool_point(world_R, world_p, model.tool_p, tool)
            chain_points(world_p, tool, points)
            # A kinematic arm's speeds are its commanded ones, within their limits by construction.
            for i in range(n):
                q_dot[i] = 0.0 if kinematic else stage[n + i]
            code = safety_code(model, scene, control.speed_tolerance, stage[:n], q_dot, points)
        if code != 0:
            stop_step[b] = k + 1
            stop_code[b] = code
            break
        for i in range(dim):
            x[i] = stage[i]
    lengths[b] = sample
    # Freeze a stopped rollout at its last valid sample so the batch arrays stay finite.
    for s in range(sample, n_samples):
        for i in range(dim):
            out_states[b, s, i] = out_states[b, sample - 1, i]
        for r in range(3):
            out_positions[b, s, r] = out_positions[b, sample - 1, r]
            out_velocities[b, s, r] = 0.0
            out_actions[b, s, r] = 0.0


@njit(cache=True, error_model="numpy")
def rollout_serial(model, scene, control, thetas, start, dt, n_steps, record_every, out):
    """Rolls out B tool-velocity policies from one start, one after another, into preallocated outputs.

    Args:
        model: the chain (``chain_dynamics.ChainModel``); scene: a ``ChainScene``; control: a
            ``ChainControl``.
        thetas: (B, 3, S); start: (D,) with D = 2n (n for a kinematic arm) (+ 1 with the phase).
        dt: the control period (s); n_steps: control steps; record_every: steps between samples.
        out: (states (B, T, D), positions, velocities, actions (B, T, 3), lengths, stop_step,
            stop_code (B,) ints) with T = n_steps // record_every + 1, filled in place.
    """
    for b in range(thetas.shape[0]):
        _rollout_one(b, model, scene, control, thetas, start, dt, n_steps, record_every, out)


@njit(cache=True, error_model="numpy", parallel=True)
def rollout_parallel(model, scene, control, thetas, start, dt, n_steps, record_every, out):
    """``rollout_serial`` with the batch spread over all cores; each rollout's arithmetic is identical."""
    for b in prange(thetas.shape[0]):
        _rollout_one(b, model, scene, control, thetas, start, dt, n_steps, record_every, out)


#: Batches at least this large are spread over cores; below it threads cost more than they save.
PARALLEL_FROM = 4
_PARALLEL_LAUNCH = threading.Lock()


def rollout(model, scene, control, thetas, start, dt, n_steps, record_every, out):
    """Runs ``rollout_serial`` or, for a batch of ``PARALLEL_FROM`` or more, ``rollout_parallel``."""
    if thetas.shape[0] >= PARALLEL_FROM:
        # Where numba falls back to its workqueue threading layer, two Python threads launching
        # parallel kernels at once abort the process (as for the planar arm): one launch at a time.
        with _PARALLEL_LAUNCH:
            rollout_parallel(model, scene, control, thetas, start, dt, n_steps, record_every, out)
    else:
        rollout_serial(model, scene, control, thetas, start, dt, n_steps, record_every, out)
