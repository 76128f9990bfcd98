"""Compiled RK4 rollouts of the two-link arm under a linear end-effector-force policy.

This is the hot path of the suite: every reproduction a student watches, every in-silico
participant and every power simulation runs through it. The controller runs at 1 kHz; at
each sample k it computes the joint torque ``tau_k = J(q_k)^T u_k`` (plus ``g(q_k)`` under
gravity compensation) from the policy ``u_k = Theta phi(x_k)``,
``phi = (r1, r2, r1dot, r2dot, 1)``, and holds it over the 1 ms step, which is integrated
with classical RK4. Held this way the result matches MuJoCo's RK4 with ``qfrc_applied``
(see benchmarks/bench_core.py). The loops are scalar on purpose: a 2-DoF arm is far too
small for array operations to pay off, and numba compiles the scalar code to a few hundred
nanoseconds a step.
"""

from __future__ import annotations

import math
import threading

import numpy as np
from numba import njit, prange


@njit(cache=True, fastmath=False)
def _acceleration(p, q1, q2, qd1, qd2, tau1, tau2):
    l1, m1, m2, lc1, lc2, i1, i2, g = p[0], p[2], p[3], p[4], p[5], p[6], p[7], p[8]
    c2 = math.cos(q2)
    s2 = math.sin(q2)
    m22 = m2 * lc2 * lc2 + i2
    m12 = m22 + m2 * l1 * lc2 * c2
    m11 = m1 * lc1 * lc1 + i1 + m2 * (l1 * l1 + 2.0 * l1 * lc2 * c2) + m22
    h = m2 * l1 * lc2 * s2
    c12 = math.cos(q1 + q2)
    g2 = m2 * lc2 * g * c12
    g1 = (m1 * lc1 + m2 * l1) * g * math.cos(q1) + g2
    b1 = tau1 - (-h * qd2 * qd1 - h * (qd1 + qd2) * qd2) - g1
    b2 = tau2 - (h * qd1 * qd1) - g2
    det = m11 * m22 - m12 * m12
    return (m22 * b1 - m12 * b2) / det, (m11 * b2 - m12 * b1) / det


@njit(cache=True)
def _policy_torque(p, theta, compensate, q1, q2, qd1, qd2):
    l1, l2, m1, m2, lc1, lc2, g = p[0], p[1], p[2], p[3], p[4], p[5], p[8]
    s1, c1 = math.sin(q1), math.cos(q1)
    s12, c12 = math.sin(q1 + q2), math.cos(q1 + q2)
    j11 = -l1 * s1 - l2 * s12
    j12 = -l2 * s12
    j21 = l1 * c1 + l2 * c12
    j22 = l2 * c12
    r1 = l1 * c1 + l2 * c12
    r2 = l1 * s1 + l2 * s12
    v1 = j11 * qd1 + j12 * qd2
    v2 = j21 * qd1 + j22 * qd2
    u1 = theta[0, 0] * r1 + theta[0, 1] * r2 + theta[0, 2] * v1 + theta[0, 3] * v2 + theta[0, 4]
    u2 = theta[1, 0] * r1 + theta[1, 1] * r2 + theta[1, 2] * v1 + theta[1, 3] * v2 + theta[1, 4]
    tau1 = j11 * u1 + j21 * u2
    tau2 = j12 * u1 + j22 * u2
    if compensate:
        g2 = m2 * lc2 * g * c12
        tau1 += (m1 * lc1 + m2 * l1) * g * c1 + g2
        tau2 += g2
    return u1, u2, tau1, tau2


