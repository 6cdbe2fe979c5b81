"""A disc cam's geometry from its follower's path: pitch curve, profile, radii of curvature and
pressure angle, for a roller (the envelope of circles about the roller centre's path) or a flat
face (the envelope of lines). Pure functions of arrays over the cam angle theta [rad]: the
follower's kinematics come from `models/cam_followers.py`, forces from `models/cam_forces.py`.

Frames and sense. The fixed frame has the cam centre O at the origin. The cam turns through
theta in the sense sigma (+1 counter-clockwise, -1 clockwise); a point X fixed in the frame is
seen from the cam at Rot(-sigma theta) X. With J the quarter turn (+90 deg) and X' = dX/dtheta,

    P = Rot(-sigma theta) R,   P' = Rot(-sigma theta) (R' - sigma J R),
    P'' = Rot(-sigma theta) (R'' - 2 sigma J R' - R),

so the pitch curve's radius of curvature rho = |P'|^3 / (P' x P'') and its normal follow from the
roller centre R and its two derivatives in the fixed frame (Norton, *Design of Machinery*,
5th ed., McGraw-Hill 2012, sec. 8.7-8.8; Rothbart (ed.), *Cam Design Handbook*, McGraw-Hill 2004,
ch. 5). The pitch curve runs clockwise for a counter-clockwise cam (orientation -sigma); rho > 0 on
its convex parts.

A flat face is a line with unit normal m (pointing away from the cam) at the distance p from O,
m . X = p. Seen from the cam its normal has the angle alpha = beta - sigma theta (beta: m's angle in
the fixed frame); the profile is the envelope of those lines, C = p u + p_a J u (u = (cos alpha,
sin alpha), p_a = dp/dalpha) with radius of curvature rho = p + p_aa: the support function of
convex geometry (for a translating face, p = Rb + s and rho = Rb + s + s'', Norton sec. 8.9).
rho <= 0 is a cusp: the face cannot follow the cam there.

Pressure angle: the signed angle from the direction g in which the follower's contact point moves
(per unit of the follower's motion s) to the profile's outward normal n at the contact (the line
of force), positive counter-clockwise in the fixed frame. For a translating roller follower with
offset e (the stem on x = e, the follower on +y) it is tan(phi) = (sigma s' - e) / (s + sqrt(Rp^2
- e^2)): the offset that lowers the rise's angle of a counter-clockwise cam raises it for a
clockwise one (tests pin the formula). Lengths in mm, angles in rad.
"""
from dataclasses import dataclass

import numpy as np

from mechopt.kit.errors import require


def quarter(v):
    """J v: 2 x n vectors turned by +90 deg."""
    return np.array([-v[1], v[0]])


def seen_from_cam(theta, v, sense: int):
    """Rot(-sense theta) v: fixed-frame vectors (2 x n) seen from the cam."""
    c, s = np.cos(theta), sense * np.sin(theta)
    return np.array([c * v[0] + s * v[1], -s * v[0] + c * v[1]])


def signed_angle(a, b):
    """The signed angle from a to b (2 x n each) [rad], counter-clockwise positive."""
    return np.arctan2(a[0] * b[1] - a[1] * b[0], a[0] * b[0] + a[1] * b[1])


@dataclass(frozen=True)
class CamCurves:
    """A cam's geometry at the cam angles `theta` [rad]: the pitch curve (the roller centre seen
    from the cam; for a flat face, the profile itself) and the profile, as 2 x n points in the
    cam frame [mm]; their signed radii of curvature [mm] (> 0 convex); the contact point and the
    profile's outward normal in the fixed frame (2 x n); the pressure angle [rad], signed (module
    docstring); `lever` = n . g, the follower's motion per unit of the normal's (contact force N =
    follower force Q / lever)."""
    theta: np.ndarray
    pitch: np.ndarray
    profile: np.ndarray
    pitch_radius_mm: np.ndarray
    profile_radius_mm: np.ndarray
    contact: np.ndarray
    normal: np.ndarray
    pressure_rad: np.ndarray
    lever: np.ndarray


def roller_cam(theta, R, dR, ddR, g, roller_mm: float, sense: int) -> CamCurves:
    """The cam under a roller of radius `roller_mm` whose centre runs R(theta) (2 x n, fixed
    frame) with derivatives dR, ddR [mm/rad, mm/rad^2]; g (2 x n) is the centre's motion per unit
    of the follower's (the contact's: a roller turns freely). Profile: P - r n (a roller on the
    cam's outer surface), radius rho - r."""
    d1 = dR - sense * quarter(R)                  # Rot(sigma theta) P', Rot(sigma theta) P''
    d2 = ddR - 2 * sense * quarter(dR) - R
    speed = np.hypot(d1[0], d1[1])
    require(bool(np.all(speed > 0)), "the pitch curve stops (P' = 0): no cam has this layout", key="base_radius_mm")
    cross = d1[0] * d2[1] - d1[1] * d2[0]
    orientation = -sense
    with np.errstate(divide="ignore", invalid="ignore"):
        rho = np.where(cross != 0, orientation * speed**3 / np.where(cross != 0, cross, 1.0), np.inf)
    tangent = d1 / speed
    # outward: right of a counter-clockwise run, left of a clockwise one
    normal = np.array([tangent[1], -tangent[0]]) * orientation
    contact = R - roller_mm * normal
    return CamCurves(np.asarray(theta, dtype=float), seen_from_cam(theta, R, sense),
                     seen_from_cam(theta, contact, sense), rho, rho - roller_mm, contact, normal,
                     signed_angle(g, normal), np.sum(normal * g, axis=0))


def groove_outer_wall(c: CamCurves):
    """A grooved cam's outer wall (2 x n, cam frame) [mm]: the roller's far side, P + r n, i.e.
    2 P - profile for `roller_cam`'s profile P - r n. Its radius is rho + r: undercut where the
    pitch curve is concave (rho < 0) with -rho <= r, as the inner wall is where it is convex with
    rho <= r."""
    return 2 * c.pitch - c.profile


def flat_cam(theta, beta, dbeta, ddbeta, p, dp, ddp, g_of_contact, sense: int) -> CamCurves:
    """The cam under a flat face whose normal m (away from the cam) has the fixed-frame angle
    beta(theta) and whose distance from O is p(theta) (each with its first two theta-derivatives,
    rad and mm per rad^k). `g_of_contact(C)` gives the contact point's motion per unit of the
    follower's as a point of the follower (2 x n) from the contact C (fixed frame)."""
    da, dda = dbeta - sense, ddbeta
    require(bool(np.all(np.abs(da) > 1e-12)), "the face turns with the cam (dalpha/dtheta = 0): no envelope",
            key="base_radius_mm")
    p_a = dp / da                                 # dp/dalpha
    p_aa = (ddp * da - dp * dda) / da**3          # d2p/dalpha2
    rho = p + p_aa
    m = np.array([np.cos(beta), np.sin(beta)])
    contact = p * m + p_a * quarter(m)
    g = g_of_contact(contact)
    return CamCurves(np.asarray(theta, dtype=float), seen_from_cam(theta, contact, sense),
                     seen_from_cam(theta, contact, sense), rho, rho, contact, m, signed_angle(g, m),
                     np.sum(m * g, axis=0))
