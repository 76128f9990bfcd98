"""Compiled rollouts of a serial-chain arm under a linear tool policy: the chain engine.

A rollout takes three structures: the chain (``chain_dynamics.ChainModel``: kinematics,
inertias, limits), the scene (``ChainScene``: the table, the conveyor, which capsules may
collide) and the controller (``ChainControl``). Nothing in here knows which arm it moves.

The controller runs at 1 kHz. At each sample k the policy gives (by default) the tool's velocity
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

Or, with ``ChainControl.force_control`` (the paper's simulated arm), the policy gives the tool's
force and the torque ``tau_k = J(q_k)^T u_k`` (plus ``g(q_k)`` under gravity compensation) is held
over the step, integrated with RK4 through the forward dynamics; the features may then carry the
tool's velocity, ``phi = (r, rdot, 1)``. Positions, velocities and actions are in the task space
(``ChainControl.task``: the base frame's axes, or a plane's two). A chain of two parallel
turning joints so controlled, with no table or collision pair to check, takes a fast path with
the same arithmetic in scalars (``planar_pair``, below).

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
    task: (R, 3) the task space's axes in the base frame (rows): the policy's positions,
    velocities and actions are in these coordinates (the identity for an arm taught in space, the
    plane's two axes for a planar one); force_control: the action is the tool's force, held as
    ``tau = J^T P^T u`` (the paper's controller) instead of a velocity through the velocity loop;
    gravity_compensation: a force-controlled arm adds g(q_k) to its held torque (a velocity loop
    always does); velocity_features: the features carry the tool's velocity, (P r, P rdot, 1)
    (a dynamic arm's: a kinematic arm's velocity follows from its action).
    """

    gain: float
    damping: float
    speed_tolerance: float
    null_gain: float
    home: np.ndarray
    kinematic: bool
    task: np.ndarray
    force_control: bool
    gravity_compensation: bool
    velocity_features: bool


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
def _freeze(b, sample, out):
    """Rollout b ends after ``sample`` samples: freeze it at its last valid one so the batch arrays stay finite."""
    out_states, out_positions, out_velocities, out_actions, lengths = out[0], out[1], out[2], out[3], out[4]
    lengths[b] = sample
    for s in range(sample, out_states.shape[1]):
        for i in range(out_states.shape[2]):
            out_states[b, s, i] = out_states[b, sample - 1, i]
        for r in range(out_positions.shape[2]):
            out_positions[b, s, r] = out_positions[b, sample - 1, r]
            out_velocities[b, s, r] = 0.0
            out_actions[b, s, r] = 0.0


@njit(cache=True, error_model="numpy", inline="always")
def force_torque(J, force, gravity_torque, compensate, effort_limit, out_tau):
    """tau = J^T F (+ g(q) under gravity compensation), each joint's clipped to its effort limit."""
    for i in range(J.shape[1]):
        acc = J[0, i] * force[0] + J[1, i] * force[1] + J[2, i] * force[2]
        if compensate:
            acc += gravity_torque[i]
        out_tau[i] = min(max(acc, -effort_limit[i]), effort_limit[i])


@njit(cache=True, error_model="numpy", inline="always")
def _in_task(task, in_space, r, vector):
    """Coordinate r of a base-frame vector (3,) in the task space (the vector's own when the task is the base frame)."""
    if in_space:
        return vector[r]
    return task[r, 0] * vector[0] + task[r, 1] * vector[1] + task[r, 2] * vector[2]


