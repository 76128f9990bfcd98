"""Compiled rigid-body algorithms for a serial chain of revolute and prismatic joints (numba).

Featherstone's algorithms in body-fixed frames: the recursive Newton-Euler algorithm (RNEA:
inverse dynamics, hence the bias forces C(q, qd) qd + g(q) and the gravity torque g(q)) and
the composite-rigid-body algorithm (CRBA: the mass matrix M(q)); forward dynamics solves
``M qdd = tau - C qd - g`` by Cholesky. For six joints this is a few thousand flops, cheaper
than the articulated-body algorithm's 6 x 6 articulated inertias, and every quantity the
controller needs (M for its velocity loop, g for gravity compensation) comes out of it too.

Conventions (as pinocchio's, which the tests compare with): body i's frame is joint i's frame
after the joint's rotation; a spatial motion vector is (angular, linear at the frame origin), a
spatial force (moment about the frame origin, force). The model is one structure, a
``ChainModel`` (a named tuple of arrays, which numba compiles against like any tuple) built by
``SerialChain`` (mt_widgets/core/serial_chain.py):

- placement_R (n, 3, 3), placement_p (n, 3): joint frame i in body i-1's frame (body -1: base);
- axis (n, 3): joint i's unit axis in its frame; prismatic (n,): 1 where joint i slides along
  its axis, 0 where it turns about it (revolute and continuous joints);
- mass (n,), com (n, 3), inertia (n, 3, 3): each body's mass, centre of mass and inertia about
  the centre of mass, in its frame;
- tool_R (3, 3), tool_p (3,): the tool frame in the last body's frame;
- gravity (3,): the gravitational acceleration in the base frame (m/s^2);
- lower, upper, velocity_limit, effort_limit (n,): the joints' limits (rad or m, per second, N m or N).

A configuration's local frames (``local_frames``: body i in body i-1's frame) are computed once
and shared by every algorithm of a step.

Scratch arrays are passed in, allocated once per rollout: allocating inside the kernels would
cost more than the arithmetic. The kernels are inlined into their callers (``inline="always"``):
a call passing some twenty arrays costs numba their reference counts, which measured about a
sixth of a rollout (benchmarks/bench_ur5.py: 50 -> 42 ms of CPU for 10,000 steps).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit


class ChainModel(NamedTuple):
    """A serial chain as the compiled kernels take it (see the module's docstring)."""

    placement_R: np.ndarray
    placement_p: np.ndarray
    axis: np.ndarray
    prismatic: np.ndarray
    mass: np.ndarray
    com: np.ndarray
    inertia: np.ndarray
    tool_R: np.ndarray
    tool_p: np.ndarray
    gravity: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    velocity_limit: np.ndarray
    effort_limit: np.ndarray


@njit(cache=True, error_model="numpy", inline="always")
def local_frames(model, q, out_R, out_p):
    """Body i in body i-1's frame: out_R[i] = placement_R[i] @ Rot(axis[i], q[i]) for a turning joint,
    out_p[i] = placement_p[i] + placement_R[i] @ (axis[i] q[i]) for a sliding one.

    A turning joint's origin does not move: out_p must start as a copy of ``model.placement_p``
    (its callers allocate it so), and only sliding joints' rows are written. Copying the rows on
    every call cost about 2 % of a UR5 rollout (benchmarks/bench_ur5.py).
    """
    placement_R, placement_p, axis, prismatic = model.placement_R, model.placement_p, model.axis, model.prismatic
    for i in range(q.shape[0]):
        P = placement_R[i]
        if prismatic[i]:
            x, y, z = axis[i, 0] * q[i], axis[i, 1] * q[i], axis[i, 2] * q[i]
            for row in range(3):
                out_p[i, row] = placement_p[i, row] + P[row, 0] * x + P[row, 1] * y + P[row, 2] * z
                for col in range(3):
                    out_R[i, row, col] = P[row, col]
            continue
        c, s = math.cos(q[i]), math.sin(q[i])
        t = 1.0 - c
        x, y, z = axis[i, 0], axis[i, 1], axis[i, 2]
        r00, r01, r02 = t * x * x + c, t * x * y - s * z, t * x * z + s * y
        r10, r11, r12 = t * x * y + s * z, t * y * y + c, t * y * z - s * x
        r20, r21, r22 = t * x * z - s * y, t * y * z + s * x, t * z * z + c
        for row in range(3):
            a, b, d = P[row, 0], P[row, 1], P[row, 2]
            out_R[i, row, 0] = a * r00 + b * r10 + d * r20
            out_R[i, row, 1] = a * r01 + b * r11 + d * r21
            out_R[i, row, 2] = a * r02 + b * r12 + d * r22


@njit(cache=True, error_model="numpy", inline="always")
def world_frames(local_R, local_p, world_R, world_p):
    """Each body's orientation and origin in the base frame from the local frames."""
    n = local_R.shape[0]
    for i in range(n):
        for row in range(3):
            if i == 0:
                world_p[i, row] = local_p[i, row]
                for col in range(3):
                    world_R[i, row, col] = local_R[i, row, col]
            else:
                acc = world_p[i - 1, row]
                for k in range(3):
                    acc += world_R[i - 1, row, k] * local_p[i, k]
                world_p[i, row] = acc
                for col in range(3):
                    acc = 0.0
                    for k in range(3):
                        acc += world_R[i - 1, row, k] * local_R[i, k, col]
                    world_R[i, row, col] = acc


@njit(cache=True, error_model="numpy", inline="always")
def tool_point(world_R, world_p, tool_p, out):
    """The tool frame's origin in the base frame (m)."""
    n = world_R.shape[0] - 1
    for row in range(3):
        out[row] = world_p[n, row] + world_R[n, row, 0] * tool_p[0] + world_R[n, row, 1] * tool_p[1] \
            + world_R[n, row, 2] * tool_p[2]


@njit(cache=True, error_model="numpy", inline="always")
def tool_jacobian(model, world_R, world_p, tool, out_J):
    """The 3 x n Jacobian of the tool point's position in the base frame: column i = z_i x (p - o_i)
    for a turning joint, z_i for a sliding one."""
    axis = model.axis
    for i in range(world_R.shape[0]):
        zx = world_R[i, 0, 0] * axis[i, 0] + world_R[i, 0, 1] * axis[i, 1] + world_R[i, 0, 2] * axis[i, 2]
        zy = world_R[i, 1, 0] * axis[i, 0] + world_R[i, 1, 1] * axis[i, 1] + world_R[i, 1, 2] * axis[i, 2]
        zz = world_R[i, 2, 0] * axis[i, 0] + world_R[i, 2, 1] * axis[i, 1] + world_R[i, 2, 2] * axis[i, 2]
        if model.prismatic[i]:
            out_J[0, i], out_J[1, i], out_J[2, i] = zx, zy, zz
            continue
        dx, dy, dz = tool[0] - world_p[i, 0], tool[1] - world_p[i, 1], tool[2] - world_p[i, 2]
        out_J[0, i] = zy * dz - zz * dy
        out_J[1, i] = zz * dx - zx * dz
        out_J[2, i] = zx * dy - zy * dx


@njit(cache=True, error_model="numpy", inline="always")
def rnea(model, local_R, local_p, qd, qdd, use_gravity, w, v, aw, al, fn, fl, out_tau):
    """Inverse dynamics: out_tau = M(q) qdd + C(q, qd) qd (+ g(q) when use_gravity).

    Gravity enters as an upward acceleration of the base (Featherstone's trick). A turning
    joint's motion subspace is (axis, 0), a sliding one's (0, axis).
    w, v, aw, al, fn, fl: (n, 3) scratch.
    """
    axis, mass, com, inertia, gravity, prismatic = (model.axis, model.mass, model.com, model.inertia, model.gravity,
                                                    model.prismatic)
    n = local_R.shape[0]
    for i in range(n):
        R = local_R[i]
        p = local_p[i]
        if i == 0:
            pw0 = pw1 = pw2 = 0.0
            pv0 = pv1 = pv2 = 0.0
            pa0 = pa1 = pa2 = 0.0
            if use_gravity:
                pl0, pl1, pl2 = -gravity[0], -gravity[1], -gravity[2]
            else:
                pl0 = pl1 = pl2 = 0.0
        else:
            pw0, pw1, pw2 = w[i - 1, 0], w[i - 1, 1], w[i - 1, 2]
            pv0, pv1, pv2 = v[i - 1, 0], v[i - 1, 1], v[i - 1, 2]
            pa0, pa1, pa2 = aw[i - 1, 0], aw[i - 1, 1], aw[i - 1, 2]
            pl0, pl1, pl2 = al[i - 1, 0], al[i - 1, 1], al[i - 1, 2]
        # linear parts moved to this body's origin: x + parent_angular x p
        tv0 = pv0 + pw1 * p[2] - pw2 * p[1]
        tv1 = pv1 + pw2 * p[0] - pw0 * p[2]
        tv2 = pv2 + pw0 * p[1] - pw1 * p[0]
        tl0 = pl0 + pa1 * p[2] - pa2 * p[1]
        tl1 = pl1 + pa2 * p[0] - pa0 * p[2]
        tl2 = pl2 + pa0 * p[1] - pa1 * p[0]
        ax0, ax1, ax2 = axis[i, 0], axis[i, 1], axis[i, 2]
        s0, s1, s2 = ax0 * qd[i], ax1 * qd[i], ax2 * qd[i]
        if prismatic[i]:
            # S = (0, a): the joint adds a qd to the linear velocity; its product term is w x a qd
            w0 = R[0, 0] * pw0 + R[1, 0] * pw1 + R[2, 0] * pw2
            w1 = R[0, 1] * pw0 + R[1, 1] * pw1 + R[2, 1] * pw2
            w2 = R[0, 2] * pw0 + R[1, 2] * pw1 + R[2, 2] * pw2
            v0 = R[0, 0] * tv0 + R[1, 0] * tv1 + R[2, 0] * tv2 + s0
            v1 = R[0, 1] * tv0 + R[1, 1] * tv1 + R[2, 1] * tv2 + s1
            v2 = R[0, 2] * tv0 + R[1, 2] * tv1 + R[2, 2] * tv2 + s2
            a0 = R[0, 0] * pa0 + R[1, 0] * pa1 + R[2, 0] * pa2
            a1 = R[0, 1] * pa0 + R[1, 1] * pa1 + R[2, 1] * pa2
            a2 = R[0, 2] * pa0 + R[1, 2] * pa1 + R[2, 2] * pa2
            l0 = R[0, 0] * tl0 + R[1, 0] * tl1 + R[2, 0] * tl2 + ax0 * qdd[i] + (w1 * s2 - w2 * s1)
            l1 = R[0, 1] * tl0 + R[1, 1] * tl1 + R[2, 1] * tl2 + ax1 * qdd[i] + (w2 * s0 - w0 * s2)
            l2 = R[0, 2] * tl0 + R[1, 2] * tl1 + R[2, 2] * tl2 + ax2 * qdd[i] + (w0 * s1 - w1 * s0)
        else:
            # rotate into this body's frame (R^T x)
            w0 = R[0, 0] * pw0 + R[1, 0] * pw1 + R[2, 0] * pw2 + ax0 * qd[i]
            w1 = R[0, 1] * pw0 + R[1, 1] * pw1 + R[2, 1] * pw2 + ax1 * qd[i]
            w2 = R[0, 2] * pw0 + R[1, 2] * pw1 + R[2, 2] * pw2 + ax2 * qd[i]
            v0 = R[0, 0] * tv0 + R[1, 0] * tv1 + R[2, 0] * tv2
            v1 = R[0, 1] * tv0 + R[1, 1] * tv1 + R[2, 1] * tv2
            v2 = R[0, 2] * tv0 + R[1, 2] * tv1 + R[2, 2] * tv2
            # velocity-product terms v x (S qd): angular w x a qd, linear v x a qd
            a0 = R[0, 0] * pa0 + R[1, 0] * pa1 + R[2, 0] * pa2 + ax0 * qdd[i] + (w1 * s2 - w2 * s1)
            a1 = R[0, 1] * pa0 + R[1, 1] * pa1 + R[2, 1] * pa2 + ax1 * qdd[i] + (w2 * s0 - w0 * s2)
            a2 = R[0, 2] * pa0 + R[1, 2] * pa1 + R[2, 2] * pa2 + ax2 * qdd[i] + (w0 * s1 - w1 * s0)
            l0 = R[0, 0] * tl0 + R[1, 0] * tl1 + R[2, 0] * tl2 + (v1 * s2 - v2 * s1)
            l1 = R[0, 1] * tl0 + R[1, 1] * tl1 + R[2, 1] * tl2 + (v2 * s0 - v0 * s2)
            l2 = R[0, 2] * tl0 + R[1, 2] * tl1 + R[2, 2] * tl2 + (v0 * s1 - v1 * s0)
        w[i, 0], w[i, 1], w[i, 2] = w0, w1, w2
        v[i, 0], v[i, 1], v[i, 2] = v0, v1, v2
        aw[i, 0], aw[i, 1], aw[i, 2] = a0, a1, a2
        al[i, 0], al[i, 1], al[i, 2] = l0, l1, l2
        m = mass[i]
        c0, c1, c2 = com[i, 0], com[i, 1], com[i, 2]
        inertia_i = inertia[i]
        # momentum h = I v: linear m (v + w x c), angular Ic w + c x linear
        hl0 = m * (v0 + w1 * c2 - w2 * c1)
        hl1 = m * (v1 + w2 * c0 - w0 * c2)
        hl2 = m * (v2 + w0 * c1 - w1 * c0)
        hn0 = inertia_i[0, 0] * w0 + inertia_i[0, 1] * w1 + inertia_i[0, 2] * w2 + c1 * hl2 - c2 * hl1
        hn1 = inertia_i[1, 0] * w0 + inertia_i[1, 1] * w1 + inertia_i[1, 2] * w2 + c2 * hl0 - c0 * hl2
        hn2 = inertia_i[2, 0] * w0 + inertia_i[2, 1] * w1 + inertia_i[2, 2] * w2 + c0 * hl1 - c1 * hl0
        # I a
        gl0 = m * (l0 + a1 * c2 - a2 * c1)
        gl1 = m * (l1 + a2 * c0 - a0 * c2)
        gl2 = m * (l2 + a0 * c1 - a1 * c0)
        gn0 = inertia_i[0, 0] * a0 + inertia_i[0, 1] * a1 + inertia_i[0, 2] * a2 + c1 * gl2 - c2 * gl1
        gn1 = inertia_i[1, 0] * a0 + inertia_i[1, 1] * a1 + inertia_i[1, 2] * a2 + c2 * gl0 - c0 * gl2
        gn2 = inertia_i[2, 0] * a0 + inertia_i[2, 1] * a1 + inertia_i[2, 2] * a2 + c0 * gl1 - c1 * gl0
        # f = I a + v x* (I v): angular w x hn + v x hl, linear w x hl
        fn[i, 0] = gn0 + (w1 * hn2 - w2 * hn1) + (v1 * hl2 - v2 * hl1)
        fn[i, 1] = gn1 + (w2 * hn0 - w0 * hn2) + (v2 * hl0 - v0 * hl2)
        fn[i, 2] = gn2 + (w0 * hn1 - w1 * hn0) + (v0 * hl1 - v1 * hl0)
        fl[i, 0] = gl0 + (w1 * hl2 - w2 * hl1)
        fl[i, 1] = gl1 + (w2 * hl0 - w0 * hl2)
        fl[i, 2] = gl2 + (w0 * hl1 - w1 * hl0)
    for i in range(n - 1, -1, -1):
        if prismatic[i]:
            out_tau[i] = axis[i, 0] * fl[i, 0] + axis[i, 1] * fl[i, 1] + axis[i, 2] * fl[i, 2]
        else:
            out_tau[i] = axis[i, 0] * fn[i, 0] + axis[i, 1] * fn[i, 1] + axis[i, 2] * fn[i, 2]
        if i > 0:
            R = local_R[i]
            p = local_p[i]
            r0 = R[0, 0] * fl[i, 0] + R[0, 1] * fl[i, 1] + R[0, 2] * fl[i, 2]
            r1 = R[1, 0] * fl[i, 0] + R[1, 1] * fl[i, 1] + R[1, 2] * fl[i, 2]
            r2 = R[2, 0] * fl[i, 0] + R[2, 1] * fl[i, 1] + R[2, 2] * fl[i, 2]
            fn[i - 1, 0] += R[0, 0] * fn[i, 0] + R[0, 1] * fn[i, 1] + R[0, 2] * fn[i, 2] + p[1] * r2 - p[2] * r1
            fn[i - 1, 1] += R[1, 0] * fn[i, 0] + R[1, 1] * fn[i, 1] + R[1, 2] * fn[i, 2] + p[2] * r0 - p[0] * r2
            fn[i - 1, 2] += R[2, 0] * fn[i, 0] + R[2, 1] * fn[i, 1] + R[2, 2] * fn[i, 2] + p[0] * r1 - p[1] * r0
            fl[i - 1, 0] += r0
            fl[i - 1, 1] += r1
            fl[i - 1, 2] += r2


@njit(cache=True, error_model="numpy", inline="always")
def crba(model, local_R, local_p, cm, ch, cJ, out_M):
    """The joint-space mass matrix M(q) (n, n) by composite rigid bodies.

    cm (n,), ch (n, 3), cJ (n, 3, 3): scratch for each composite's mass, first moment m c and
    rotational inertia about its frame's origin.
    """
    axis, mass, com, inertia, prismatic = model.axis, model.mass, model.com, model.inertia, model.prismatic
    n = local_R.shape[0]
    for i in range(n):
        m = mass[i]
        c0, c1, c2 = com[i, 0], com[i, 1], com[i, 2]
        cc = c0 * c0 + c1 * c1 + c2 * c2
        cm[i] = m
        ch[i, 0], ch[i, 1], ch[i, 2] = m * c0, m * c1, m * c2
        for r in range(3):
            for k in range(3):
                cJ[i, r, k] = inertia[i, r, k] - m * com[i, r] * com[i, k]
            cJ[i, r, r] += m * cc
    for i in range(n - 1, 0, -1):
        m = cm[i]
        if m <= 0.0:
            continue
        R = local_R[i]
        p = local_p[i]
        c0, c1, c2 = ch[i, 0] / m, ch[i, 1] / m, ch[i, 2] / m
        cc = c0 * c0 + c1 * c1 + c2 * c2
        # about the composite's centre of mass, in this body's frame
        J00 = cJ[i, 0, 0] - m * (cc - c0 * c0)
        J11 = cJ[i, 1, 1] - m * (cc - c1 * c1)
        J22 = cJ[i, 2, 2] - m * (cc - c2 * c2)
        J01 = cJ[i, 0, 1] + m * c0 * c1
        J02 = cJ[i, 0, 2] + m * c0 * c2
        J12 = cJ[i, 1, 2] + m * c1 * c2
        # centre of mass in the parent's frame
        d0 = R[0, 0] * c0 + R[0, 1] * c1 + R[0, 2] * c2 + p[0]
        d1 = R[1, 0] * c0 + R[1, 1] * c1 + R[1, 2] * c2 + p[1]
        d2 = R[2, 0] * c0 + R[2, 1] * c1 + R[2, 2] * c2 + p[2]
        dd = d0 * d0 + d1 * d1 + d2 * d2
        # R Jc R^T, then the parallel-axis shift to the parent's origin
        for r in range(3):
            t0 = R[r, 0] * J00 + R[r, 1] * J01 + R[r, 2] * J02
            t1 = R[r, 0] * J01 + R[r, 1] * J11 + R[r, 2] * J12
            t2 = R[r, 0] * J02 + R[r, 1] * J12 + R[r, 2] * J22
            for k in range(3):
                cJ[i - 1, r, k] += t0 * R[k, 0] + t1 * R[k, 1] + t2 * R[k, 2]
        cJ[i - 1, 0, 0] += m * (dd - d0 * d0)
        cJ[i - 1, 1, 1] += m * (dd - d1 * d1)
        cJ[i - 1, 2, 2] += m * (dd - d2 * d2)
        cJ[i - 1, 0, 1] -= m * d0 * d1
        cJ[i - 1, 1, 0] -= m * d0 * d1
        cJ[i - 1, 0, 2] -= m * d0 * d2
        cJ[i - 1, 2, 0] -= m * d0 * d2
        cJ[i - 1, 1, 2] -= m * d1 * d2
        cJ[i - 1, 2, 1] -= m * d1 * d2
        cm[i - 1] += m
        ch[i - 1, 0] += m * d0
        ch[i - 1, 1] += m * d1
        ch[i - 1, 2] += m * d2
    for i in range(n):
        a0, a1, a2 = axis[i, 0], axis[i, 1], axis[i, 2]
        if prismatic[i]:
            # F = Ic_i (0, a): moment h x a, force m a
            n0 = ch[i, 1] * a2 - ch[i, 2] * a1
            n1 = ch[i, 2] * a0 - ch[i, 0] * a2
            n2 = ch[i, 0] * a1 - ch[i, 1] * a0
            f0, f1, f2 = cm[i] * a0, cm[i] * a1, cm[i] * a2
            out_M[i, i] = a0 * f0 + a1 * f1 + a2 * f2
        else:
            # F = Ic_i (a, 0): moment J a, force a x h
            n0 = cJ[i, 0, 0] * a0 + cJ[i, 0, 1] * a1 + cJ[i, 0, 2] * a2
            n1 = cJ[i, 1, 0] * a0 + cJ[i, 1, 1] * a1 + cJ[i, 1, 2] * a2
            n2 = cJ[i, 2, 0] * a0 + cJ[i, 2, 1] * a1 + cJ[i, 2, 2] * a2
            f0 = a1 * ch[i, 2] - a2 * ch[i, 1]
            f1 = a2 * ch[i, 0] - a0 * ch[i, 2]
            f2 = a0 * ch[i, 1] - a1 * ch[i, 0]
            out_M[i, i] = a0 * n0 + a1 * n1 + a2 * n2
        j = i
        while j > 0:
            R = local_R[j]
            p = local_p[j]
            r0 = R[0, 0] * f0 + R[0, 1] * f1 + R[0, 2] * f2
            r1 = R[1, 0] * f0 + R[1, 1] * f1 + R[1, 2] * f2
            r2 = R[2, 0] * f0 + R[2, 1] * f1 + R[2, 2] * f2
            m0 = R[0, 0] * n0 + R[0, 1] * n1 + R[0, 2] * n2 + p[1] * r2 - p[2] * r1
            m1 = R[1, 0] * n0 + R[1, 1] * n1 + R[1, 2] * n2 + p[2] * r0 - p[0] * r2
            m2 = R[2, 0] * n0 + R[2, 1] * n1 + R[2, 2] * n2 + p[0] * r1 - p[1] * r0
            n0, n1, n2, f0, f1, f2 = m0, m1, m2, r0, r1, r2
            j -= 1
            if prismatic[j]:
                value = axis[j, 0] * f0 + axis[j, 1] * f1 + axis[j, 2] * f2
            else:
                value = axis[j, 0] * n0 + axis[j, 1] * n1 + axis[j, 2] * n2
            out_M[i, j] = value
            out_M[j, i] = value


@njit(cache=True, error_model="numpy", inline="always")
def gravity_from_composites(model, world_R, cm, ch, out_g):
    """g(q) from the composite first moments ``ch`` that ``crba`` leaves (no second pass over the chain).

    The weight of everything beyond joint i acts at its centre of mass: its moment about the
    joint's origin is h_i x g_i (h_i the composite's first moment, g_i gravity in body i's frame),
    and holding it still takes the torque -a_i . (h_i x g_i); a sliding joint holds its weight
    m_i g_i with the force -a_i . (m_i g_i).
    """
    axis, gravity = model.axis, model.gravity
    for i in range(axis.shape[0]):
        R = world_R[i]
        g0 = R[0, 0] * gravity[0] + R[1, 0] * gravity[1] + R[2, 0] * gravity[2]
        g1 = R[0, 1] * gravity[0] + R[1, 1] * gravity[1] + R[2, 1] * gravity[2]
        g2 = R[0, 2] * gravity[0] + R[1, 2] * gravity[1] + R[2, 2] * gravity[2]
        if model.prismatic[i]:
            out_g[i] = -cm[i] * (axis[i, 0] * g0 + axis[i, 1] * g1 + axis[i, 2] * g2)
            continue
        n0 = ch[i, 1] * g2 - ch[i, 2] * g1
        n1 = ch[i, 2] * g0 - ch[i, 0] * g2
        n2 = ch[i, 0] * g1 - ch[i, 1] * g0
        out_g[i] = -(axis[i, 0] * n0 + axis[i, 1] * n1 + axis[i, 2] * n2)


@njit(cache=True, error_model="numpy", inline="always")
def cholesky_solve(M, b, L, out_x):
    """Solves M x = b for a symmetric positive-definite M (n, n) by Cholesky; L (n, n) is scratch.

    Returns False (and leaves out_x undefined) when M is not positive definite.
    """
    n = M.shape[0]
    for j in range(n):
        s = M[j, j]
        for k in range(j):
            s -= L[j, k] * L[j, k]
        if not s > 0.0:
            return False
        d = math.sqrt(s)
        L[j, j] = d
        for i in range(j + 1, n):
            s = M[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            L[i, j] = s / d
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= L[i, k] * out_x[k]
        out_x[i] = s / L[i, i]
    for i in range(n - 1, -1, -1):
        s = out_x[i]
        for k in range(i + 1, n):
            s -= L[k, i] * out_x[k]
        out_x[i] = s / L[i, i]
    return True