@njit(cache=True)
def _rollout_one(b, thetas, start, params, compensate, dt, n_steps, record_every, max_joint_speed,
                 out_states, out_positions, out_velocities, out_actions, lengths, diverged_step):
    n_samples = out_states.shape[1]
    theta = thetas[b]
    l1, l2 = params[0], params[1]
    q1, q2, qd1, qd2 = start[0], start[1], start[2], start[3]
    sample = 0
    diverged_step[b] = -1
    for k in range(n_steps + 1):
        u1, u2, tau1, tau2 = _policy_torque(params, theta, compensate, q1, q2, qd1, qd2)
        if k % record_every == 0 and sample < n_samples:
            out_states[b, sample, 0] = q1
            out_states[b, sample, 1] = q2
            out_states[b, sample, 2] = qd1
            out_states[b, sample, 3] = qd2
            s1, c1, s12, c12 = math.sin(q1), math.cos(q1), math.sin(q1 + q2), math.cos(q1 + q2)
            out_positions[b, sample, 0] = l1 * c1 + l2 * c12
            out_positions[b, sample, 1] = l1 * s1 + l2 * s12
            out_velocities[b, sample, 0] = (-l1 * s1 - l2 * s12) * qd1 - l2 * s12 * qd2
            out_velocities[b, sample, 1] = (l1 * c1 + l2 * c12) * qd1 + l2 * c12 * qd2
            out_actions[b, sample, 0] = u1
            out_actions[b, sample, 1] = u2
            sample += 1
        if k == n_steps:
            break
        a1, a2 = _acceleration(params, q1, q2, qd1, qd2, tau1, tau2)
        k1q1, k1q2, k1v1, k1v2 = qd1, qd2, a1, a2
        h = 0.5 * dt
        a1, a2 = _acceleration(params, q1 + h * k1q1, q2 + h * k1q2, qd1 + h * k1v1, qd2 + h * k1v2, tau1, tau2)
        k2q1, k2q2, k2v1, k2v2 = qd1 + h * k1v1, qd2 + h * k1v2, a1, a2
        a1, a2 = _acceleration(params, q1 + h * k2q1, q2 + h * k2q2, qd1 + h * k2v1, qd2 + h * k2v2, tau1, tau2)
        k3q1, k3q2, k3v1, k3v2 = qd1 + h * k2v1, qd2 + h * k2v2, a1, a2
        a1, a2 = _acceleration(params, q1 + dt * k3q1, q2 + dt * k3q2, qd1 + dt * k3v1, qd2 + dt * k3v2,
                               tau1, tau2)
        k4q1, k4q2, k4v1, k4v2 = qd1 + dt * k3v1, qd2 + dt * k3v2, a1, a2
        w = dt / 6.0
        n1 = q1 + w * (k1q1 + 2.0 * k2q1 + 2.0 * k3q1 + k4q1)
        n2 = q2 + w * (k1q2 + 2.0 * k2q2 + 2.0 * k3q2 + k4q2)
        n3 = qd1 + w * (k1v1 + 2.0 * k2v1 + 2.0 * k3v1 + k4v1)
        n4 = qd2 + w * (k1v2 + 2.0 * k2v2 + 2.0 * k3v2 + k4v2)
        if not (math.isfinite(n1) and math.isfinite(n2) and abs(n3) <= max_joint_speed
                and abs(n4) <= max_joint_speed):
            diverged_step[b] = k + 1
            break
        q1, q2, qd1, qd2 = n1, n2, n3, n4
    lengths[b] = sample
    # Freeze a stopped rollout at its last valid sample so the batch arrays stay finite.
    for s in range(sample, n_samples):
        for i in range(4):
            out_states[b, s, i] = out_states[b, sample - 1, i]
        for i in range(2):
            out_positions[b, s, i] = out_positions[b, sample - 1, i]
            out_velocities[b, s, i] = 0.0
            out_actions[b, s, i] = 0.0


@njit(cache=True)
def rollout_serial(thetas, start, params, compensate, dt, n_steps, record_every, max_joint_speed,
                   out_states, out_positions, out_velocities, out_actions, lengths, diverged_step):
    """Rolls out B policies from one start state one after another, into preallocated outputs.

    Args:
        thetas: (B, 2, 5) policy parameters.
        start: (4,) initial state (q1, q2, qd1, qd2).
        params: (9,) ``ArmParameters.as_array()``.
        compensate: add g(q_k) to the held torque.
        dt: step in seconds; n_steps: number of steps; record_every: steps between samples.
        max_joint_speed: a joint speed above this (rad/s) counts as divergence.
        out_states (B, T, 4), out_positions (B, T, 2), out_velocities (B, T, 2), out_actions (B, T, 2)
            with T = n_steps // record_every + 1.
        lengths: (B,) int, receives the number of valid samples.
        diverged_step: (B,) int, receives the step at which divergence was found, or -1.
    """
    for b in range(thetas.shape[0]):
        _rollout_one(b, thetas, start, params, compensate, dt, n_steps, record_every, max_joint_speed,
                     out_states, out_positions, out_velocities, out_actions, lengths, diverged_step)


@njit(cache=True, parallel=True)
def rollout_parallel(thetas, start, params, compensate, dt, n_steps, record_every, max_joint_speed,
                     out_states, out_positions, out_velocities, out_actions, lengths, diverged_step):
    """``rollout_serial`` with the batch spread over all cores; each rollout's arithmetic is identical."""
    for b in prange(thetas.shape[0]):
        _rollout_one(b, thetas, start, params, compensate, dt, n_steps, record_every, max_joint_speed,
                     out_states, out_positions, out_velocities, out_actions, lengths, diverged_step)


#: Batches at least this large are spread over cores; below it threads cost more than they save.
PARALLEL_FROM = 8
_PARALLEL_LAUNCH = threading.Lock()


def rollout(thetas, start, params, compensate, dt, n_steps, record_every, max_joint_speed):
    """Allocates the outputs and runs the serial or parallel kernel.

    Returns:
        (states, positions, velocities, actions, lengths, diverged_step) as described above.
    """
    batch, n_samples = thetas.shape[0], n_steps // record_every + 1
    outputs = (np.empty((batch, n_samples, 4)), np.empty((batch, n_samples, 2)), np.empty((batch, n_samples, 2)),
               np.empty((batch, n_samples, 2)), np.empty(batch, dtype=np.int64), np.empty(batch, dtype=np.int64))
    if batch >= PARALLEL_FROM:
        # Where numba falls back to its workqueue threading layer (no OpenMP or TBB), two Python
        # threads launching parallel kernels at once abort the process; one launch at a time.
        with _PARALLEL_LAUNCH:
            rollout_parallel(thetas, start, params, compensate, dt, n_steps, record_every, max_joint_speed, *outputs)
    else:
        rollout_serial(thetas, start, params, compensate, dt, n_steps, record_every, max_joint_speed, *outputs)
    return outputs