@njit(cache=True, error_model="numpy", inline="always")
def tool_velocity(J, qd, out):
    """J qd: the tool point's velocity (3,) in the base frame."""
    for r in range(3):
        acc = 0.0
        for i in range(J.shape[1]):
            acc += J[r, i] * qd[i]
        out[r] = acc


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
    # local_p starts as the joints' placements: local_frames writes only sliding joints' rows
    local_R, local_p = np.empty((n, 3, 3)), model.placement_p.copy()
    world_R, world_p = np.empty((n, 3, 3)), np.empty((n, 3))
    w, v, aw, al, fn, fl = (np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)),
                            np.empty((n, 3)), np.empty((n, 3)))
    cm, ch, cJ, M, L = np.empty(n), np.empty((n, 3)), np.empty((n, 3, 3)), np.empty((n, n)), np.zeros((n, n))
    zeros, bias, rhs, g_torque = np.zeros(n), np.empty(n), np.empty(n), np.empty(n)
    tool, J, points = np.empty(3), np.empty((3, n)), np.empty((n + 2, 3))
    task, force_control, velocity_features = control.task, control.force_control, control.velocity_features
    n_task, n_features = task.shape[0], thetas.shape[2]
    # The task space is the base frame (every arm taught in space): its coordinates are the base's own.
    in_space = n_task == 3
    for r in range(n_task):
        for c in range(3):
            in_space = in_space and task[r, c] == (1.0 if r == c else 0.0)
    tau, u, reference = np.empty(n), np.empty(n_task), np.empty(n)
    phi, command, tool_v = np.empty(n_features), np.empty(3), np.empty(3)
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
        if not kinematic:
            tool_velocity(J, x[n:2 * n], tool_v)
        # phi(x) = (P r, [P rdot], [s], 1) and u = Theta phi, the command P^T u in the base frame
        for r in range(n_task):
            phi[r] = _in_task(task, in_space, r, tool)
            if velocity_features:
                phi[n_task + r] = _in_task(task, in_space, r, tool_v)
        if with_phase:
            phi[n_features - 2] = x[dim - 1]
        phi[n_features - 1] = 1.0
        for r in range(n_task):
            acc_u = 0.0
            for j in range(n_features):
                acc_u += theta[r, j] * phi[j]
            u[r] = acc_u
        for c in range(3):
            if in_space:
                command[c] = u[c]
            else:
                acc_u = 0.0
                for r in range(n_task):
                    acc_u += task[r, c] * u[r]
                command[c] = acc_u
        if not force_control:
            joint_velocity_reference(J, command, x[:n], model.velocity_limit, control.damping, control.null_gain,
                                     control.home, reference)
            if kinematic:
                tool_velocity(J, reference, tool_v)
        if k % record_every == 0 and sample < n_samples:
            for i in range(dim):
                out_states[b, sample, i] = x[i]
            for r in range(n_task):
                out_positions[b, sample, r] = phi[r]
                out_velocities[b, sample, r] = _in_task(task, in_space, r, tool_v)
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
            if force_control:
                force_torque(J, command, g_torque, control.gravity_compensation, model.effort_limit, tau)
            else:
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
    _freeze(b, sample, out)


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
        # prange's index is unsigned: as int64 the call is rollout_serial's, compiled (and cached) once
        _rollout_one(np.int64(b), model, scene, control, thetas, start, dt, n_steps, record_every, out)


# -- the fast path of a planar pair --------------------------------------------------------------------
# A chain of two turning joints whose axes stay parallel (the second's axis, carried by the first
# joint, is the first's), force-controlled in the plane they turn in, with no table or collision
# pair to check: the paper's arm. Its rigid-body dynamics reduce to a dozen scalars, and the
# rollout runs on those in registers at about a twentieth of the general algorithms' cost per step
# (0.11 against 2.2 us), which keeps the paper's arm as fast as MuJoCo's ratio asks
# (benchmarks/bench_core.py). It computes the same M, C qd + g and J as they do
# (tests/core/test_arm_dynamics.py compares the two paths' rollouts to 1e-12), so it is a
# specialisation chosen by the model's data, not another model.
#
# In the plane (basis e1, e2 with e1 x e2 the axis a) body 1's vectors turn with q1 and body 2's
# with q1 + q2. With d the second joint's offset, c1, c2 the centres of mass, t the tool point and
# w1 = m1 c1 + m2 d, w2 = m2 c2 the first moments (all at q = 0):
#   M11 = k11 + 2 P, M12 = k22 + P, M22 = k22, P(q2) = A cos q2 - B sin q2 (A = m2 d.c2, B = m2 d x c2),
#   C qd = P' (2 qd1 qd2 + qd2^2, -qd1^2), g2 = G2 cos(q1 + q2 - phi2), g1 = G1 cos(q1 - phi1) + g2
# with G cos(phi) = gp x w, G sin(phi) = gp . w for the gravity gp in the plane (one cosine each:
# a branch or a sine for the tilted case costs a quarter of the step).
_K11, _K22, _A, _B, _G1, _PHI1, _G2, _PHI2 = range(8)
_O, _D, _T, _TASK, _OFFSET, _LOWER, _UPPER, _SPEED, _EFFORT = 8, 10, 12, 14, 18, 20, 22, 24, 26
_PLANAR_SIZE = 28


# Small products written out: numba compiles `@` and np.linalg through BLAS, which it takes from scipy,
# and the core install (numpy and numba, tests/install/smoke_core.py) has no scipy.
@njit(cache=True, inline="always")
def _dot(u, v):
    total = 0.0
    for k in range(u.shape[0]):
        total += u[k] * v[k]
    return total


