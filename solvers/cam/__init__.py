"""Disc cams with any follower: what a designer sizes a cam with.

* `sizing`       a posed cam's figures: pressure angle on rise and return (with the sense), radii
                 of curvature, undercut or cusp, the flat face's width, the follower and contact
                 forces, the jump speed or the groove's crossovers, Hertz stress, the profile's
                 points: `size_cam`.
* `base_radius`  the least base radius meeting the pressure-angle limit (roller) or the cusp
                 condition (flat face), a 1-D search with counts, certified at its answer:
                 `least_base_radius`.
"""
from typing import TYPE_CHECKING

from mechopt.kit.lazy import lazy_names

if TYPE_CHECKING:       # for readers and the docs; at run time each name imports its module when used
    from mechopt.solvers.cam.base_radius import least_base_radius
    from mechopt.solvers.cam.sizing import size_cam

__getattr__, __dir__ = lazy_names(__name__, {"sizing": ["size_cam"], "base_radius": ["least_base_radius"]})

__all__ = ["least_base_radius", "size_cam"]
