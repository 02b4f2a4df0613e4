"""Three-vectors as tuples of floats: the reference interpreter's own small geometry kit.

Plain Python on purpose: the reference interpreter is an oracle, written for clarity and
independence from the vectorised code it checks, not for speed.
"""

from __future__ import annotations

import math

Vec = tuple[float, float, float]

ZERO: Vec = (0.0, 0.0, 0.0)


def add(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def mul(a: Vec, k: float) -> Vec:
    return (a[0] * k, a[1] * k, a[2] * k)


def dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def length(a: Vec) -> float:
    return math.sqrt(dot(a, a))


def unit(a: Vec) -> Vec:
    n = length(a)
    return mul(a, 1.0 / n) if n > 0.0 else ZERO


def angle(a: Vec, b: Vec) -> float:
    """Angle (rad, [0, pi]) between two vectors, accurate near 0 and pi."""
    return math.atan2(length(cross(a, b)), dot(a, b))


def rotate(r: Vec, axis: Vec, phi: float) -> Vec:
    """``r`` (perpendicular to the unit ``axis``) turned by ``phi`` about it."""
    return add(mul(r, math.cos(phi)), mul(cross(axis, r), math.sin(phi)))


def peak_of_turning(a: float, b: float, sweep: float) -> float:
    """max |a cos(phi) + b sin(phi)| for phi in [0, sweep].

    The candidates are the two ends and every stationary point of the sinusoid inside the
    range (where its derivative -a sin + b cos vanishes: phi = atan2(b, a) + k pi).
    """
    best = max(abs(a), abs(a * math.cos(sweep) + b * math.sin(sweep)))
    phi = math.atan2(b, a)
    # the stationary points phi + k pi that fall in [0, sweep]
    k = math.ceil(-phi / math.pi)
    while phi + k * math.pi <= sweep:
        x = phi + k * math.pi
        best = max(best, abs(a * math.cos(x) + b * math.sin(x)))
        k += 1
    return best