@njit(cache=True, inline="always")
def _matvec(M, v):
    out = np.empty(M.shape[0])
    for i in range(M.shape[0]):
        out[i] = _dot(M[i], v)
    return out


@njit(cache=True, inline="always")
def _matmul(A, B):
    out = np.empty((A.shape[0], B.shape[1]))
    for i in range(A.shape[0]):
        for j in range(B.shape[1]):
            total = 0.0
            for k in range(A.shape[1]):
                total += A[i, k] * B[k, j]
            out[i, j] = total
    return out


@njit(cache=True, error_model="numpy")
def planar_pair(model, scene, control, n_features):
    """The constants of the planar fast path (above) when it applies to this rollout, else an empty array.

    Compiled: the rollout's entry asks on every call, and numpy would cost more than a short rollout.
    """
    none = np.empty(0)
    if model.axis.shape[0] != 2 or model.prismatic[0] or model.prismatic[1] or not control.force_control \
            or control.kinematic or not control.velocity_features or control.task.shape[0] != 2 or n_features != 5 \
            or scene.with_phase or scene.pairs.shape[0] or (scene.first_table_point < 4
                                                            and scene.table_height > -np.inf):
        return none
    B0 = model.placement_R[0]
    B1 = _matmul(B0, model.placement_R[1])
    if np.max(np.abs(_matvec(model.placement_R[1], model.axis[1]) - model.axis[0])) > 1e-15:
        return none
    a = _matvec(B0, model.axis[0])
    # e1: the base's x (else y) in the plane; e2 = a x e1, so that a turn about a is a turn from e1 to e2
    e1 = np.array([1.0, 0.0, 0.0]) - a[0] * a
    if math.sqrt(_dot(e1, e1)) < 0.5:
        e1 = np.array([0.0, 1.0, 0.0]) - a[1] * a
    e1 = e1 / math.sqrt(_dot(e1, e1))
    e2 = np.cross(a, e1)
    plane = np.empty((2, 3))
    plane[0], plane[1] = e1, e2
    m1, m2 = model.mass[0], model.mass[1]
    o = _matvec(plane, model.placement_p[0])
    d, c1 = _matvec(plane, _matvec(B0, model.placement_p[1])), _matvec(plane, _matvec(B0, model.com[0]))
    c2, t = _matvec(plane, _matvec(B1, model.com[1])), _matvec(plane, _matvec(B1, model.tool_p))
    inertia1 = _dot(model.axis[0], _matvec(model.inertia[0], model.axis[0]))
    inertia2 = _dot(model.axis[1], _matvec(model.inertia[1], model.axis[1]))
    k22 = inertia2 + m2 * (c2[0] * c2[0] + c2[1] * c2[1])
    k11 = inertia1 + m1 * (c1[0] * c1[0] + c1[1] * c1[1]) + m2 * (d[0] * d[0] + d[1] * d[1]) + k22
    gp = _matvec(plane, model.gravity)
    w1, w2 = m1 * c1 + m2 * d, m2 * c2
    # The tool's height along a is fixed; the task's coordinates of the tool are offset + T (x, y).
    height = _dot(a, model.placement_p[0] + _matvec(B0, model.placement_p[1]) + _matvec(B1, model.tool_p))
    T = _matmul(control.task, plane.T)
    offset = _matvec(control.task, a) * height
    p = np.empty(_PLANAR_SIZE)
    p[_K11], p[_K22] = k11, k22
    p[_A], p[_B] = m2 * (d[0] * c2[0] + d[1] * c2[1]), m2 * (d[0] * c2[1] - d[1] * c2[0])
    for index, w in ((_G1, w1), (_G2, w2)):
        across, along = gp[0] * w[1] - gp[1] * w[0], gp[0] * w[0] + gp[1] * w[1]
        p[index], p[index + 1] = math.hypot(across, along), math.atan2(along, across)
    for k in range(2):
        p[_O + k], p[_D + k], p[_T + k], p[_OFFSET + k] = o[k], d[k], t[k], offset[k]
        p[_TASK + k], p[_TASK + 2 + k] = T[0, k], T[1, k]
        p[_LOWER + k], p[_UPPER + k] = model.lower[k], model.upper[k]
        p[_SPEED + k] = model.velocity_limit[k] * (1.0 + control.speed_tolerance)
        p[_EFFORT + k] = model.effort_limit[k]
    return p


