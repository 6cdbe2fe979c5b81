"""The crank press's laws (paper 001): the tool's travel X(phi) and the rod's motion (the paper's
lambda << 1 form or the exact crank-slider), the linkage's loads, the cutting force of eq. (1) and the
motor's Kloss characteristic. Functions of numbers or CasADi symbols (``m=np`` or ``m=casadi``); SI
units inside (m, rad), the force law in mm of penetration as published (models/press.py says which
reading each one is)."""

import numpy as np

FORCE_KEYS = ("force_c1_N_mm", "force_c2_N_mm2", "force_c3_N_mm3", "force_c4_N_mm4")   # eq. (1)


# --- kinematics -------------------------------------------------------------------------------

def travel_m(phi, r_m, lam, kinematics="paper", m=np):
    """Tool travel X from top dead centre, downwards [m].

    ``"paper"``: X = r [1 - cos phi + lambda/4 (1 - cos 2 phi)] (text after U, lambda << 1);
    ``"exact"``: X = r (1 - cos phi) + l (1 - sqrt(1 - lambda^2 sin^2 phi)), l = r / lambda.
    """
    if kinematics == "paper":
        return r_m * (1 - m.cos(phi) + lam / 4 * (1 - m.cos(2 * phi)))
    return r_m * (1 - m.cos(phi)) + r_m / lam * (1 - m.sqrt(1 - (lam * m.sin(phi)) ** 2))


def rod_middle_m(phi, r_m, lam, kinematics="paper", m=np):
    """(horizontal, vertical-down) position of the rod's middle [m]: half-way from pin to tool."""
    return 0.5 * r_m * m.sin(phi), 0.5 * (r_m * (1 - m.cos(phi)) + travel_m(phi, r_m, lam, kinematics, m))


def coefficient_b(phi, lam, m=np):
    """Table row 5: b = (1 + lambda cos phi) sin phi = dX/dphi / r of the paper's X [-]."""
    return (1 + lam * m.cos(phi)) * m.sin(phi)


def coefficient_d(phi, lam, m=np):
    """Table row 6 as read here: d = sin phi (1 + lambda/2 cos phi), the rod middle's vertical
    velocity ratio (the printed sin phi + lambda/2 cos phi is not dimensionally a velocity ratio
    of anything in the mechanism and gives d(0) != 0 at top dead centre)."""
    return m.sin(phi) * (1 + lam / 2 * m.cos(phi))


def coefficient_k(phi, lam, m=np):
    """Table row 7: k = lambda^2 cos^2 phi, the squared rod angular-velocity ratio [-]."""
    return lam**2 * m.cos(phi) ** 2


def rod_angle_rad(phi, lam, kinematics="paper", m=np):
    """Rod angle beta from the stroke line [rad]: the direction along which both rod ends move alike
    (v_pin - v_tool is normal to the rod, so the rod neither stretches nor shortens). Exact
    crank-slider: sin beta = lambda sin phi; the paper's X implies tan beta = lambda sin phi (its
    X' = r sin(phi + beta) / cos beta); the two differ by O(lambda^3)."""
    if kinematics == "paper":
        return m.arctan(lam * m.sin(phi))
    return m.arcsin(lam * m.sin(phi))


def linkage_forces(phi, beta, Q, rod_x, rod_y, r_m, m=np):
    """Joint forces of the crank-slider from the rod's Newton-Euler equations [N, N m].

    y along the stroke (+X), x across it; crank pin at r (sin phi, -cos phi), so its velocity is
    omega r (cos phi, sin phi). The model's X (paper's or exact, both with + lambda) is the tool
    moving towards the crank axis: the rod runs from the tool to the pin along u = (sin beta, cos
    beta), and pulls the tool through the cut. Q: the force of the rod on the tool along +X;
    (rod_x, rod_y) = m_rod (a_mid - g): what the rod's mass at its middle needs (no moment of
    inertia about it, as in J_k), so both ends carry the same force across the rod, half of it.

    Returns (axial rod force at the tool end, at the crank pin (each + when it drives the tool along
    +X: tension here, compression on a press whose crank sits above the slide), crank torque (what
    the shaft gives the linkage: power at the pin / omega), main-bearing load |pin force|, guide
    force across the stroke). With the crank balanced by its counterweight and the belt pull left
    out (its geometry is not given), the main bearing carries the pin force."""
    c, s = m.cos(beta), m.sin(beta)
    half_across = 0.5 * (rod_x * c - rod_y * s)
    By = -Q                                  # the tool's force on the rod
    Bx = (half_across + By * s) / c
    Ax, Ay = rod_x - Bx, rod_y - By          # the crank pin's force on the rod
    rod_tool = -(Bx * s + By * c)            # (rod on tool) . u
    rod_pin = Ax * s + Ay * c                # (pin on rod) . u
    torque = r_m * (Ax * m.cos(phi) + Ay * m.sin(phi))
    return rod_tool, rod_pin, torque, m.sqrt(Ax**2 + Ay**2), Bx


# The paper's X(phi) drops the O(lambda^3) terms of the crank-slider; past this error of the tool's
# acceleration (relative to its exact peak: about lambda = 0.29) the inertia loads it gives are off.
PAPER_KINEMATICS_TOLERANCE = 0.01


def paper_kinematics_error(rod_ratio: float, samples: int = 2881) -> float:
    """Largest error of the paper's X''(phi) / r = cos phi + lambda cos 2 phi against the exact
    crank-slider's, over a turn, relative to the exact peak [-] (0.00017 at lambda = 0.071)."""
    phi = np.linspace(0.0, 2 * np.pi, samples)
    s, c = np.sin(phi), np.cos(phi)
    root = np.sqrt(1 - rod_ratio**2 * s**2)
    exact = c + rod_ratio * (c**2 - s**2) / root + rod_ratio**3 * s**2 * c**2 / root**3
    paper = c + rod_ratio * np.cos(2 * phi)
    return float(np.max(np.abs(paper - exact)) / np.max(np.abs(exact)))


def cutting_force_N(penetration_mm, c1, c2, c3, c4):
    """Cutting force, eq. (1) [N], for the tool's penetration into the blank [mm]."""
    x = penetration_mm
    return ((c4 * x + c3) * x + c2) * x * x + c1 * x


def kloss_torque_Nm(slip, breakdown_torque_Nm, breakdown_slip):
    """Static characteristic of an induction motor (Kloss): torque at a slip [N m]."""
    return 2 * breakdown_torque_Nm * breakdown_slip * slip / (slip**2 + breakdown_slip**2)
