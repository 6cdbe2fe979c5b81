"""Follower motions in closed form for the follower tests, written here independently of the
package's law library: a cycloidal rise-dwell-return-dwell and a harmonic out-and-back."""
import math

import numpy as np


def cycloid(x, b):
    """Unit cycloidal rise over b [rad] at the fraction x: S, S', S'', S''' per rad^k."""
    w = 2 * math.pi * x
    return (x - np.sin(w) / (2 * math.pi), (1 - np.cos(w)) / b, 2 * math.pi * np.sin(w) / b**2,
            4 * math.pi**2 * np.cos(w) / b**3)


class CycloidRDRD:
    """Rise h [mm] over `rise` deg, dwell, return over `ret` deg (cycloidal), dwell."""

    def __init__(self, h=20.0, rise=120.0, dwell=60.0, ret=120.0):
        self.h, self.b1, self.dw, self.b2 = h, math.radians(rise), math.radians(dwell), math.radians(ret)

    def at(self, theta):
        th = np.mod(np.atleast_1d(np.asarray(theta, dtype=float)), 2 * math.pi)
        out = [np.zeros_like(th) for _ in range(4)]
        up = th <= self.b1
        for k, v in enumerate(cycloid(th[up] / self.b1, self.b1)):
            out[k][up] = self.h * v
        out[0][(th > self.b1) & (th <= self.b1 + self.dw)] = self.h
        down = (th > self.b1 + self.dw) & (th <= self.b1 + self.dw + self.b2)
        for k, v in enumerate(cycloid((th[down] - self.b1 - self.dw) / self.b2, self.b2)):
            out[k][down] = (self.h if k == 0 else 0.0) - self.h * v
        return tuple(out)


class HarmonicOutAndBack:
    """s = h/2 (1 - cos theta): a harmonic rise over 180 deg and return over 180 deg [mm]."""

    def __init__(self, h=50.0):
        self.h = h

    def at(self, theta):
        th = np.atleast_1d(np.asarray(theta, dtype=float))
        a = self.h / 2
        return a * (1 - np.cos(th)), a * np.sin(th), a * np.cos(th), -a * np.sin(th)


def poly345(x, b):
    """Unit 3-4-5 polynomial rise over b [rad] at the fraction x: S, S', S'' per rad^k."""
    return (10 * x**3 - 15 * x**4 + 6 * x**5, (30 * x**2 - 60 * x**3 + 30 * x**4) / b,
            (60 * x - 180 * x**2 + 120 * x**3) / b**2)


def piecewise(theta, pieces):
    """s, s', s'' [mm, mm/rad, mm/rad^2] of a cam given as (law, angle_deg, lift_mm) pieces from
    theta = 0 (law None: a dwell); `law(x, b)` -> S, S', S'' of a unit rise."""
    th = np.mod(np.asarray(theta, dtype=float), 2 * math.pi)
    out = [np.zeros_like(th) for _ in range(3)]
    start, level = 0.0, 0.0
    for law, angle, lift in pieces:
        b = math.radians(angle)
        here = (th >= start) & (th < start + b)
        if law is None:
            out[0][here] = level
        else:
            for k, v in enumerate(law((th[here] - start) / b, b)[:3]):
                out[k][here] = (level if k == 0 else 0.0) + lift * v
        start, level = start + b, level + lift
    return tuple(out)
