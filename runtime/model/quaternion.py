"""Quaternion helpers in NumPy (scalar part first, as everywhere in kvrod)."""

from __future__ import annotations

import numpy as np


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Quaternion product (scalar first), shapes (4,) or (..., 4)."""
    a0, av, b0, bv = a[..., 0], a[..., 1:], b[..., 0], b[..., 1:]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a0 * b0 - np.sum(av * bv, axis=-1)
    # av x bv written out as np.cross computes it (a1 b2 - a2 b1, ...: the same
    # roundings), without its axis handling, which cost more than the arithmetic here
    x1, x2, x3, y1, y2, y3 = av[..., 0], av[..., 1], av[..., 2], bv[..., 0], bv[..., 1], bv[..., 2]
    out[..., 1] = a0 * y1 + b0 * x1 + (x2 * y3 - x3 * y2)
    out[..., 2] = a0 * y2 + b0 * x2 + (x3 * y1 - x1 * y3)
    out[..., 3] = a0 * y3 + b0 * x3 + (x1 * y2 - x2 * y1)
    return out


def quat_exp(theta: np.ndarray) -> np.ndarray:
    """exp((0, theta)/2) = (cos(|theta|/2), sin(|theta|/2) theta/|theta|), shape (..., 4)."""
    th = np.asarray(theta, dtype=float)
    a = np.linalg.norm(th, axis=-1)
    out = np.empty(th.shape[:-1] + (4,))
    out[..., 0] = np.cos(a / 2)
    sinc = np.where(a > 1e-8, np.sin(a / 2) / np.where(a > 0, a, 1.0), 0.5 - a**2 / 48)
    out[..., 1:] = sinc[..., None] * th
    return out


def quat_rotation(p: np.ndarray) -> np.ndarray:
    """R(p) (3, 3) or (..., 3, 3), homogeneous of degree 0 (the kernels' formula)."""
    p = np.asarray(p, dtype=float)
    p0, q = p[..., 0], p[..., 1:]
    n2 = np.sum(p * p, axis=-1)
    I = np.eye(3)
    qx = np.zeros(p.shape[:-1] + (3, 3))
    qx[..., 0, 1], qx[..., 0, 2] = -q[..., 2], q[..., 1]
    qx[..., 1, 0], qx[..., 1, 2] = q[..., 2], -q[..., 0]
    qx[..., 2, 0], qx[..., 2, 1] = -q[..., 1], q[..., 0]
    R = ((p0**2 - np.sum(q * q, axis=-1))[..., None, None] * I
         + 2 * q[..., :, None] * q[..., None, :] + 2 * p0[..., None, None] * qx)
    return R / n2[..., None, None]


def quat_from_matrix(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (scalar first, p0 >= 0) of rotation matrices (..., 3, 3)
    (Shepperd's method: the largest of the four candidates is computed first). All
    matrices at once, grouped by the candidate taken: element by element the same
    operations as one matrix at a time (a model build converts every segment's frame)."""
    R = np.asarray(R, dtype=float)
    shape = R.shape[:-2]
    m = R.reshape(-1, 3, 3)
    m00, m11, m22 = m[:, 0, 0], m[:, 1, 1], m[:, 2, 2]
    tr = m00 + m11 + m22
    first = np.argmax(np.stack([tr, m00, m11, m22], axis=1), axis=1)
    out = np.empty((m.shape[0], 4))
    for k in range(4):
        t = first == k
        if not t.any():
            continue
        a, b, c = m00[t], m11[t], m22[t]
        d10, d02, d21 = (m[t, 1, 0] - m[t, 0, 1], m[t, 0, 2] - m[t, 2, 0],
                         m[t, 2, 1] - m[t, 1, 2])
        s01, s02, s12 = (m[t, 0, 1] + m[t, 1, 0], m[t, 0, 2] + m[t, 2, 0],
                         m[t, 1, 2] + m[t, 2, 1])
        if k == 0:
            s = 2 * np.sqrt(1 + tr[t])
            q = (s / 4, d21 / s, d02 / s, d10 / s)
        elif k == 1:
            s = 2 * np.sqrt(1 + a - b - c)
            q = (d21 / s, s / 4, s01 / s, s02 / s)
        elif k == 2:
            s = 2 * np.sqrt(1 - a + b - c)
            q = (d02 / s, s01 / s, s / 4, s12 / s)
        else:
            s = 2 * np.sqrt(1 - a - b + c)
            q = (d10 / s, s02 / s, s12 / s, s / 4)
        out[t] = np.stack(q, axis=1)
    return np.where(out[:, :1] >= 0, out, -out).reshape(shape + (4,))


def quat_angle(p: np.ndarray) -> np.ndarray:
    """Rotation angle (rad, in [0, pi]) of quaternions (..., 4) of any norm."""
    p = np.asarray(p, dtype=float)
    return 2.0 * np.arctan2(np.linalg.norm(p[..., 1:], axis=-1), np.abs(p[..., 0]))


def cayley_curvature(p_a: np.ndarray, p_b: np.ndarray, h: np.ndarray) -> np.ndarray:
    """The kernels' discrete curvature (2/h) Im(r)/Re(r), r = conj(p_a) p_b: (..., 3)."""
    conj = p_a * np.array([1.0, -1.0, -1.0, -1.0])
    r = quat_mul(conj, p_b)
    return 2.0 / np.asarray(h)[..., None] * r[..., 1:] / r[..., :1]


def quat_log(p: np.ndarray) -> np.ndarray:
    """Rotation vector theta (rad, |theta| <= pi) of quaternions (..., 4) of any norm:
    the inverse of :func:`quat_exp` (``p ~ exp((0, theta)/2)``)."""
    p = np.asarray(p, dtype=float)
    p = np.where(p[..., :1] < 0, -p, p)            # the shorter of the two rotations
    s = np.linalg.norm(p[..., 1:], axis=-1)
    angle = 2.0 * np.arctan2(s, p[..., 0])
    scale = np.where(s > 0, angle / np.where(s > 0, s, 1.0), 2.0 / np.where(
        p[..., 0] != 0, p[..., 0], 1.0))
    return scale[..., None] * p[..., 1:]


def end_quaternion(p_inner: np.ndarray, p_last: np.ndarray, h_last: np.ndarray,
                   h_joint: np.ndarray) -> np.ndarray:
    """The frame at the free end of a rod, a half segment beyond the centre of its last
    segment: the rotation between the last two segments (centres ``h_joint`` apart) per
    length, continued over ``h_last / 2`` (second order in h; quaternions (..., 4), the
    result normalised)."""
    conj = np.asarray(p_inner, dtype=float) * np.array([1.0, -1.0, -1.0, -1.0])
    rel = quat_mul(conj, np.asarray(p_last, dtype=float))
    theta = quat_log(rel) * (0.5 * np.asarray(h_last) / np.asarray(h_joint))[..., None]
    q = quat_mul(np.asarray(p_last, dtype=float), quat_exp(theta))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)