@njit(cache=True, error_model="numpy", inline="always")
def _planar_gravity(p, q1, q2):
    g2 = p[_G2] * math.cos(q1 + q2 - p[_PHI2])
    return p[_G1] * math.cos(q1 - p[_PHI1]) + g2, g2


@njit(cache=True, error_model="numpy", inline="always")
def _planar_acceleration(p, q1, q2, qd1, qd2, tau1, tau2):
    c2, s2 = math.cos(q2), math.sin(q2)
    k11, k22, A, B = p[_K11], p[_K22], p[_A], p[_B]
    P = A * c2 - B * s2
    dP = -A * s2 - B * c2
    m11, m12 = k11 + 2.0 * P, k22 + P
    g1, g2 = _planar_gravity(p, q1, q2)
    b1 = tau1 - dP * (2.0 * qd1 * qd2 + qd2 * qd2) - g1
    b2 = tau2 + dP * qd1 * qd1 - g2
    det = m11 * k22 - m12 * m12
    return (k22 * b1 - m12 * b2) / det, (m11 * b2 - m12 * b1) / det


@njit(cache=True, error_model="numpy")
def _planar_rollout_one(b, p, compensate, thetas, start, dt, n_steps, record_every, out):
    """``_rollout_one`` for a planar pair (the fast path above), its state in scalars."""
    out_states, out_positions, out_velocities, out_actions, lengths, stop_step, stop_code = out
    n_samples = out_states.shape[1]
    theta = thetas[b]
    q1, q2, qd1, qd2 = start[0], start[1], start[2], start[3]
    sample = 0
    stop_step[b] = -1
    stop_code[b] = 0
    for k in range(n_steps + 1):
        c1, s1, c12, s12 = math.cos(q1), math.sin(q1), math.cos(q1 + q2), math.sin(q1 + q2)
        # the tool t turned by q1 + q2 and the elbow's offset d by q1; J's columns are their perpendiculars
        tx, ty = c12 * p[_T] - s12 * p[_T + 1], s12 * p[_T] + c12 * p[_T + 1]
        dx, dy = c1 * p[_D] - s1 * p[_D + 1], s1 * p[_D] + c1 * p[_D + 1]
        j12, j22 = -ty, tx
        j11, j21 = j12 - dy, j22 + dx
        x, y = p[_O] + dx + tx, p[_O + 1] + dy + ty
        vx, vy = j11 * qd1 + j12 * qd2, j21 * qd1 + j22 * qd2
        r1 = p[_OFFSET] + p[_TASK] * x + p[_TASK + 1] * y
        r2 = p[_OFFSET + 1] + p[_TASK + 2] * x + p[_TASK + 3] * y
        v1 = p[_TASK] * vx + p[_TASK + 1] * vy
        v2 = p[_TASK + 2] * vx + p[_TASK + 3] * vy
        u1 = theta[0, 0] * r1 + theta[0, 1] * r2 + theta[0, 2] * v1 + theta[0, 3] * v2 + theta[0, 4]
        u2 = theta[1, 0] * r1 + theta[1, 1] * r2 + theta[1, 2] * v1 + theta[1, 3] * v2 + theta[1, 4]
        if k % record_every == 0 and sample < n_samples:
            out_states[b, sample, 0] = q1
            out_states[b, sample, 1] = q2
            out_states[b, sample, 2] = qd1
            out_states[b, sample, 3] = qd2
            out_positions[b, sample, 0] = r1
            out_positions[b, sample, 1] = r2
            out_velocities[b, sample, 0] = v1
            out_velocities[b, sample, 1] = v2
            out_actions[b, sample, 0] = u1
            out_actions[b, sample, 1] = u2
            sample += 1
        if k == n_steps:
            break
        # the force in the plane T^T u, held as tau = J^T F (+ g(q_k))
        fx, fy = p[_TASK] * u1 + p[_TASK + 2] * u2, p[_TASK + 1] * u1 + p[_TASK + 3] * u2
        tau1, tau2 = j11 * fx + j21 * fy, j12 * fx + j22 * fy
        if compensate:
            g1, g2 = _planar_gravity(p, q1, q2)
            tau1 += g1
            tau2 += g2
        tau1 = min(max(tau1, -p[_EFFORT]), p[_EFFORT])
        tau2 = min(max(tau2, -p[_EFFORT + 1]), p[_EFFORT + 1])
        h = 0.5 * dt
        a1, a2 = _planar_acceleration(p, q1, q2, qd1, qd2, tau1, tau2)
        k1q1, k1q2, k1v1, k1v2 = qd1, qd2, a1, a2
        a1, a2 = _planar_acceleration(p, q1 + h * k1q1, q2 + h * k1q2, qd1 + h * k1v1, qd2 + h * k1v2, tau1, tau2)
        k2q1, k2q2, k2v1, k2v2 = qd1 + h * k1v1, qd2 + h * k1v2, a1, a2
        a1, a2 = _planar_acceleration(p, q1 + h * k2q1, q2 + h * k2q2, qd1 + h * k2v1, qd2 + h * k2v2, tau1, tau2)
        k3q1, k3q2, k3v1, k3v2 = qd1 + h * k2v1, qd2 + h * k2v2, a1, a2
        a1, a2 = _planar_acceleration(p, q1 + dt * k3q1, q2 + dt * k3q2, qd1 + dt * k3v1, qd2 + dt * k3v2,
                                      tau1, tau2)
        k4q1, k4q2, k4v1, k4v2 = qd1 + dt * k3v1, qd2 + dt * k3v2, a1, a2
        w = dt / 6.0
        n1 = q1 + w * (k1q1 + 2.0 * k2q1 + 2.0 * k3q1 + k4q1)
        n2 = q2 + w * (k1q2 + 2.0 * k2q2 + 2.0 * k3q2 + k4q2)
        n3 = qd1 + w * (k1v1 + 2.0 * k2v1 + 2.0 * k3v1 + k4v1)
        n4 = qd2 + w * (k1v2 + 2.0 * k2v2 + 2.0 * k3v2 + k4v2)
        # safety_code's checks, in its order, for a scene without table or pairs
        code = 0
        if not (math.isfinite(n1) and math.isfinite(n2) and math.isfinite(n3) and math.isfinite(n4)):
            code = DIVERGED
        elif n1 < p[_LOWER] or n1 > p[_UPPER] or n2 < p[_LOWER + 1] or n2 > p[_UPPER + 1]:
            code = JOINT_LIMIT
        elif abs(n3) > p[_SPEED] or abs(n4) > p[_SPEED + 1]:
            code = JOINT_SPEED
        if code != 0:
            stop_step[b] = k + 1
            stop_code[b] = code
            break
        q1, q2, qd1, qd2 = n1, n2, n3, n4
    _freeze(b, sample, out)


@njit(cache=True, error_model="numpy")
def planar_rollout_serial(p, compensate, thetas, start, dt, n_steps, record_every, out):
    """``rollout_serial`` for a planar pair: p from ``planar_pair``."""
    for b in range(thetas.shape[0]):
        _planar_rollout_one(b, p, compensate, thetas, start, dt, n_steps, record_every, out)


@njit(cache=True, error_model="numpy", parallel=True)
def planar_rollout_parallel(p, compensate, thetas, start, dt, n_steps, record_every, out):
    """``planar_rollout_serial`` with the batch spread over all cores."""
    for b in prange(thetas.shape[0]):
        _planar_rollout_one(np.int64(b), p, compensate, thetas, start, dt, n_steps, record_every, out)  # as above


#: Batches at least this large are spread over cores; below it threads cost more than they save.
PARALLEL_FROM = 4
_PARALLEL_LAUNCH = threading.Lock()


def rollout(model, scene, control, thetas, start, dt, n_steps, record_every, out):
    """Runs ``rollout_serial`` or, for a batch of ``PARALLEL_FROM`` or more, ``rollout_parallel``.

    A planar pair (``planar_pair``) takes the fast path with the same arithmetic in scalars.
    """
    if control.kinematic and control.velocity_features:
        # A kinematic arm's state is q alone: the tool velocity its features would read is the last
        # step's command, not a measured velocity, so no skill can be taught through it.
        raise ValueError("control: velocity_features=True needs a dynamic arm (its state carries joint speeds); "
                         "got kinematic=True, whose state is the joint angles only")
    p = planar_pair(model, scene, control, thetas.shape[2])
    parallel = thetas.shape[0] >= PARALLEL_FROM
    if p.shape[0]:
        kernel = planar_rollout_parallel if parallel else planar_rollout_serial
        arguments = (p, control.gravity_compensation, thetas, start, dt, n_steps, record_every, out)
    else:
        kernel = rollout_parallel if parallel else rollout_serial
        arguments = (model, scene, control, thetas, start, dt, n_steps, record_every, out)
    if parallel:
        # Where numba falls back to its workqueue threading layer, two Python threads launching
        # parallel kernels at once abort the process: one launch at a time.
        with _PARALLEL_LAUNCH:
            kernel(*arguments)
    else:
        kernel(*arguments)
